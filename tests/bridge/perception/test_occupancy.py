"""The rolling occupancy grid of the robot's own scans: a known sequence of poses and scans
gives the expected cells in the egocentric crop (translation, rotation, heading up, the
LiDAR's mount), the grid remembers what left the view, rolls past its extent and resets; the
depth image's pseudo-scan reads an analytic wall's ranges and drops the floor (level and
pitched cameras, and the simulator's own camera beside its LiDAR)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from pic4rl_base.geometry import Pose2D

from pic4rl_bridge.env import NavEnv
from pic4rl_bridge.perception.collision import FLOOR_M, depth_scan
from pic4rl_bridge.perception.occupancy import OccupancyGrid
from pic4rl_bridge.readings.frame import ScanData


def _scan(angle: float, r: float, mount: Pose2D = Pose2D(0.0, 0.0, 0.0)) -> ScanData:
    """One return at ``angle`` (rad) and ``r`` (m), beside beams with nothing in range."""
    ranges = np.full(8, np.inf, np.float32)
    ranges[4] = r
    return ScanData(ranges, angle - 4 * math.pi / 4, math.pi / 4, 0.05, 10.0, mount)


def _lit(crop: np.ndarray) -> list[tuple[int, int]]:
    return [tuple(int(v) for v in rc) for rc in np.argwhere(crop)]


def test_a_return_ahead_lands_ahead_of_the_centre_heading_up():
    grid = OccupancyGrid(0.05)
    grid.mark_scan(_scan(0.0, 1.2), Pose2D(0.0, 0.0, 0.0))
    # The cell's centre (1.225, 0.025): 2.45 pixels of 0.5 m ahead, 0.05 left of the centre.
    assert _lit(grid.crop(Pose2D(0.0, 0.0, 0.0), 8, 0.5)) == [(1, 3)]
    # Translated: the robot 1 m on, the return 0.225 m ahead.
    assert _lit(grid.crop(Pose2D(1.0, 0.0, 0.0), 8, 0.5)) == [(3, 3)]
    # Rotated: facing +y, the same world point is on the robot's right (heading up).
    assert _lit(grid.crop(Pose2D(0.0, 0.0, math.pi / 2), 8, 0.5)) == [(3, 6)]
    # Behind: facing -x, it is below the centre.
    assert _lit(grid.crop(Pose2D(0.0, 0.0, math.pi), 8, 0.5)) == [(6, 4)]


def test_the_scan_is_placed_with_the_pose_and_the_mount():
    grid = OccupancyGrid(0.05)
    mount = Pose2D(0.2, 0.0, math.pi)  # mounted backwards, 0.2 m ahead of the base
    grid.mark_scan(_scan(0.0, 1.0, mount), Pose2D(2.01, 1.01, math.pi / 2))
    # base frame: (0.2 - 1.0, 0) = (-0.8, 0); the robot faces +y: world (2.01, 1.01 - 0.8)
    assert np.array_equal(grid.cells, [[40, 4]])
    assert np.allclose(_scan(0.0, 1.0, mount).points(), [[-0.8, 0.0]])


def test_it_remembers_what_left_the_view_marks_once_and_resets():
    grid = OccupancyGrid(0.05)
    first = grid.mark_scan(_scan(0.0, 1.2), Pose2D(0.0, 0.0, 0.0))
    again = grid.mark_scan(_scan(0.0, 1.2), Pose2D(0.0, 0.0, 0.0))
    grid.mark_scan(_scan(math.pi / 2, 1.2), Pose2D(0.0, 0.0, 0.0))  # a second one, left
    assert len(first) == 1 and len(again) == 0 and len(grid.cells) == 2
    assert grid.occupied(np.array([[1.21, 0.01], [0.01, 1.21], [0.5, 0.5]])).tolist() == [
        True, True, False]
    grid.reset()
    assert len(grid.cells) == 0 and not grid.crop(Pose2D(0.0, 0.0, 0.0), 8, 0.5).any()


def test_past_its_extent_it_rolls_and_forgets_the_far_cells():
    grid = OccupancyGrid(0.05, max_extent_m=20.0)
    grid.mark(np.array([[0.51, 0.51]]), (0.0, 0.0))
    grid.mark(np.array([[40.01, 0.01]]), (40.0, 0.0))  # the robot drove 40 m on
    assert np.array_equal(grid.cells, [[800, 0]])
    assert grid.occupied(np.array([[40.01, 0.01], [0.51, 0.51]])).tolist() == [True, False]


def test_the_depth_pseudo_scan_reads_a_square_wall_s_ranges():
    hfov, width, wall = math.radians(90.0), 64, 2.0
    image = np.full((6, width), wall, np.float32)  # a wall square to the camera: depth 2 m
    image[:, -3:] = np.inf  # nothing in range at the right edge (the image's last columns)
    scan = depth_scan(image, Pose2D(0.1, 0.0, 0.0), hfov)
    angles = scan.angles()
    assert len(angles) == width and angles[0] == pytest.approx(-hfov / 2 + hfov / width / 2)
    assert angles[-1] == pytest.approx(hfov / 2 - hfov / width / 2)
    seen = np.isfinite(scan.ranges)
    assert not seen[0] and seen[width // 2:].all()  # the right edge: the lowest angles
    assert np.allclose(scan.ranges[seen], wall / np.cos(angles[seen]), rtol=1e-6)
    points = scan.points()
    assert np.allclose(points[:, 0], 0.1 + wall, atol=1e-5)  # on the wall, in the base frame
    blinded = depth_scan(np.full((6, width), -np.inf, np.float32), Pose2D(0, 0, 0), hfov)
    assert np.isneginf(blinded.ranges).all()


def _floor_and_wall(height: int, width: int, hfov: float, camera_m: float, pitch: float,
                    wall_m: float, wall_top_m: float) -> np.ndarray:
    """The depth image (m along the optical axis) of a camera ``camera_m`` above a flat floor,
    pitched down ``pitch``, facing a wall ``wall_m`` ahead (level distance) that rises to
    ``wall_top_m``; beyond its top, nothing in range."""
    f = 0.5 * width / math.tan(0.5 * hfov)
    down = (np.arange(height) + 0.5 - 0.5 * height) / f
    cp, sp = math.cos(pitch), math.sin(pitch)
    fwd, drop = cp - sp * down, sp + cp * down  # per metre of optical depth
    with np.errstate(divide="ignore"):
        to_wall = np.where(fwd > 0, wall_m / fwd, np.inf)
        to_floor = np.where(drop > 0, camera_m / drop, np.inf)
    on_wall = (to_wall < to_floor) & (camera_m - to_wall * drop <= wall_top_m)
    column = np.where(on_wall, to_wall, np.where(np.isfinite(to_floor), to_floor, np.inf))
    return np.repeat(column[:, None], width, axis=1).astype(np.float32)


@pytest.mark.parametrize("pitch", [0.0, math.radians(15.0)])
def test_the_pseudo_scan_drops_the_floor_and_keeps_the_wall(pitch):
    """A camera 0.4 m up sees the floor in its lower rows (a ring 0.5-1 m round the robot if
    it were an obstacle) and a wall 2 m ahead: with its height the pseudo-scan reads the wall
    only; an image of the floor alone gives no return at all."""
    hfov, height, width = math.radians(87.0), 60, 80
    floor_only = _floor_and_wall(height, width, hfov, 0.4, pitch, 100.0, -1.0)
    assert np.isfinite(floor_only).sum() > width  # the floor is in view
    blind = depth_scan(floor_only, Pose2D(0.2, 0.0, 0.0), hfov)  # no height known
    assert np.isfinite(blind.ranges).all() and blind.ranges.max() < 1.5  # the floor ring
    scan = depth_scan(floor_only, Pose2D(0.2, 0.0, 0.0), hfov, height_m=0.4, pitch_rad=pitch)
    assert np.isposinf(scan.ranges).all()
    walled = _floor_and_wall(height, width, hfov, 0.4, pitch, 2.0, 1.0)
    scan = depth_scan(walled, Pose2D(0.2, 0.0, 0.0), hfov, height_m=0.4, pitch_rad=pitch)
    np.testing.assert_allclose(scan.ranges, 2.0 / np.cos(scan.angles()), rtol=1e-5)
    low = _floor_and_wall(height, width, hfov, 0.4, pitch, 2.0, 2 * FLOOR_M)  # a kerb
    kerb = depth_scan(low, Pose2D(0.2, 0.0, 0.0), hfov, height_m=0.4, pitch_rad=pitch)
    np.testing.assert_allclose(kerb.ranges, 2.0 / np.cos(kerb.angles()), rtol=1e-5)


def test_the_simulators_camera_pseudo_scan_lies_on_what_its_lidar_sees():
    """The Jackal's real (ray-cast) depth camera in the indoor world: every return of its
    pseudo-scan within 3 m lies within 0.1 m of a LiDAR return (the walls and furniture both
    see), none on the floor, as the robot drives and turns (farther, a column's nearest pixel
    placed on the column's middle bearing may stray more at an object's edge)."""
    env = NavEnv(sensor="depth", sim={"depth.enabled": True, "lidar.enabled": True,
                                      "lidar.beams": 720})
    try:
        env.reset(seed=3)
        robot, checked = env.scenario.robot, 0
        for step in range(30):
            frame = env.frame
            pseudo = depth_scan(frame.depth, robot.depth_mount, robot.depth_hfov_rad,
                                height_m=robot.depth_height_m,
                                pitch_rad=robot.depth_pitch_rad).points()
            pseudo = pseudo[np.hypot(*pseudo.T) < 3.0]
            lidar = frame.scan.points()
            near = np.linalg.norm(pseudo[:, None] - lidar[None], axis=2).min(axis=1)
            assert (near < 0.1).all(), (step, near.max())
            checked += len(pseudo)
            _, _, done, cut, _ = env.step(np.array([0.3, 0.6], np.float32))
            if done or cut:
                env.reset()
        assert checked > 200  # the camera saw something near to compare
    finally:
        env.close()
