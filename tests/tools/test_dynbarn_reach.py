"""``tools/dynbarn_reach.py``: the foresighted disc's arrival against answers worked by hand (an
open field; a gate that a slow obstacle holds shut for a known time), its obstacles against the
engine's, and the command over bags (a bag of another world is named, the batch goes on)."""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

import numpy as np
import pytest

from pic4rl_metrics.synthetic.synthetic import straight_line, write_episode_bag
from pic4rl_sim.engine.core import Engine
from pic4rl_sim.engine.geometry import Twist2D
from pic4rl_sim.engine.robot_specs import JACKAL
from pic4rl_sim.engine.worlds.generators import make_world
from pic4rl_sim.engine.worlds.spec import Box, MovingObstacles, WorldSpec

ROOT = Path(__file__).resolve().parents[2]
SPEC = importlib.util.spec_from_file_location("dynbarn_reach", ROOT / "tools" / "dynbarn_reach.py")
assert SPEC is not None and SPEC.loader is not None
dynbarn_reach = sys.modules.setdefault(SPEC.name, importlib.util.module_from_spec(SPEC))
SPEC.loader.exec_module(dynbarn_reach)

BOUNDS = (-5.0, -3.0, 5.0, 3.0)


def gate(mover_start_x: float | None) -> WorldSpec:
    """A wall along y = 0 with a gate 0.5 m wide at x = 0; optionally one obstacle (radius
    0.15 m) held to the wall's line, from ``mover_start_x`` along +x at 0.25 m/s."""
    walls = (Box(-2.625, 0.0, 4.75, 0.1, 1.0), Box(2.625, 0.0, 4.75, 0.1, 1.0))
    moving = None
    if mover_start_x is not None:
        moving = MovingObstacles((-4.0, -0.1501, 4.0, 0.1501), ((mover_start_x, 0.0),), (0.0,),
                                 (0.25,), (0.25, 0.25), turn_time_s=20.0, radius_m=0.15)
    return WorldSpec("gate", BOUNDS, boxes=walls, moving=moving)


def arrival(world: WorldSpec, budget_s: float = 20.0) -> float | None:
    """A disc of 0.2 m at 1 m/s from (0, -2) to within 0.5 m of (0, 2)."""
    return dynbarn_reach.earliest_arrival(world, 0, (0.0, -2.0), (0.0, 2.0),
                                          goal_tolerance_m=0.5, budget_s=budget_s,
                                          radius_m=0.2, speed_mps=1.0)


def test_an_open_gate_is_crossed_straight_and_a_short_budget_is_not_enough() -> None:
    """3.5 m to the goal's circle at 1 m/s: 3.5 s; the gate's 0.05 m of play for a 0.2 m
    disc does not slow it."""
    assert arrival(gate(None)) == pytest.approx(3.5, abs=0.11)
    assert arrival(gate(None), budget_s=3.3) is None


def test_a_slow_obstacle_in_the_gate_is_waited_for() -> None:
    """The obstacle starts 0.5 m left of the gate's centre at 0.25 m/s. The disc fits through
    the gate on the 5 cm grid's columns at x = ±0.025 only, and no closer than 0.35 m to the
    obstacle: its centre reaches the wall's line (the cells at y = -0.025) once the obstacle is
    at x = 0.325, at (0.5 + 0.325) / 0.25 = 3.3 s; one period later it is across (y = 0.025),
    then has 1.5 m to the goal's circle: 4.9 s, against 3.5 s with the gate clear."""
    assert arrival(gate(-0.5)) == pytest.approx(4.9, abs=0.01)
    assert arrival(gate(3.0)) == pytest.approx(3.5, abs=0.11)  # far off, moving away


def test_the_obstacles_move_as_in_the_engine() -> None:
    world = make_world("dynbarn", seed=5)
    engine = Engine(JACKAL, world, seed=77)
    tracks = dynbarn_reach.mover_positions(world, 77)
    for _ in range(20):
        engine.step(Twist2D(0.0, 0.0, 0.0))
        np.testing.assert_allclose(next(tracks), engine.movers.pos, atol=1e-12)


def test_the_command_replays_dynbarn_bags_and_names_a_bag_of_another_world(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    facts = {"agent": "mine", "seed": 3, "start": [-2.25, 3.0, 1.57], "goal": [-2.25, 13.0],
             "goal_tolerance_m": 1.0, "time_budget_s": 100.0,
             "footprint": {"length_m": 0.508, "width_m": 0.43}}
    track = straight_line(0.5, 2.0, 0.1)
    for name, world in (("a", "dynbarn:0"), ("b", "barn:0")):
        write_episode_bag(tmp_path / "run" / name, track, facts={**facts, "world": world},
                          outcome="collision")
    assert dynbarn_reach.main([str(tmp_path / "run"), "--speed", "2.0"]) == 0
    out, err = capsys.readouterr()
    assert "run/b: world 'barn:0'; expected dynbarn:<variant>" in err
    lines = out.splitlines()
    # its last pose, (1, 0), is off the moving obstacles' field
    assert lines[0].endswith("run/a: dynbarn:0, collision (static obstacle); with foresight "
                             "crosses in 4.6 s")
    assert lines[1:] == ["mine: 1 episodes, 1 crossable with foresight at 2 m/s",
                         ("  collision: 1 (0 with a moving obstacle, 1 with the static field); "
                          "1 of them crossable")]


def test_a_collision_is_put_on_the_nearer_obstacle() -> None:
    """In the gate world, the obstacle at x = -0.5 + 0.25 t on the wall's line: at 2 s it is
    at (0, 0); a robot at (0, -0.3) is 0.15 m from its surface and 0.25 m from the wall's."""
    world = gate(-0.5)
    assert dynbarn_reach.what_was_hit(world, 0, 2.0, (0.0, -0.3)) == "moving"
    assert dynbarn_reach.what_was_hit(world, 0, 2.0, (-1.0, -0.1)) == "static"
