"""Metrics of synthetic bags against values known by hand (docs/metrics.md's definitions).

Every bag here is written by ``synthetic.write_episode_bag`` into a temporary directory, read
back through the public API (``compute`` or ``read_episode`` + ``compute_metrics``) and
compared with a value worked out from the geometry, not from the code under test.

Tolerances (absolute unless stated):

* ``EXACT = 1e-12``: quantities that are exact in real arithmetic and only pick up float64
  rounding of O(1..10) values summed over ~100 samples (a few ulps each, ~1e-14 in all).
* ``DIFF = 1e-9``: finite differences of float64 samples: ``Δv/Δt`` divides a rounding error
  of ~1e-16 by ``Δt = 0.1`` s (twice for jerk), far below 1e-9.
* ``F32 = 1e-6``: scan ranges travel as float32 (relative error 6e-8, ranges <= 10 m), so
  anything read from a scan is compared to 1e-6 m.
* Chord-vs-arc: a circle sampled every ``Δφ`` has a path ``N·2r·sin(Δφ/2)``, shorter than
  the arc ``N·r·Δφ`` by a relative ``Δφ²/24``; the code is compared with the exact chord sum
  at ``DIFF`` and with the arc within that discretisation error.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
from rosbags.rosbag2 import Reader, Writer
from rosbags.typesys import Stores, get_typestore

from pic4rl_metrics import (
    EpisodeFacts,
    Footprint,
    TopicMap,
    compute,
    compute_metrics,
    read_episode,
)
from pic4rl_metrics.synthetic import (
    DEFAULT_T0_NS,
    Obstacles,
    Track,
    circle,
    speed_ramp,
    straight_line,
    write_episode_bag,
)

EXACT = 1e-12
DIFF = 1e-9
F32 = 1e-6
NS = 1_000_000_000

JACKAL = {"length_m": 0.508, "width_m": 0.430}  # half-length 0.254, half-width 0.215


def _row(bag: Path | str, **kwargs: object) -> dict[str, object]:
    """The one metrics row of ``bag`` (asserting that it was judged without error)."""
    frame = compute([bag], **kwargs).frame  # type: ignore[arg-type]
    assert len(frame) == 1, frame
    row = frame.iloc[0].to_dict()
    assert row["error"] == "", row["error"]
    return row


def _same(a: object, b: object) -> bool:
    """Equal, with NaN equal to NaN (and None to None)."""
    if isinstance(a, float) and isinstance(b, float) and math.isnan(a) and math.isnan(b):
        return True
    return a == b


def _rewrite(src: Path, dst: Path, *, outcome_stamp_ns: int | None = None,
             outcome_word_recv_ns: int | None = None) -> Path:
    """Copy bag ``src`` to ``dst`` message by message (a real rosbag2 bag again), changing
    the outcome event: its ``stamp_ns``, or a bare word (no stamp) received at a given bag
    time. custom_data is not copied (the facts and outcome topics carry what it held)."""
    ts = get_typestore(Stores.ROS2_JAZZY)
    with Reader(src) as reader, Writer(dst, version=9) as writer:
        conns = {c.id: writer.add_connection(c.topic, c.msgtype, typestore=ts)
                 for c in reader.connections}
        for conn, t_ns, raw in reader.messages():
            data = bytes(raw)
            if conn.topic == "/episode/outcome":
                msg = ts.deserialize_cdr(data, conn.msgtype)
                event = json.loads(msg.data)
                if outcome_stamp_ns is not None:
                    text = json.dumps(event | {"stamp_ns": outcome_stamp_ns})
                else:
                    text, t_ns = event["outcome"], outcome_word_recv_ns or t_ns
                data = ts.serialize_cdr(ts.types[conn.msgtype](text), conn.msgtype)
            writer.write(conns[conn.id], t_ns, data)
    return dst


# --- straight line ---------------------------------------------------------------------------

LINE = straight_line(0.5, 10.0)  # 0.5 m/s along +x for 10 s at 10 Hz: 101 poses, x 0..5 m


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


def test_headerless_outcome_word_is_placed_by_the_pose_offset(tmp_path: Path) -> None:
    # Receive times run 1000 s ahead of the header stamps; the bare word "goal" arrives at
    # receive time t0 + 1000 s + 7 s, i.e. 7 s into the episode on the header time base.
    offset = 1000 * NS
    src = write_episode_bag(tmp_path / "src", LINE, goal=(5.0, 0.0), outcome="goal",
                            receive_offset_ns=offset)
    bag = _rewrite(src, tmp_path / "word", outcome_word_recv_ns=DEFAULT_T0_NS + offset + 7 * NS)
    m = _row(bag)
    assert m["outcome"] == "goal"
    assert m["clearance_time_s"] == pytest.approx(7.0, abs=EXACT)


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


@pytest.mark.parametrize(
    ("max_speed", "expected"),
    [
        # l = 5 m, T = 10 s. OT = 5/3 s: 4 OT = 6.7 <= T <= 8 OT = 13.3, no clip: OT / T.
        (3.0, (5 / 3) / 10.0),
        # OT = 5 s: T < 4 OT = 20, clipped up: OT / (4 OT) = 1/4.
        (1.0, 0.25),
        # OT = 0.5 s: T > 8 OT = 4, clipped down: OT / (8 OT) = 1/8.
        (10.0, 0.125),
    ],
)
def test_barn_score_by_hand(line_bags, max_speed: float, expected: float) -> None:
    facts = EpisodeFacts(max_speed_mps=max_speed)
    given = frozenset({"max_speed_mps"})
    assert _row(line_bags["goal"], facts=facts, given=given)["barn_score"] == pytest.approx(
        expected, abs=EXACT
    )
    # S = 0 for a timeout.
    assert _row(line_bags["timeout"], facts=facts, given=given)["barn_score"] == 0.0


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


# --- circle -----------------------------------------------------------------------------------

R, V, T_CIRCLE, DT = 1.0, 0.5, 10.0, 0.1  # 5 rad of arc: crosses the +-pi yaw wrap
DPHI = V / R * DT  # turn between samples (rad)
N_SEG = round(T_CIRCLE / DT)  # 100 chords
CHORD = 2 * R * math.sin(DPHI / 2)


@pytest.fixture(scope="module")
def circle_bags(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    root = tmp_path_factory.mktemp("circle")
    track = circle(R, V, T_CIRCLE, DT)
    return {
        "odometry": write_episode_bag(root / "odom", track),
        "pose_only": write_episode_bag(
            root / "pose", track, pose_type="pose_stamped", also_odom=False
        ),
    }


@pytest.mark.parametrize("source", ["odometry", "pose_only"])
def test_circle_path_and_turning(circle_bags, source: str) -> None:
    m = _row(circle_bags[source])
    arc = V * T_CIRCLE  # 2 pi r x (fraction covered = 5 / 2 pi)
    assert arc == pytest.approx(2 * math.pi * R * (V / R * T_CIRCLE) / (2 * math.pi))
    assert m["path_length_m"] == pytest.approx(N_SEG * CHORD, abs=DIFF)
    assert m["path_length_m"] == pytest.approx(arc, rel=DPHI**2 / 24 * 1.01)
    # Every interior vertex turns by DPHI between two chords of equal length.
    assert m["path_curvature_mean_radpm"] == pytest.approx(DPHI / CHORD, abs=DIFF)
    assert m["path_curvature_mean_radpm"] == pytest.approx(1 / R, rel=DPHI**2 / 24 * 1.01)
    # 99 turns over 100 chords.
    expected_aol = (N_SEG - 1) * DPHI / (N_SEG * CHORD)
    assert m["angle_over_length_radpm"] == pytest.approx(expected_aol, abs=DIFF)
    assert m["angle_over_length_radpm"] == pytest.approx(1 / R, rel=1.5 / N_SEG)


def test_slow_circle_turning_is_measured_after_merging_close_positions(tmp_path: Path) -> None:
    # r = 1 m at 0.05 m/s, 10 Hz: samples 5 mm apart (dphi = 0.005 rad). Two steps make a
    # chord 2 sin(0.005) = 9.99996 mm < 1 cm, three steps 2 sin(0.0075) = 15 mm: the 1 cm
    # merge keeps every third pose, indices 0, 3, ..., 99 (34 points, 32 interior vertices).
    dphi = 0.005
    m = _row(write_episode_bag(tmp_path / "slow", circle(1.0, 0.05, 10.0)))
    chord3 = 2 * math.sin(1.5 * dphi)
    assert m["path_curvature_mean_radpm"] == pytest.approx(3 * dphi / chord3, abs=DIFF)
    # The path length is over all poses (no smoothing): 100 chords of 2 sin(dphi / 2).
    raw_length = 100 * 2 * math.sin(dphi / 2)
    assert m["path_length_m"] == pytest.approx(raw_length, abs=DIFF)
    assert m["angle_over_length_radpm"] == pytest.approx(32 * 3 * dphi / raw_length, abs=DIFF)


@pytest.mark.parametrize("source", ["odometry", "pose_only"])
def test_circle_yaw_rate_is_constant(circle_bags, source: str) -> None:
    m = _row(circle_bags[source])
    assert m["ang_vel_mean_radps"] == pytest.approx(V / R, abs=DIFF)
    assert m["ang_vel_std_radps"] == pytest.approx(0.0, abs=DIFF)
    assert m["yaw_acc_max_radps2"] == pytest.approx(0.0, abs=DIFF)
    assert m["yaw_acc_mean_radps2"] == pytest.approx(0.0, abs=DIFF)
    assert m["yaw_jerk_max_radps3"] == pytest.approx(0.0, abs=DIFF)
    # Odometry reports the tangential speed V; poses give chord / dt, the mean speed along
    # each chord (both constant, so no linear acceleration).
    speed = V if source == "odometry" else CHORD / DT
    assert m["lin_vel_mean_mps"] == pytest.approx(speed, abs=DIFF)
    assert m["lin_vel_std_mps"] == pytest.approx(0.0, abs=DIFF)
    assert m["lin_acc_max_mps2"] == pytest.approx(0.0, abs=DIFF)


def test_circle_pose_differences_rotate_into_the_body_frame(circle_bags) -> None:
    from pic4rl_metrics.kinematics import velocity_series

    ep = read_episode(circle_bags["pose_only"])
    assert ep.pose.vx is None  # pose-only source
    vel = velocity_series(ep.pose)
    # The chord of each interval points along the interval's mean heading: vy = 0.
    np.testing.assert_allclose(vel.vx, CHORD / DT, atol=DIFF)
    np.testing.assert_allclose(vel.vy, 0.0, atol=DIFF)
    np.testing.assert_allclose(vel.wz, V / R, atol=DIFF)
    # Placed at interval midpoints.
    np.testing.assert_array_equal(vel.t_ns, ep.pose.t_ns[:-1] + np.diff(ep.pose.t_ns) // 2)


# --- speed ramp (constant jerk) --------------------------------------------------------------

JERK, T_RAMP = 0.2, 3.0


@pytest.fixture(scope="module")
def ramp_bags(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    root = tmp_path_factory.mktemp("ramp")
    track = speed_ramp(JERK, T_RAMP, DT)
    return {
        "odometry": write_episode_bag(root / "odom", track),
        "pose_only": write_episode_bag(
            root / "pose", track, pose_type="pose_stamped", also_odom=False
        ),
    }


def test_speed_ramp_from_twist(ramp_bags) -> None:
    m = _row(ramp_bags["odometry"])
    # v = j t^2 / 2 at t = 0, dt, ..., T: a at the interval midpoints = j t_mid exactly.
    t_mid_last = T_RAMP - DT / 2
    assert m["lin_acc_max_mps2"] == pytest.approx(JERK * t_mid_last, abs=DIFF)
    assert m["lin_acc_mean_mps2"] == pytest.approx(JERK * T_RAMP / 2, abs=DIFF)  # mean t_mid
    assert m["lin_jerk_max_mps3"] == pytest.approx(JERK, abs=DIFF)
    assert m["lin_jerk_mean_mps3"] == pytest.approx(JERK, abs=DIFF)
    # Trapezoid mean of j t^2 / 2: (j/2) (T^2/3 + dt^2/6).
    assert m["lin_vel_mean_mps"] == pytest.approx(JERK / 2 * (T_RAMP**2 / 3 + DT**2 / 6), abs=DIFF)
    assert m["path_length_m"] == pytest.approx(JERK * T_RAMP**3 / 6, abs=EXACT)


def test_speed_ramp_from_pose_differences(ramp_bags) -> None:
    m = _row(ramp_bags["pose_only"])
    # Δx/Δt of x = j t^3/6 is (j/2)(t_mid^2 + dt^2/12) at the interval midpoints; its
    # difference over the midpoints is j times the sample time between them: 0.1 .. T - dt.
    assert m["lin_acc_max_mps2"] == pytest.approx(JERK * (T_RAMP - DT), abs=DIFF)
    assert m["lin_acc_mean_mps2"] == pytest.approx(JERK * T_RAMP / 2, abs=DIFF)
    assert m["lin_jerk_max_mps3"] == pytest.approx(JERK, abs=DIFF)
    assert m["lin_jerk_mean_mps3"] == pytest.approx(JERK, abs=DIFF)


# --- pose-only and PoseWithCovarianceStamped sources ------------------------------------------


@pytest.mark.parametrize("yaw", [0.0, math.radians(30)])
def test_pose_only_straight_line_speeds_match_the_analytic_ones(tmp_path: Path, yaw: float) -> None:
    track = straight_line(0.5, 10.0, start=(1.0, -2.0, yaw))
    bag = write_episode_bag(tmp_path / "pose", track, pose_type="pose_stamped", also_odom=False)
    ep = read_episode(bag)
    assert ep.pose.vx is None
    m = compute_metrics(ep)
    assert m.lin_vel_mean_mps == pytest.approx(0.5, abs=DIFF)
    assert m.lin_vel_std_mps == pytest.approx(0.0, abs=DIFF)
    assert m.lin_acc_max_mps2 == pytest.approx(0.0, abs=DIFF)
    assert m.ang_vel_mean_radps == pytest.approx(0.0, abs=DIFF)
    assert m.path_length_m == pytest.approx(5.0, abs=EXACT)
    from pic4rl_metrics.kinematics import velocity_series

    vel = velocity_series(ep.pose)
    np.testing.assert_allclose(vel.vx, 0.5, atol=DIFF)  # body frame: all forward
    np.testing.assert_allclose(vel.vy, 0.0, atol=DIFF)


def test_pose_with_covariance_source_via_topic_map(tmp_path: Path) -> None:
    bag = write_episode_bag(
        tmp_path / "amcl", LINE, pose_topic="/amcl_pose", pose_type="pose_cov", also_odom=False
    )
    # Not a default pose topic and not Odometry: without a map the bag is an error row.
    frame = compute([bag]).frame
    assert "/amcl_pose" in frame.loc[0, "error"]
    m = _row(bag, topic_map=TopicMap(pose=("/amcl_pose",)))
    assert m["pose_topic"] == "/amcl_pose"
    assert m["path_length_m"] == pytest.approx(5.0, abs=EXACT)
    assert m["lin_vel_mean_mps"] == pytest.approx(0.5, abs=DIFF)
    # Same through the override the CLI's --pose-topic uses.
    via_override = _row(bag, topic_map=TopicMap().with_overrides(pose=("amcl_pose",)))
    assert via_override["path_length_m"] == pytest.approx(5.0, abs=EXACT)


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
    assert m["outcome"] == "collision" and m["success"] == 0.0
    assert m["obstacle_dist_min_m"] == pytest.approx(WALL_X - 2.85, abs=F32)
    # margin = (3.03 - x) - 0.2 <= 0.05 from x = 2.80 on: one rising edge.
    assert m["collision_count"] == 1.0
    # margin <= 0.3 (safety) from x = 2.55 (t = 5.1 s) to the end (5.7 s): 6 intervals held.
    assert m["safety_violation_time_s"] == pytest.approx(0.6, abs=EXACT)
    assert m["safety_violation_time_s"] > 0


def test_collision_count_counts_rising_edges(tmp_path: Path) -> None:
    from pic4rl_metrics.synthetic import from_waypoints

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
    from pic4rl_metrics.metrics import scan_clearance

    margin = scan_clearance(ep.scan, ep.facts).margin_m
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


# --- time base -----------------------------------------------------------------------------


@pytest.mark.parametrize("stamped", [False, True])
def test_headerless_cmd_vel_lands_on_the_header_time_base(tmp_path: Path, stamped: bool) -> None:
    bag = write_episode_bag(
        tmp_path / "offset", LINE, cmd_stamped=stamped, receive_offset_ns=1000 * NS
    )
    ep = read_episode(bag)
    assert ep.cmd is not None and len(ep.cmd) == len(ep.pose)
    assert abs(int(ep.cmd.t_ns[0]) - int(ep.pose.t_ns[0])) <= 1_000_000  # within 1 ms
    assert abs(int(ep.cmd.t_ns[-1]) - int(ep.pose.t_ns[-1])) <= 1_000_000
    assert int(ep.pose.t_ns[0]) == DEFAULT_T0_NS  # header stamps, not receive times
    assert compute_metrics(ep).clearance_time_s == pytest.approx(10.0, abs=EXACT)


# --- storage: killed recorder, MCAP ------------------------------------------------------------

FACTS = {"agent": "td3", "run": "r1", "episode": "3", "footprint": {"radius_m": 0.2}}
SCENE = Obstacles(circles=((2.5, 0.8, 0.3),), segments=((-1.0, -1.0, 8.0, -1.0),))


def _episode_kwargs() -> dict[str, object]:
    return {"obstacles": SCENE, "goal": (5.0, 0.0), "facts": FACTS, "outcome": "goal"}


def _assert_same_rows(a: dict[str, object], b: dict[str, object]) -> None:
    differ = {k: (a[k], b[k]) for k in a if k != "bag" and not _same(a[k], b[k])}
    assert differ == {}


def test_killed_recorder_gives_the_same_row(tmp_path: Path) -> None:
    full = write_episode_bag(tmp_path / "full", LINE, **_episode_kwargs())
    killed = write_episode_bag(
        tmp_path / "bags" / "killed", LINE, write_metadata=False, **_episode_kwargs()
    )
    files = sorted(p.name for p in killed.iterdir())
    assert files == ["killed.db3"]
    reference = _row(full)
    assert reference["outcome"] == "goal"
    assert not math.isnan(reference["collision_count"])  # the footprint was there
    _assert_same_rows(reference, _row(killed / "killed.db3"))
    globbed = compute([str(tmp_path / "bags" / "*" / "*.db3")]).frame
    assert len(globbed) == 1
    _assert_same_rows(reference, globbed.iloc[0].to_dict())
    # The facts came from the facts topic (custom_data lived in the lost metadata.yaml).
    ep = read_episode(killed / "killed.db3")
    assert ep.facts.agent == "td3" and ep.facts.run == "r1"
    assert ep.facts.goal == (5.0, 0.0)
    assert ep.facts.footprint == Footprint(radius_m=0.2)


def test_mcap_gives_the_same_metrics_as_sqlite3(tmp_path: Path) -> None:
    sqlite = write_episode_bag(tmp_path / "sqlite", LINE, **_episode_kwargs())
    mcap = write_episode_bag(tmp_path / "mcap", LINE, storage="mcap", **_episode_kwargs())
    assert any(p.suffix == ".mcap" for p in mcap.iterdir())
    a, b = _row(sqlite), _row(mcap)
    _assert_same_rows(a, b)
    # The cylinder (2.5, 0.8, r 0.3) passes 0.8 - 0.3 = 0.5 m to the left at x = 2.5.
    assert a["obstacle_dist_min_m"] == pytest.approx(0.5, abs=F32)


# --- inputs ------------------------------------------------------------------------------------


def _bags(inputs: list[object]) -> list[Path]:
    frame = compute(inputs).frame  # type: ignore[arg-type]
    assert (frame["error"] == "").all(), frame["error"].tolist()
    return [Path(b).resolve() for b in frame["bag"]]


def test_inputs_all_name_the_same_bags_once(tmp_path: Path) -> None:
    root = tmp_path / "runs"
    short = straight_line(0.5, 1.0)
    a = write_episode_bag(root / "a", short)
    b = write_episode_bag(root / "deep" / "er" / "b", short)
    k = write_episode_bag(root / "deep" / "k", short, write_metadata=False)
    every = sorted(p.resolve() for p in (a, b, k / "k.db3"))

    assert _bags([root]) == every  # a directory, searched recursively
    assert _bags([a / "metadata.yaml"]) == [a.resolve()]
    assert _bags([a / "a.db3"]) == [a.resolve()]  # the .db3 beside its metadata is that bag
    assert _bags([a, a / "metadata.yaml", a / "a.db3"]) == [a.resolve()]  # once, not thrice
    assert _bags([str(root / "**" / "metadata.yaml")]) == sorted([a.resolve(), b.resolve()])
    assert _bags([str(root / "**" / "*.db3")]) == every
    assert _bags([root, str(root / "*"), a, k / "k.db3", b / "metadata.yaml"]) == every


def test_input_naming_nothing_is_an_error_row(tmp_path: Path) -> None:
    frame = compute([tmp_path / "missing", str(tmp_path / "*.db3")]).frame
    assert len(frame) == 2
    assert all(frame["error"] != "")
    assert frame["outcome"].isna().all()


def test_track_constants() -> None:
    # The hand-made constants above describe the tracks they are used with.
    assert isinstance(LINE, Track) and len(LINE) == 101 and LINE.x[-1] == pytest.approx(5.0)
    assert CRASH.x[-1] == pytest.approx(2.85) and len(CRASH) == 58
