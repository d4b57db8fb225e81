"""``kinematics``: path, speeds, accelerations and turning of synthetic circles, speed ramps and
pose-only tracks against their analytic values (tolerances: ``metrics_helpers``).

Chord-vs-arc: a circle sampled every ``Δφ`` has a path ``N·2r·sin(Δφ/2)``, shorter than the
arc ``N·r·Δφ`` by a relative ``Δφ²/24``; the code is compared with the exact chord sum at
``DIFF`` and with the arc within that discretisation error.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from metrics_helpers import DIFF, EXACT, LINE
from metrics_helpers import row as _row

from pic4rl_metrics import (
    TopicMap,
    compute,
    compute_metrics,
    read_episode,
)
from pic4rl_metrics.synthetic.synthetic import (
    circle,
    speed_ramp,
    straight_line,
    write_episode_bag,
)

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
    from pic4rl_metrics.core.kinematics import velocity_series

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
    from pic4rl_metrics.core.kinematics import velocity_series

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
