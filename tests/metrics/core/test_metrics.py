"""``metrics``: the metrics of synthetic bags against values known by hand (docs/metrics.md's
definitions): success, clearance time, outcome inference, BARN score, heading error, scan
clearance, collisions and footprints, row crop and person following, path optimality.

Every bag is written by ``synthetic.write_episode_bag`` into a temporary directory, read back
through the public API and compared with a value worked out from the geometry, not from the
code under test (tolerances: ``metrics_helpers``).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from metrics_helpers import DIFF, EXACT, F32, JACKAL, LINE, NS
from metrics_helpers import rewrite as _rewrite
from metrics_helpers import row as _row

from pic4rl_metrics import (
    EpisodeFacts,
    compute_metrics,
    read_episode,
)
from pic4rl_metrics.synthetic.synthetic import (
    DEFAULT_T0_NS,
    Obstacles,
    Track,
    straight_line,
    write_episode_bag,
)

# --- straight line ---------------------------------------------------------------------------



@pytest.fixture(scope="module")
def line_bags(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    root = tmp_path_factory.mktemp("line")
    return {
        "plain": write_episode_bag(root / "plain", LINE),
        "goal": write_episode_bag(root / "goal", LINE, goal=(5.0, 0.0), outcome="goal"),
        "goal_inferred": write_episode_bag(root / "goal_inferred", LINE, goal=(5.0, 0.0)),
        "timeout": write_episode_bag(root / "timeout", LINE, goal=(10.0, 0.0)),
    }


def test_straight_line_kinematics_are_exact(line_bags: dict[str, Path]) -> None:
    m = _row(line_bags["goal"])
    assert m["n_poses"] == 101
    assert m["path_length_m"] == pytest.approx(5.0, abs=EXACT)
    assert m["net_displacement_m"] == pytest.approx(5.0, abs=EXACT)
    assert m["start_goal_distance_m"] == pytest.approx(5.0, abs=EXACT)
    assert m["distance_path_ratio"] == pytest.approx(1.0, abs=EXACT)
    assert m["lin_vel_mean_mps"] == pytest.approx(0.5, abs=EXACT)
    assert m["lin_vel_std_mps"] == pytest.approx(0.0, abs=EXACT)
    for key in ("ang_vel_mean_radps", "ang_vel_std_radps", "lin_acc_max_mps2",
                "lin_acc_mean_mps2", "yaw_acc_max_radps2", "yaw_acc_mean_radps2",
                "lin_jerk_max_mps3", "lin_jerk_mean_mps3", "yaw_jerk_max_radps3",
                "yaw_jerk_mean_radps3", "path_curvature_mean_radpm", "angle_over_length_radpm",
                "time_not_moving_s"):
        assert m[key] == pytest.approx(0.0, abs=DIFF), key
    # The goal lies straight ahead on the line the whole episode: bearing 0.
    assert m["heading_error_mean_rad"] == pytest.approx(0.0, abs=EXACT)
    assert m["heading_error_signed_mean_rad"] == pytest.approx(0.0, abs=EXACT)


def test_straight_line_goal_recorded_gives_success_spl_and_soft_spl_one(line_bags) -> None:
    m = _row(line_bags["goal"])
    assert m["outcome"] == "goal" and m["success"] == 1.0
    assert m["clearance_time_s"] == pytest.approx(10.0, abs=EXACT)
    assert m["spl"] == pytest.approx(1.0, abs=EXACT)
    assert m["soft_spl"] == pytest.approx(1.0, abs=EXACT)
    assert m["goal_dist_final_m"] == pytest.approx(0.0, abs=EXACT)
    assert m["goal_dist_min_m"] == pytest.approx(0.0, abs=EXACT)


def test_clearance_time_without_outcome_is_the_pose_span(line_bags) -> None:
    m = _row(line_bags["plain"])
    assert m["clearance_time_s"] == pytest.approx(10.0, abs=EXACT)


@pytest.mark.parametrize(
    ("stamp_s", "expected_s"),
    [(6.0, 6.0), (2.5, 2.5), (20.0, 10.0), (-3.0, 0.0)],  # the last two are clamped to the span
)
def test_clearance_time_ends_at_the_recorded_outcome_stamp(
    line_bags, tmp_path: Path, stamp_s: float, expected_s: float
) -> None:
    bag = _rewrite(line_bags["goal"], tmp_path / "moved",
                   outcome_stamp_ns=DEFAULT_T0_NS + int(stamp_s * NS))
    m = _row(bag)
    assert m["outcome"] == "goal"
    assert m["clearance_time_s"] == pytest.approx(expected_s, abs=EXACT)




def test_recorded_start_sets_the_start_goal_distance(tmp_path: Path) -> None:
    # Recorded start 1 m behind the first pose: l = 6 m, p = 5 m.
    bag = write_episode_bag(tmp_path / "start", LINE, goal=(5.0, 0.0), outcome="goal",
                            facts={"start": [-1.0, 0.0, 0.0]})
    m = _row(bag)
    assert m["start_goal_distance_m"] == pytest.approx(6.0, abs=EXACT)
    assert m["distance_path_ratio"] == pytest.approx(6.0 / 5.0, abs=EXACT)
    assert m["spl"] == pytest.approx(1.0, abs=EXACT)  # l / max(p, l) = 6 / 6


def test_time_not_moving_of_a_stop_then_go(tmp_path: Path) -> None:
    # Still for 2 s (samples 0 .. 2.0 s), then 0.5 m/s for 2 s: 20 still intervals of 0.1 s.
    t = np.arange(41) * 0.1
    vx = np.where(t <= 2.0 + 1e-9, 0.0, 0.5)
    x = np.where(t <= 2.0 + 1e-9, 0.0, 0.5 * (t - 2.0))
    zeros = np.zeros_like(t)
    m = _row(write_episode_bag(tmp_path / "stopgo", Track(t, x, zeros, zeros, vx, zeros, zeros)))
    assert m["time_not_moving_s"] == pytest.approx(2.0, abs=EXACT)
    assert m["path_length_m"] == pytest.approx(1.0, abs=EXACT)
    # One step of 0.5 m/s in 0.1 s: the only linear acceleration, 5 m/s^2 over 1 of 40 intervals.
    assert m["lin_acc_max_mps2"] == pytest.approx(5.0, abs=DIFF)
    assert m["lin_acc_mean_mps2"] == pytest.approx(5.0 / 40, abs=DIFF)


@pytest.mark.parametrize(("budget_s", "recorded", "expected"), [
    (30.0, None, "aborted"),   # 10 s of a 30 s budget, no outcome: the sim died
    (10.2, None, "timeout"),   # within 5 % of the budget: the last steps went unrecorded
    (30.0, "timeout", "timeout"),  # a recorded outcome stands
    (None, None, "timeout"),   # no budget known (a real bag): as before
])
def test_an_unrecorded_end_before_the_budget_is_aborted(tmp_path: Path, budget_s, recorded,
                                                        expected) -> None:
    facts = {} if budget_s is None else {"time_budget_s": budget_s}
    bag = write_episode_bag(tmp_path / "cut", LINE, goal=(10.0, 0.0), facts=facts,
                            outcome=recorded)
    m = _row(bag)
    assert m["outcome"] == expected
    assert math.isnan(m["success"]) if expected == "aborted" else m["success"] == 0.0
    warned = "no outcome recorded and 10.0 s of its 30 s budget: judged aborted"
    assert (warned in m["warnings"]) == (expected == "aborted")


def test_goal_inferred_from_final_distance(line_bags) -> None:
    m = _row(line_bags["goal_inferred"])
    assert m["outcome"] == "goal" and m["success"] == 1.0
    assert m["spl"] == pytest.approx(1.0, abs=EXACT)


def test_timeout_when_goal_never_reached(line_bags) -> None:
    m = _row(line_bags["timeout"])
    assert m["outcome"] == "timeout" and m["success"] == 0.0
    assert m["spl"] == 0.0
    # l = 10, p = 5, d_final = 5: clip(1 - 5/10) * 10 / max(5, 10) = 0.5
    assert m["soft_spl"] == pytest.approx(0.5, abs=EXACT)
    assert m["goal_dist_final_m"] == pytest.approx(5.0, abs=EXACT)
    assert m["goal_dist_min_m"] == pytest.approx(5.0, abs=EXACT)
    assert m["start_goal_distance_m"] == pytest.approx(10.0, abs=EXACT)
    assert m["distance_path_ratio"] == pytest.approx(2.0, abs=EXACT)  # l / p
    assert m["heading_error_mean_rad"] == pytest.approx(0.0, abs=EXACT)


def test_unknown_outcome_without_goal_or_collision(line_bags) -> None:
    m = _row(line_bags["plain"])
    assert m["outcome"] == "unknown"
    for key in ("success", "spl", "soft_spl", "barn_score", "heading_error_mean_rad",
                "start_goal_distance_m", "goal_dist_final_m"):
        assert math.isnan(m[key]), key
    # No goal: dist/path falls back to net displacement / path.
    assert m["distance_path_ratio"] == pytest.approx(1.0, abs=EXACT)


# LINE: 0.5 m/s along x for 10 s, a pose every 0.1 s. It is 0.1 m from its start at
# t = 0.2 s, where BARN's clock starts: AT = 10 - 0.2 = 9.8 s.
BARN_AT = 9.8


@pytest.mark.parametrize(
    ("reference_m", "expected"),
    [
        # OT = 5 / 2 = 2.5 s: 2 OT = 5 <= AT <= 8 OT = 20, no clip: OT / AT.
        (5.0, 2.5 / BARN_AT),
        # OT = 10 s: AT < 2 OT = 20 (too fast), clipped up: OT / (2 OT) = 1/2.
        (20.0, 0.5),
        # OT = 0.5 s: AT > 8 OT = 4 (too slow), clipped down: OT / (8 OT) = 1/8.
        (1.0, 0.125),
    ],
)
def test_barn_score_by_hand(line_bags, reference_m: float, expected: float) -> None:
    facts = EpisodeFacts(reference_path_m=reference_m)
    given = frozenset({"reference_path_m"})
    row = _row(line_bags["goal"], facts=facts, given=given)
    assert row["barn_time_s"] == pytest.approx(BARN_AT, abs=EXACT)
    assert row["barn_score"] == pytest.approx(expected, abs=EXACT)
    # S = 0 for a timeout, whatever the times.
    assert _row(line_bags["timeout"], facts=facts, given=given)["barn_score"] == 0.0


def test_barn_score_without_a_reference_uses_the_optimal_path(line_bags) -> None:
    # A BARN world without reference_path_m: l_ref = the straight 5 m line, OT = 2.5 s.
    facts, given = EpisodeFacts(world="barn:7"), frozenset({"world"})
    row = _row(line_bags["goal"], facts=facts, given=given)
    assert row["barn_score"] == pytest.approx(2.5 / BARN_AT, abs=EXACT)


@pytest.mark.parametrize("world", [None, "indoor:0", "barn_like:3"])
def test_the_barn_columns_are_nan_outside_a_barn_world(line_bags, world: str | None) -> None:
    """Issue 37.6: an indoor episode or a real log (no world, no reference path) has no BARN
    score and no BARN time, and a log without a goal has neither even in a BARN world."""
    given = frozenset({"world"} if world else set())
    row = _row(line_bags["goal"], facts=EpisodeFacts(world=world), given=given)
    assert math.isnan(row["barn_score"]) and math.isnan(row["barn_time_s"])
    no_goal = _row(line_bags["plain"], facts=EpisodeFacts(world="barn:7"),
                   given=frozenset({"world"}))
    assert math.isnan(no_goal["barn_score"]) and math.isnan(no_goal["barn_time_s"])


def test_heading_error_of_a_goal_to_the_side(tmp_path: Path) -> None:
    # Standing robot facing +x; goal at +y is 90 deg left, at -y 90 deg right.
    still = straight_line(0.0, 2.0)
    left = _row(write_episode_bag(tmp_path / "left", still, goal=(0.0, 3.0)))
    right = _row(write_episode_bag(tmp_path / "right", still, goal=(0.0, -3.0)))
    assert left["heading_error_mean_rad"] == pytest.approx(math.pi / 2, abs=EXACT)
    assert left["heading_error_signed_mean_rad"] == pytest.approx(math.pi / 2, abs=EXACT)
    assert right["heading_error_mean_rad"] == pytest.approx(math.pi / 2, abs=EXACT)
    assert right["heading_error_signed_mean_rad"] == pytest.approx(-math.pi / 2, abs=EXACT)
    # Standing still the whole time, no path.
    assert left["time_not_moving_s"] == pytest.approx(2.0, abs=EXACT)
    assert left["path_length_m"] == 0.0
    assert math.isnan(left["distance_path_ratio"])  # 0/0: cannot be computed, not 0


def test_distance_path_ratio_of_a_robot_that_barely_moved(tmp_path: Path) -> None:
    # 5 mm of creeping toward a goal 3 m away: no path, so no ratio (not 600).
    creep = straight_line(0.001, 5.0)
    row = _row(write_episode_bag(tmp_path / "creep", creep, goal=(3.0, 0.0)))
    assert row["path_length_m"] == pytest.approx(0.005, abs=1e-6)
    assert math.isnan(row["distance_path_ratio"])
    moved = _row(write_episode_bag(tmp_path / "moved", straight_line(0.01, 5.0),
                                   goal=(3.0, 0.0)))
    assert moved["distance_path_ratio"] == pytest.approx(3.0 / 0.05, rel=1e-6)

# --- scans -------------------------------------------------------------------------------------

# 360 beams from -pi in steps of 1 deg: beams at exactly +-90 deg and 0 deg exist.
DEG = np.radians(np.arange(-180, 180))


def test_wall_parallel_to_the_path(tmp_path: Path) -> None:
    d = 1.0  # wall y = 1 along the whole path (long enough that every beam within 10 m hits)
    world = Obstacles(segments=((-1000.0, d, 1000.0, d),))
    m = _row(write_episode_bag(tmp_path / "wall", LINE, obstacles=world))
    assert m["n_scans"] == 101
    # The beam at +90 deg is perpendicular to the wall: the minimum is d up to float32.
    assert m["obstacle_dist_min_m"] == pytest.approx(d, abs=F32)
    assert m["obstacle_dist_mean_m"] == pytest.approx(d, abs=F32)
    # Beam at bearing th hits at d / sin(th) when that is within range_max = 10 m.
    hits = d / np.sin(DEG[np.sin(DEG) > 0])
    hits = hits[hits <= 10.0]
    assert len(hits) == 169  # 6 .. 174 deg
    assert m["scan_range_mean_m"] == pytest.approx(float(hits.mean()), abs=F32)
    # No footprint: collisions cannot be judged.
    assert math.isnan(m["collision_count"]) and math.isnan(m["safety_violation_time_s"])


def test_cylinder_at_known_distance(tmp_path: Path) -> None:
    cx, rc = 3.0, 0.5  # cylinder centre 3 m ahead, radius 0.5: nearest surface 2.5 m
    world = Obstacles(circles=((cx, 0.0, rc),))
    m = _row(write_episode_bag(tmp_path / "cyl", straight_line(0.0, 2.0), obstacles=world))
    assert m["obstacle_dist_min_m"] == pytest.approx(cx - rc, abs=F32)
    assert m["obstacle_dist_mean_m"] == pytest.approx(cx - rc, abs=F32)
    s = cx * np.sin(DEG)
    hit = (np.abs(s) <= rc) & (np.cos(DEG) > 0)
    ranges = cx * np.cos(DEG[hit]) - np.sqrt(rc**2 - s[hit] ** 2)
    assert hit.sum() == 19  # -9 .. 9 deg
    assert m["scan_range_mean_m"] == pytest.approx(float(ranges.mean()), abs=F32)


def test_scan_rep117_special_values(tmp_path: Path) -> None:
    # Four beams at -180, -90, 0, 90 deg: +inf (no return), -inf (closer than range_min
    # 0.05), 12 m (beyond range_max 10: no obstacle) and NaN (error).
    scans = [[np.inf, -np.inf, 12.0, np.nan]] * 5
    bag = write_episode_bag(tmp_path / "rep117", straight_line(0.0, 0.4), scans=scans,
                            facts={"footprint": {"radius_m": 0.2}})
    m = _row(bag)
    assert m["obstacle_dist_min_m"] == pytest.approx(0.05, abs=F32)  # -inf reads range_min
    assert m["scan_range_mean_m"] == pytest.approx(0.05, abs=F32)  # the only valid return
    assert m["collision_count"] == 1.0 and m["outcome"] == "collision"


# A dropout: the middle one of five scans (0.1 s apart) has no valid beam. The others see an
# obstacle 0.22 m ahead: margin 0.02 <= 0.05 with a 0.2 m circle.
_TOUCH = [np.inf, np.inf, 0.22, np.inf]
_DROPOUT = [_TOUCH, _TOUCH, [np.inf] * 4, _TOUCH, _TOUCH]


@pytest.fixture(scope="module")
def dropout_bag(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return write_episode_bag(
        tmp_path_factory.mktemp("dropout") / "bag", straight_line(0.0, 0.4), scans=_DROPOUT,
        facts={"footprint": {"radius_m": 0.2}},
    )


def test_scan_without_valid_beam_does_not_split_a_collision(dropout_bag: Path) -> None:
    """docs/metrics.md, Scans: "A scan with no valid beam contributes nothing." One contact
    interrupted by a scan that saw nothing is still one rising edge of the contact flag."""
    m = _row(dropout_bag)
    assert m["obstacle_dist_min_m"] == pytest.approx(0.22, abs=F32)
    assert m["obstacle_dist_mean_m"] == pytest.approx(0.22, abs=F32)  # the dropout is skipped
    assert m["collision_count"] == 1.0


def test_scan_without_valid_beam_does_not_end_a_safety_violation(dropout_bag: Path) -> None:
    """Same reading of "contributes nothing": the scan before the dropout holds until the next
    scan that has data, so the margin is violated for the whole 0.4 s."""
    assert _row(dropout_bag)["safety_violation_time_s"] == pytest.approx(0.4, abs=EXACT)

# --- collisions and footprints ----------------------------------------------------------------

WALL_X = 3.03  # wall across the path; the robot stops at x = 2.85 (0.18 m short)
CRASH = straight_line(0.5, 5.7)  # x = 0, 0.05, ..., 2.85
CRASH_WORLD = Obstacles(segments=((WALL_X, -10.0, WALL_X, 10.0),))


def test_collision_inferred_from_scan_margin(tmp_path: Path) -> None:
    bag = write_episode_bag(
        tmp_path / "crash", CRASH, obstacles=CRASH_WORLD, facts={"footprint": {"radius_m": 0.2}}
    )
    m = _row(bag)
    # no goal: a crash, but no success to speak of (issue 37.6: NaN, not 0)
    assert m["outcome"] == "collision" and math.isnan(m["success"])
    assert m["obstacle_dist_min_m"] == pytest.approx(WALL_X - 2.85, abs=F32)
    # margin = (3.03 - x) - 0.2 <= 0.05 from x = 2.80 on: one rising edge.
    assert m["collision_count"] == 1.0
    # margin <= 0.3 (safety) from x = 2.55 (t = 5.1 s) to the end (5.7 s): 6 intervals held.
    assert m["safety_violation_time_s"] == pytest.approx(0.6, abs=EXACT)
    assert m["safety_violation_time_s"] > 0


def test_collision_count_counts_rising_edges(tmp_path: Path) -> None:
    from pic4rl_metrics.synthetic.synthetic import from_waypoints

    # In to 0.18 m of the wall, back to 1.03 m, in again.
    track = from_waypoints([(0.0, 0.0), (2.85, 0.0), (2.0, 0.0), (2.85, 0.0)], 0.5)
    bag = write_episode_bag(
        tmp_path / "twice", track, obstacles=CRASH_WORLD, facts={"footprint": {"radius_m": 0.2}}
    )
    m = _row(bag)
    assert m["collision_count"] == 2.0
    assert m["outcome"] == "collision"


@pytest.mark.parametrize(
    ("tolerance", "outcome"),
    [
        # Within 0.3 m of the goal from x = 2.55 (t = 5.1 s), before the first contact at 5.6 s.
        (0.3, "goal"),
        # Within 0.03 m only at x = 2.85 (t = 5.7 s), after the contact at 5.6 s.
        (0.03, "collision"),
    ],
)
def test_goal_counts_only_when_reached_before_any_collision(
    tmp_path: Path, tolerance: float, outcome: str
) -> None:
    facts = {"footprint": {"radius_m": 0.2}, "goal_tolerance_m": tolerance}
    bag = write_episode_bag(
        tmp_path / "near", CRASH, obstacles=CRASH_WORLD, goal=(2.85, 0.0), facts=facts
    )
    assert _row(bag)["outcome"] == outcome


@pytest.mark.parametrize(
    ("wall", "footprint", "collides", "min_margin"),
    [
        # Wall beside at 0.24 m: inside half-length 0.254 but the side edge is at 0.215.
        ((-5.0, 0.24, 5.0, 0.24), JACKAL, True, 0.24 - 0.215),
        # Wall in front at 0.30 m: 0.30 - 0.254 = 0.046 <= 0.05, a collision ...
        ((0.30, -5.0, 0.30, 5.0), JACKAL, True, 0.30 - 0.254),
        # ... but the same wall beside: 0.30 - 0.215 = 0.085 > 0.05, none.
        ((-5.0, 0.30, 5.0, 0.30), JACKAL, False, 0.30 - 0.215),
        # The inscribed circle (r = 0.215) misses the front wall at 0.30 m: the rectangle matters.
        ((0.30, -5.0, 0.30, 5.0), {"radius_m": 0.215}, False, 0.30 - 0.215),
    ],
)
def test_rectangular_footprint_margins(
    tmp_path: Path, wall: tuple[float, ...], footprint: dict, collides: bool, min_margin: float
) -> None:
    still = straight_line(0.0, 1.0)  # 11 scans, 10 intervals of 0.1 s
    bag = write_episode_bag(
        tmp_path / "rect", still, obstacles=Obstacles(segments=(wall,)),
        facts={"footprint": footprint},
    )
    ep = read_episode(bag)
    from pic4rl_metrics.core.scan_summary import scan_clearance

    whole = read_episode(bag, full_scans=True)  # every beam kept: the same margins from them
    np.testing.assert_array_equal(scan_clearance(whole.scan, whole.facts).margin_m,
                                  ep.scan.margin_m)
    margin = ep.scan.margin_m
    np.testing.assert_allclose(margin, min_margin, atol=F32)
    m = compute_metrics(ep)
    assert m.outcome == ("collision" if collides else "unknown")
    assert m.collision_count == (1.0 if collides else 0.0)
    # Every margin is <= 0.3 (the default safety margin) for the whole second.
    assert m.safety_violation_time_s == pytest.approx(1.0, abs=EXACT)

# --- row crop and person following --------------------------------------------------------


@pytest.mark.parametrize("offset", [0.1, -0.1])
def test_row_path_error_of_a_parallel_drive(tmp_path: Path, offset: float) -> None:
    track = straight_line(0.5, 10.0, start=(0.0, offset, 0.0))
    facts = {"row_centerline": [[-1.0, 0.0], [2.0, 0.0], [6.0, 0.0]]}
    m = _row(write_episode_bag(tmp_path / "row", track, facts=facts))
    assert m["row_path_mae_m"] == pytest.approx(0.1, abs=EXACT)
    assert m["row_path_mse_m2"] == pytest.approx(0.01, abs=EXACT)


@pytest.mark.parametrize(
    ("person_start", "bearing"),
    [
        ((1.0, 0.0, 0.0), 0.0),  # 1 m straight ahead on the same line
        ((1.0, 0.5, 0.0), math.atan2(0.5, 1.0)),  # constant offset to the left
        ((1.0, -0.5, 0.0), -math.atan2(0.5, 1.0)),  # ... and to the right
    ],
)
def test_person_following_bearing(
    tmp_path: Path, person_start: tuple[float, float, float], bearing: float
) -> None:
    # Person sampled at the robot's stamps: no interpolation needed.
    person = straight_line(0.5, 10.0, start=person_start)
    m = _row(write_episode_bag(tmp_path / "follow", LINE, person=person))
    assert m["follow_heading_mean_rad"] == pytest.approx(bearing, abs=EXACT)
    assert m["follow_heading_mae_rad"] == pytest.approx(abs(bearing), abs=EXACT)
    assert m["follow_heading_rmse_rad"] == pytest.approx(abs(bearing), abs=EXACT)
    assert m["follow_heading_max_rad"] == pytest.approx(abs(bearing), abs=EXACT)


def test_person_interpolation_is_exact_for_linear_motion(tmp_path: Path) -> None:
    """The person at 4 Hz, the robot at 10 Hz: linear interpolation of a person moving in a
    straight line at constant speed is exact, so every bearing is -atan(0.5) to float64
    rounding (~1e-16). Interpolating on absolute stamps turned into float64 (1.7e18 ns has a
    256 ns resolution) shifts the interpolated position by up to ~1e-7 m."""
    person = straight_line(0.5, 10.0, 0.25, start=(1.0, -0.5, 0.0))
    m = _row(write_episode_bag(tmp_path / "follow", LINE, person=person))
    bearing = -math.atan2(0.5, 1.0)
    assert m["follow_heading_mean_rad"] == pytest.approx(bearing, abs=1e-6)
    assert m["follow_heading_max_rad"] == pytest.approx(abs(bearing), abs=1e-6)
    # Exact to rounding, as the docs' "linearly interpolated" gives for linear motion.
    assert m["follow_heading_max_rad"] == pytest.approx(abs(bearing), abs=EXACT)

# --- track constants ----------------------------------------------------------------------


def test_track_constants() -> None:
    # The hand-made constants above describe the tracks they are used with.
    assert isinstance(LINE, Track) and len(LINE) == 101 and LINE.x[-1] == pytest.approx(5.0)
    assert CRASH.x[-1] == pytest.approx(2.85) and len(CRASH) == 58
