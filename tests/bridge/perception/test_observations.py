"""LiDAR sectors (from the beams' angles, whatever the scan's geometry) and depth images
against hand-computed answers."""

from __future__ import annotations

import math

import numpy as np
import pytest
from pic4rl_base.geometry import Pose2D

from pic4rl_bridge.config import EnvConfig
from pic4rl_bridge.errors import ConfigError
from pic4rl_bridge.readings.frame import ScanData
from pic4rl_bridge.perception.observations import (clipped_action, depth_observation, depth_space,
                                              lidar_sectors, target_polar)


F32_PI = float(np.float32(math.pi))
SIM_INC = float(np.float32(2 * math.pi / 360))  # the sim's 360-beam LiDAR, as published


def scan(ranges, angle_min: float, increment: float, yaw: float = 0.0) -> ScanData:
    """A LaserScan as decoded: float32 ranges and angles."""
    return ScanData(np.asarray(ranges, np.float32), float(np.float32(angle_min)),
                    float(np.float32(increment)), 0.1, 30.0, Pose2D(0.1, 0.0, yaw))


def lidar(sectors: int = 36, clip_m: float = 10.0, fov_deg: float = 360.0):
    return EnvConfig().replace(**{"lidar.sectors": sectors, "lidar.clip_m": clip_m,
                                  "lidar.fov_deg": fov_deg}).lidar


def index_runs(ranges: np.ndarray, beams: int, far: float) -> np.ndarray:
    """The sectors as the scan's beams split in order into equal runs (before issue 27)."""
    r = np.nan_to_num(np.asarray(ranges, np.float64), nan=far, posinf=far, neginf=0.0)
    starts = (np.arange(beams) * r.size) // beams
    return np.clip(np.minimum.reduceat(r, starts), 0.0, far).astype(np.float32)


@pytest.mark.parametrize("beams", [36, 24, 40, 72, 360, 4, 1])
def test_the_sims_scan_gives_the_index_runs_bit_for_bit(beams):
    """The built-in LiDAR (360 beams from -pi, float32 angles) keeps the observation the
    shipped agents were trained on."""
    ranges = np.random.default_rng(beams).uniform(0.05, 12.0, 360).astype(np.float32)
    ranges[::17] = np.inf
    out = lidar_sectors(scan(ranges, -math.pi, 2 * math.pi / 360), lidar(beams))
    assert out.dtype == np.float32
    assert out.tobytes() == index_runs(ranges, beams, 10.0).tobytes()


def test_a_sim_scan_narrower_than_360_over_a_layout_of_its_width():
    ranges = np.random.default_rng(1).uniform(0.05, 12.0, 271).astype(np.float32)
    narrow = scan(ranges, -0.75 * math.pi, math.radians(1.0))  # the sim's 270 deg, 271 beams
    out = lidar_sectors(narrow, lidar(27, fov_deg=270.0))
    assert out.tobytes() == index_runs(ranges, 27, 10.0).tobytes()


def cast(angles: np.ndarray, yaw: float = 0.0) -> np.ndarray:
    """Ranges from the sensor (at the base origin, turned by ``yaw``) along ``angles`` (its
    frame) in a round room of radius 5 m holding three thin posts, one in the middle of a
    10-degree sector each: 1.0 m at 35 deg, 2.0 m at -65 deg, 1.5 m at 175 deg (base frame)."""
    theta = np.asarray(angles, np.float64) + yaw
    ux, uy = np.cos(theta), np.sin(theta)
    out = np.full(theta.shape, 5.0)
    for distance, bearing in ((1.0, 35.0), (2.0, -65.0), (1.5, 175.0)):
        rad = math.radians(bearing)
        cx, cy = distance * math.cos(rad), distance * math.sin(rad)
        along = ux * cx + uy * cy
        miss2 = cx * cx + cy * cy - along * along
        hit = (along > 0) & (miss2 <= 0.02 ** 2)
        out = np.where(hit, np.minimum(out, along - np.sqrt(np.maximum(0.02 ** 2 - miss2, 0))),
                       out)
    return out


def world_scan(angle_min: float, increment: float, n: int, yaw: float = 0.0) -> ScanData:
    angles = float(np.float32(angle_min)) + float(np.float32(increment)) * np.arange(n)
    return scan(cast(angles, yaw), angle_min, increment, yaw)


