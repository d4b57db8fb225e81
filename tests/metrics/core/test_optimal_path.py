"""SPL, soft-SPL, BARN's optimal time and path optimality against a wall with a gap.

The world: start (0, 0), goal (4, 0), a wall along x = 2 with a gap from y = 1 to y = 2.
For a point robot the shortest collision-free path bends at the gap's lower corner (2, 1):
``l* = 2 √5`` m, while the straight line is 4 m. The robot drives through the gap's middle,
(0, 0) → (2, 1.5) → (4, 0): ``p = 2 · 2.5 = 5`` m at 0.5 m/s (the corner falls on a
sample). Every expected value
below is worked out from these numbers, not from the code.
"""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from pic4rl_metrics import compute
from pic4rl_metrics.synthetic.synthetic import Obstacles, from_waypoints, write_episode_bag

SHORTEST = 2 * math.sqrt(5.0)  # via the gap's corner (2, 1)
STRAIGHT = 4.0
TRAVELLED = 2 * math.hypot(2.0, 1.5)
SPEED = 0.5
WALL = Obstacles(segments=((2.0, -10.0, 2.0, 1.0), (2.0, 2.0, 2.0, 10.0)))
THROUGH_GAP = from_waypoints([(0.0, 0.0), (2.0, 1.5), (4.0, 0.0)], SPEED, dt_s=0.05)
START = [0.0, 0.0, 0.0]
GOAL = (4.0, 0.0)


def _row(bag: Path) -> dict[str, object]:
    frame = compute([bag]).frame
    row = frame.iloc[0].to_dict()
    assert row["error"] == "", row["error"]
    return row


def _bag(tmp_path: Path, name: str, facts: dict[str, object], outcome: str = "goal",
         track=THROUGH_GAP) -> Path:  # noqa: ANN001
    base = {"start": START, "goal": list(GOAL), "max_speed_mps": 2.0, "footprint": {"radius_m": 0.1}}
    return write_episode_bag(tmp_path / name, track, obstacles=WALL, goal=GOAL,
                             facts={**base, **facts}, outcome=outcome)


def test_the_shortest_path_fact_makes_spl_and_path_optimality(tmp_path: Path) -> None:
    row = _row(_bag(tmp_path, "sim", {"shortest_path_m": SHORTEST, "straight_line_m": STRAIGHT,
                                      "world": "barn:0"}))
    assert row["path_length_m"] == pytest.approx(TRAVELLED, abs=1e-9)
    assert row["optimal_path_source"] == "shortest"
    assert row["optimal_path_m"] == pytest.approx(SHORTEST, abs=1e-12)
    assert row["spl"] == pytest.approx(SHORTEST / TRAVELLED, abs=1e-9)
    assert row["soft_spl"] == pytest.approx(SHORTEST / TRAVELLED, abs=1e-9)  # reached: progress 1
    assert row["path_optimality"] == pytest.approx(SHORTEST / TRAVELLED, abs=1e-9)
    # dist/path stays the paper's straight line over the path
    assert row["distance_path_ratio"] == pytest.approx(STRAIGHT / TRAVELLED, abs=1e-9)
    # BARN: OT = l* / 2 m/s; AT from 0.1 m off the start (0.2 s in, at 0.5 m/s) lies within
    # [2, 8] x OT, so no clip.
    optimal_time = SHORTEST / 2.0
    assert row["barn_time_s"] == pytest.approx(TRAVELLED / SPEED - 0.2, abs=0.05 + 1e-9)
    assert row["barn_score"] == pytest.approx(optimal_time / row["barn_time_s"], abs=1e-9)


def test_without_the_fact_the_straight_line_stands_in(tmp_path: Path) -> None:
    """A real robot's bag: no map, so SPL falls back on the straight start-goal line."""
    row = _row(_bag(tmp_path, "real", {}))
    assert row["optimal_path_source"] == "straight"
    assert row["optimal_path_m"] == pytest.approx(STRAIGHT, abs=1e-12)
    assert row["spl"] == pytest.approx(STRAIGHT / TRAVELLED, abs=1e-9)
    assert row["path_optimality"] == pytest.approx(STRAIGHT / TRAVELLED, abs=1e-9)
    # no BARN world: no BARN columns (issue 37.6)
    assert math.isnan(row["barn_score"]) and math.isnan(row["barn_time_s"])


def test_a_recorded_straight_line_and_an_infinite_shortest_path(tmp_path: Path) -> None:
    """``straight_line_m`` is used as recorded; ``shortest_path_m = inf`` (no path was found)
    is no optimal path: the straight line stands in."""
    row = _row(_bag(tmp_path, "inf", {"shortest_path_m": "inf", "straight_line_m": 4.2}))
    assert row["optimal_path_source"] == "straight"
    assert row["spl"] == pytest.approx(4.2 / TRAVELLED, abs=1e-9)


def test_a_crash_into_the_wall_scores_zero_spl_and_partial_soft_spl(tmp_path: Path) -> None:
    """Straight at the wall, stopped 0.2 m before it: SPL 0; soft-SPL = progress
    1 - d_final / straight = 1 - 2.2 / 4 with weight l*/max(p, l*) = 1 (p = 1.8 m < l*)."""
    crash = from_waypoints([(0.0, 0.0), (1.8, 0.0)], SPEED, dt_s=0.05)
    row = _row(_bag(tmp_path, "crash", {"shortest_path_m": SHORTEST, "world": "barn:0"},
                    "collision", crash))
    assert row["spl"] == 0.0 and row["barn_score"] == 0.0
    assert row["soft_spl"] == pytest.approx(1 - 2.2 / STRAIGHT, abs=1e-9)
    assert row["path_optimality"] == pytest.approx(SHORTEST / 1.8, abs=1e-9)
