"""Footprint clearance from synthetic scans and depth images, against analytic distances."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from pic4rl_base.geometry import Footprint, Pose2D
from pic4rl_bridge.config import EnvConfig
from pic4rl_bridge.perception.collision import assess, depth_points, obstacle_distance
from pic4rl_bridge.readings.frame import ScanData, SensorFrame
from pic4rl_bridge.robot_info import RobotInfo
from pic4rl_sim.engine.geometry import Twist2D

CIRCLE = Footprint(radius_m=0.3)
RECT = Footprint(length_m=0.6, width_m=0.4)
INC = 2 * math.pi / 360


def robot(footprint: Footprint = CIRCLE, depth_mount: Pose2D | None = None) -> RobotInfo:
    return RobotInfo(name="test", footprint=footprint, omni=False, min_linear_m_s=0.0,
                     max_linear_m_s=0.5, max_angular_rad_s=1.0, max_lateral_m_s=0.0,
                     control_dt_s=0.1, mounts={"depth": depth_mount} if depth_mount else {},
                     depth_hfov_rad=math.radians(90.0))


def wall_scan(x_wall: float, mount: Pose2D = Pose2D(0.0, 0.0, 0.0)) -> ScanData:
    """360 beams from -pi seeing the wall x = x_wall (base frame) and nothing else."""
    angles = -math.pi + INC * np.arange(360) + mount.yaw  # beam directions in the base frame
    along = np.cos(angles)
    with np.errstate(divide="ignore"):
        ranges = np.where(along > 1e-9, (x_wall - mount.x) / along, np.inf)
    return ScanData(ranges.astype(np.float32), -math.pi, INC, 0.1, 30.0, mount)


def frame(scan: ScanData | None = None, depth: np.ndarray | None = None) -> SensorFrame:
    return SensorFrame(0, Pose2D(0.0, 0.0, 0.0), Twist2D(), scan=scan, depth=depth)


def test_scan_points_use_the_mount_and_rep117():
    ranges = np.array([1.0, np.inf, np.nan, -np.inf], np.float32)
    scan = ScanData(ranges, 0.0, math.pi / 2, 0.25, 10.0, Pose2D(0.2, 0.1, math.pi / 2))
    pts = scan.points()
    # beam 0 (along the LiDAR's x = base +y) at 1 m; beam 3 (LiDAR -y = base +x) at range_min
    np.testing.assert_allclose(pts, [[0.2, 1.1], [0.45, 0.1]], atol=1e-12)


@pytest.mark.parametrize("footprint, expected", [(CIRCLE, 1.7), (RECT, 1.7)])
def test_wall_ahead_gives_exact_clearance(footprint, expected):
    assert obstacle_distance(frame(wall_scan(2.0)), robot(footprint)) == pytest.approx(
        expected, abs=1e-6)


def test_off_centre_and_backward_lidar_see_the_same_wall():
    for mount in (Pose2D(0.25, 0.0, 0.0), Pose2D(0.25, 0.0, math.pi), Pose2D(-0.1, 0.05, 0.3)):
        scan = wall_scan(2.0, mount)
        assert obstacle_distance(frame(scan), robot(RECT)) == pytest.approx(1.7, abs=1e-5)
    # a circle's nearest wall point is straight ahead, which an off-axis LiDAR may miss by a
    # beam; from (0.25, 0) the 0-degree beam exists
    assert obstacle_distance(frame(wall_scan(2.0, Pose2D(0.25, 0.0, 0.0))),
                             robot(CIRCLE)) == pytest.approx(1.7, abs=1e-6)


def test_rectangle_distance_is_the_exact_box_distance():
    pts = np.array([[0.0, 0.0], [0.0, 1.0], [1.0, 0.1], [0.6, 0.6], [0.25, 0.0], [0.3, 0.2]])
    np.testing.assert_allclose(RECT.signed_distance(pts),
                               [-0.2, 0.8, 0.7, math.hypot(0.3, 0.4), -0.05, 0.0], atol=1e-12)
    np.testing.assert_allclose(CIRCLE.signed_distance(pts[:2]), [-0.3, 0.7])


def test_no_returns_is_infinitely_far():
    empty = ScanData(np.full(360, np.inf, np.float32), -math.pi, INC, 0.1, 30.0)
    assert obstacle_distance(frame(empty), robot()) == math.inf
    assert obstacle_distance(frame(), robot()) == math.inf


def test_too_close_beam_collides_at_range_min():
    ranges = np.full(360, np.inf, np.float32)
    ranges[180] = -np.inf  # straight ahead
    scan = ScanData(ranges, -math.pi, INC, 0.1, 30.0, Pose2D(0.2, 0.0, 0.0))
    assert obstacle_distance(frame(scan), robot(CIRCLE)) == pytest.approx(0.0, abs=1e-9)


def test_depth_fallback_wall_ahead():
    image = np.full((6, 8), 2.0, np.float32)
    image[0, :] = np.inf  # sky: ignored
    image[1, 3] = np.nan
    mount = Pose2D(0.1, 0.0, 0.0)
    # the central columns look 0.5 px off axis: y = ±2 * 0.5 / f with f = 4 px, beside the box
    rect = obstacle_distance(frame(depth=image), robot(RECT, depth_mount=mount))
    assert rect == pytest.approx(math.hypot(2.1 - 0.3, 0.25 - 0.2), abs=1e-12)
    circle = obstacle_distance(frame(depth=image), robot(CIRCLE, depth_mount=mount))
    assert circle == pytest.approx(math.hypot(2.1, 0.25) - 0.3, abs=1e-12)
    image[:, 3:5] = np.inf  # the central columns see nothing: the next ones are the nearest
    rect = obstacle_distance(frame(depth=image), robot(RECT, depth_mount=mount))
    assert rect == pytest.approx(math.hypot(2.1 - 0.3, 0.75 - 0.2), abs=1e-12)


def test_depth_points_pinhole_geometry():
    image = np.full((4, 8), np.inf, np.float32)
    image[2, 0] = 3.0  # leftmost column: left of the optical axis
    image[1, 0] = 4.0  # farther pixel of the same column: not the column's minimum
    pts = depth_points(image, Pose2D(0.1, 0.05, 0.0), math.radians(90.0))
    # column 0's centre: tan(bearing) = (W/2 - 0.5) / f, f = (W/2) / tan(45 deg) = 4
    np.testing.assert_allclose(pts, [[3.1, 0.05 + 3.0 * 3.5 / 4.0]])


def test_depth_points_of_the_floor_are_not_obstacles():
    """A level camera 0.4 m up: a pixel below the horizon at the depth where its ray meets
    the floor is the floor (no obstacle with the robot's camera height; one without it), and
    the same pixel nearer is an obstacle."""
    image = np.full((4, 8), np.inf, np.float32)
    down = 1.5 / 4.0  # row 3's centre, f = 4 px
    image[3, 4] = 0.4 / down  # where its ray meets the floor
    mount = Pose2D(0.1, 0.0, 0.0)
    assert len(depth_points(image, mount, math.radians(90.0))) == 1
    assert not len(depth_points(image, mount, math.radians(90.0), height_m=0.4))
    info = robot(CIRCLE, depth_mount=mount)
    info = dataclasses.replace(info, depth_height_m=0.4)
    assert obstacle_distance(frame(depth=image), info) == math.inf
    image[3, 4] = 0.5  # 0.21 m above the floor: a box, 0.5 m ahead and 1/8 of that right
    assert obstacle_distance(frame(depth=image), info) == pytest.approx(
        math.hypot(0.6, 0.5 / 8.0) - 0.3, abs=1e-6)


def test_depth_too_close_counts_as_touching():
    image = np.full((4, 8), np.inf, np.float32)
    image[3, 4] = -np.inf
    info = robot(CIRCLE, depth_mount=Pose2D(0.1, 0.0, 0.0))
    assert obstacle_distance(frame(depth=image), info) == pytest.approx(0.1 - 0.3)


def test_assess_streak_warning_and_end():
    config = EnvConfig().replace(collision_steps=3)
    near = frame(wall_scan(0.32))  # clearance 0.02 < collision 0.05
    streaks = []
    for _ in range(3):
        s = assess(near, robot(), config, streaks[-1] if streaks else 0)
        streaks.append(s.streak)
        assert s.collision and s.warning
    assert streaks == [1, 2, 3]
    assert [assess(near, robot(), config, k).ended for k in (0, 1, 2)] == [False, False, True]
    warn = assess(frame(wall_scan(0.38)), robot(), config, 2)  # clearance 0.08
    assert (warn.collision, warn.warning, warn.streak, warn.ended) == (False, True, 0, False)
    assert warn.min_obstacle_m == pytest.approx(0.08, abs=1e-6)