def test_one_world_through_scans_of_other_geometries_gives_the_same_sectors():
    full = lidar_sectors(world_scan(-math.pi, 2 * math.pi / 360, 360), lidar())
    assert full[21] == pytest.approx(0.98, abs=1e-5) and full[11] == pytest.approx(1.98, abs=1e-5)
    assert full[35] == pytest.approx(1.48, abs=1e-5) and np.count_nonzero(full == 5.0) == 33
    zero_to_two_pi = lidar_sectors(world_scan(0.0, 2 * math.pi / 360, 360), lidar())
    np.testing.assert_allclose(zero_to_two_pi, full, atol=1e-5)
    clockwise = lidar_sectors(world_scan(math.pi, -2 * math.pi / 360, 360), lidar())
    np.testing.assert_allclose(clockwise, full, atol=1e-5)
    hokuyo = lidar_sectors(world_scan(-0.75 * math.pi, 1.5 * math.pi / 1080, 1081), lidar())
    inside = slice(5, 31)  # the sectors within -135 .. 135 deg
    np.testing.assert_allclose(hokuyo[inside], full[inside], atol=1e-5)
    # outside the 270 deg field of view: no return (the post at 175 deg is not seen)
    np.testing.assert_array_equal(hokuyo[np.r_[0:4, 32:36]], 10.0)


def test_the_collision_check_uses_the_same_angles():
    """``ScanData.points`` places each scan's returns on the same obstacles."""
    scans = [world_scan(-math.pi, 2 * math.pi / 360, 360), world_scan(0.0, 2 * math.pi / 360, 360),
             world_scan(-0.75 * math.pi, 1.5 * math.pi / 1080, 1081),
             world_scan(-math.pi, 2 * math.pi / 360, 360, yaw=math.pi)]
    for s in scans:
        points = s.points() - [s.mount.x, s.mount.y]
        nearest = points[np.argmin(np.hypot(*points.T))]
        np.testing.assert_allclose(nearest, [0.98 * math.cos(math.radians(35)),
                                             0.98 * math.sin(math.radians(35))], atol=1e-5)


def test_a_mount_turned_by_pi_turns_the_sectors():
    ranges = np.random.default_rng(2).uniform(0.5, 9.0, 360)
    ahead = lidar_sectors(scan(ranges, -math.pi, 2 * math.pi / 360), lidar())
    behind = lidar_sectors(scan(ranges, -math.pi, 2 * math.pi / 360, yaw=math.pi), lidar())
    np.testing.assert_array_equal(behind, np.roll(ahead, 18))
    # the world seen by a LiDAR mounted backwards reads as the forward one's
    full = lidar_sectors(world_scan(-math.pi, 2 * math.pi / 360, 360), lidar())
    backwards = lidar_sectors(world_scan(-math.pi, 2 * math.pi / 360, 360, yaw=math.pi), lidar())
    np.testing.assert_allclose(backwards, full, atol=1e-5)


def test_a_layout_narrower_than_the_scan_drops_the_beams_outside_it():
    ranges = np.full(360, 8.0)
    ranges[0] = 1.0  # behind the robot: outside a 180 deg layout
    ranges[180 + 45] = 2.0  # 45 deg left: sector 13 of 18 over -90 .. 90 deg
    out = lidar_sectors(scan(ranges, -math.pi, 2 * math.pi / 360), lidar(18, fov_deg=180.0))
    expected = np.full(18, 8.0, np.float32)
    expected[13] = 2.0
    np.testing.assert_array_equal(out, expected)


@pytest.mark.bad_input
@pytest.mark.parametrize("n, angle_min, increment", [
    (7, 0.0, 2 * math.pi / 7),  # 7 beams round the circle for 36 sectors
    (35, -math.pi, 2 * math.pi / 35),
    (20, -0.75 * math.pi, 1.5 * math.pi / 19),  # 270 deg, 14 deg apart
])
def test_a_scan_too_coarse_for_the_sectors_is_refused(n, angle_min, increment):
    with pytest.raises(ConfigError, match=r"^lidar\.sectors: 36 sectors of 10 deg .* need a beam "
                       r"each, but the scan's \d+ beams .* leave sector\(s\) \d"):
        lidar_sectors(scan(np.ones(n), angle_min, increment), lidar())


