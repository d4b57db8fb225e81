"""The ``orca`` baseline (``pic4rl_bridge.baselines.orca``): two ORCA agents head-on choose
velocities outside their truncated velocity obstacle, and a person standing on the straight
path to the goal is passed with clearance, by ORCA through the ``people`` reading and by DWA
through the scan alone (the crowd's people are obstacles to the scan-based baselines)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from pic4rl_base.geometry import Footprint, Pose2D
from pic4rl_bridge.baselines.orca import OrcaController, orca_line, solve
from pic4rl_bridge.baselines.registry import make_baseline
from pic4rl_bridge.config import EnvConfig
from pic4rl_bridge.control.actions import planar_command
from pic4rl_bridge.readings.frame import ScanData
from pic4rl_bridge.readings.sensor_table import build_frame
from pic4rl_bridge.robot_info import RobotInfo
from pic4rl_sim.engine.geometry import Twist2D

#: The Jackal of env_goto_lidar.yaml: v in [0, 0.5] m/s, |ω| <= 1 rad/s, 3 m/s², 6 rad/s².
JACKAL = RobotInfo(name="jackal", footprint=Footprint(length_m=0.508, width_m=0.430), omni=False,
                   min_linear_m_s=0.0, max_linear_m_s=0.5, max_angular_rad_s=1.0,
                   max_lateral_m_s=0.0, control_dt_s=0.1,
                   mounts={"lidar": Pose2D(0.12, 0.0, 0.0)},
                   max_linear_accel_m_s2=3.0, max_angular_accel_rad_s2=6.0)
PERSON = np.array([2.0, 0.0])
PERSON_RADIUS_M = 0.25


def _vo_distance(rel_position: np.ndarray, rel_velocity: np.ndarray, horizon_s: float) -> float:
    """The least distance between two discs' centres over (0, ``horizon_s``] at constant
    relative velocity (own minus other's)."""
    speed_sq = float(rel_velocity @ rel_velocity)
    t = 0.0 if speed_sq == 0 else float(np.clip(rel_position @ rel_velocity / speed_sq, 0.0,
                                                horizon_s))
    return float(np.hypot(*(rel_position - t * rel_velocity)))


def test_two_agents_head_on_each_take_half_and_leave_the_velocity_obstacle() -> None:
    a, b = np.array([0.0, 0.0]), np.array([4.0, 0.05])
    va, vb = np.array([1.0, 0.0]), np.array([-1.0, 0.0])
    radius, horizon = 1.0, 3.0
    assert _vo_distance(b - a, va - vb, horizon) < radius  # they would collide within 3 s
    line_a = orca_line(b - a, va - vb, va, radius, horizon, 0.1, 0.5)
    line_b = orca_line(a - b, vb - va, vb, radius, horizon, 0.1, 0.5)
    new_a = solve([line_a], 1.0, va)
    new_b = solve([line_b], 1.0, vb)
    assert _vo_distance(b - a, new_a - new_b, horizon) >= radius - 1e-9
    np.testing.assert_allclose(new_a, -new_b, atol=1e-9)  # reciprocal: equal shares
    assert new_a[1] < 0.0 < new_b[1]  # each to its right
    assert np.hypot(*new_a) <= 1.0 + 1e-9


def test_a_velocity_the_half_planes_cannot_all_permit_violates_them_least() -> None:
    up = orca_line(np.array([0.0, -1.0]), np.zeros(2), np.zeros(2), 1.2, 1.0, 0.1, 1.0)
    down = orca_line(np.array([0.0, 1.0]), np.zeros(2), np.zeros(2), 1.2, 1.0, 0.1, 1.0)
    chosen = solve([up, down], 1.0, np.array([1.0, 0.0]))
    assert abs(chosen[1]) < 1e-9  # squeezed between two overlapping discs: midway


def _scan(pose: Pose2D, beams: int = 180, range_max_m: float = 6.0) -> ScanData:
    """The LiDAR's scan of the standing person's cylinder from ``pose``."""
    mount = JACKAL.mounts["lidar"]
    c, s = math.cos(pose.yaw), math.sin(pose.yaw)
    origin = np.array([pose.x + c * mount.x, pose.y + s * mount.x])
    angles = -math.pi + 2 * math.pi / beams * np.arange(beams)
    dirs = np.column_stack((np.cos(angles + pose.yaw), np.sin(angles + pose.yaw)))
    to_c = PERSON - origin
    along = dirs @ to_c
    disc = along**2 - (to_c @ to_c - PERSON_RADIUS_M**2)
    hit = along - np.sqrt(np.maximum(disc, 0.0))
    ranges = np.where((disc >= 0) & (hit > 0) & (hit < range_max_m), hit, np.inf)
    return ScanData(ranges.astype(np.float32), float(angles[0]), 2 * math.pi / beams, 0.1,
                    range_max_m, mount)


def _pass_person(name: str) -> tuple[float, Pose2D]:
    """Drive baseline ``name`` from (0, 0) to (4, 0) past the person at (2, 0): the least
    clearance between the footprint and the person's disc, and the last pose."""
    config = EnvConfig(task="goToPose")
    baseline = make_baseline(name, config, JACKAL)
    baseline.reset()
    pose, twist, clearance = Pose2D(0.0, 0.0, 0.0), Twist2D(), math.inf
    for step in range(300):
        readings = {"scan": _scan(pose), "people": np.array([[*PERSON, 0.0]])}
        frame = build_frame(step * 100_000_000, (pose, twist), (4.0, 0.0), readings,
                            lambda sensor: readings.get(sensor.name))
        twist = planar_command(baseline.action(frame), JACKAL)
        yaw = pose.yaw + twist.wz * 0.1
        pose = Pose2D(pose.x + twist.vx * math.cos(yaw) * 0.1,
                      pose.y + twist.vx * math.sin(yaw) * 0.1, yaw)
        c, s = math.cos(pose.yaw), math.sin(pose.yaw)
        rel = PERSON - (pose.x, pose.y)
        local = np.array([[c * rel[0] + s * rel[1], -s * rel[0] + c * rel[1]]])
        clearance = min(clearance, float(JACKAL.footprint.signed_distance(local)[0])
                        - PERSON_RADIUS_M)
        if math.hypot(4.0 - pose.x, pose.y) < 0.2:
            break
    return clearance, pose


@pytest.mark.parametrize("name", ["orca", "dwa"])
def test_a_person_standing_on_the_path_is_passed_with_clearance(name: str) -> None:
    clearance, pose = _pass_person(name)
    assert math.hypot(4.0 - pose.x, pose.y) < 0.2, pose  # it got there
    assert clearance > 0.0, clearance


def test_people_velocities_are_finite_differences_kept_across_steps() -> None:
    orca = OrcaController(JACKAL)
    for stamp, people in ((0, [[1.0, 2.0, 0.0]]), (200_000_000, [[1.2, 1.9, 0.0]])):
        frame = build_frame(stamp, (Pose2D(0.0, 0.0, 0.0), Twist2D()), (4.0, 0.0), {"people"},
                            lambda sensor, p=people: np.array(p))
        xy, velocity = orca.people_velocities(frame)
    np.testing.assert_allclose(velocity, [[1.0, -0.5]])
    orca.reset()
    assert not orca.people_velocities(frame)[1].any()  # forgotten: from zero again