def test_a_scan_just_fine_enough_is_accepted():
    out = lidar_sectors(scan(np.arange(36.0), -math.pi, 2 * math.pi / 36), lidar(clip_m=40))
    np.testing.assert_array_equal(out, np.arange(36.0))
    narrow = scan(np.ones(28), -0.75 * math.pi, math.radians(10.0))  # 270 deg, 10 deg apart
    assert np.count_nonzero(lidar_sectors(narrow, lidar()) == 1.0) == 28


def test_sector_special_values_and_clipping():
    ranges = np.array([np.nan, np.inf, 12.0, 3.0, -np.inf, 4.0], np.float32)
    out = lidar_sectors(scan(ranges, -math.pi, math.pi / 3), lidar(6))
    np.testing.assert_array_equal(out, [10, 10, 10, 3, 0, 4])
    out = lidar_sectors(scan(ranges, -math.pi, math.pi / 3), lidar(3))
    np.testing.assert_array_equal(out, [10, 3, 0])
    with pytest.raises(ConfigError, match="without ranges"):
        lidar_sectors(scan(np.array([]), 0.0, 0.1), lidar())


def test_depth_block_mean():
    image = np.arange(16, dtype=np.float32).reshape(4, 4) * 0.25  # 0 .. 3.75 m
    out = depth_observation(image, 2, 2, 5.0, "float32")
    assert out.shape == (1, 2, 2) and out.dtype == np.float32
    # top-left block: 0, 0.25, 1.0, 1.25 -> 0.625
    np.testing.assert_allclose(out[0], [[0.625, 1.125], [2.625, 3.125]])


def test_depth_nearest_when_not_an_integer_factor():
    image = np.arange(9, dtype=np.float32).reshape(3, 3)
    out = depth_observation(image, 2, 2, 10.0, "float32")
    np.testing.assert_array_equal(out[0], [[0, 2], [6, 8]])  # centres 0.75 -> 0, 2.25 -> 2
    up = depth_observation(image, 6, 3, 10.0, "float32")
    np.testing.assert_array_equal(up[0, 1], [3, 3, 4, 4, 5, 5])


def test_depth_special_values_clipping_and_uint8():
    image = np.array([[np.nan, np.inf], [-np.inf, 9.0], [1.0, 2.5]], np.float32)
    metres = depth_observation(image, 2, 3, 5.0, "float32")
    np.testing.assert_array_equal(metres[0], [[5, 5], [0, 5], [1, 2.5]])
    codes = depth_observation(image, 2, 3, 5.0, "uint8")
    assert codes.dtype == np.uint8
    np.testing.assert_array_equal(codes[0], [[255, 255], [0, 255], [51, 128]])
    # a far pixel weighs as max_depth in a block mean: (1 + 5) / 2
    far = depth_observation(np.array([[1.0, 40.0]], np.float32), 1, 1, 5.0, "float32")
    assert far[0, 0, 0] == pytest.approx(3.0)


@pytest.mark.parametrize("encoding", ["uint8", "float32"])
def test_depth_space_contains_observations(encoding):
    config = EnvConfig().replace(**{"depth.encoding": encoding, "depth.obs_width": 16,
                                    "depth.obs_height": 12})
    space = depth_space(config.depth)
    assert space.shape == (1, 12, 16)
    rng = np.random.default_rng(0)
    image = rng.uniform(-1.0, 20.0, (48, 64)).astype(np.float32)
    image[0, :5] = [np.inf, -np.inf, np.nan, 0.0, 5.0]
    obs = depth_observation(image, 16, 12, config.depth.clip_m, encoding)
    assert space.contains(obs)
    assert not space.contains(obs[0])


def test_target_polar_and_clipped_action():
    d, angle = target_polar(Pose2D(1.0, 1.0, math.pi / 2), 2.0, 1.0)
    assert d == pytest.approx(1.0) and angle == pytest.approx(-math.pi / 2)
    d, angle = target_polar(Pose2D(0.0, 0.0, 3.0), -1.0, 0.0)
    assert angle == pytest.approx(math.pi - 3.0)
    np.testing.assert_array_equal(clipped_action(np.array([2.0, -0.5]), 2), [1.0, -0.5])
    with pytest.raises(ValueError):
        clipped_action(np.zeros(3), 2)
