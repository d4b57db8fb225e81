"""LiDAR sectors and depth images against hand-computed answers."""

from __future__ import annotations

import math

import numpy as np
import pytest
from pic4rl_sim.engine.geometry import Pose2D

from pic4rl_bridge.config import EnvConfig
from pic4rl_bridge.tasks.observations import (clipped_action, depth_observation, depth_space,
                                              lidar_sectors, target_polar)


def test_sector_minima_of_a_known_array():
    out = lidar_sectors(np.arange(12, dtype=np.float32)[::-1], 4, 20.0)
    assert out.dtype == np.float32
    np.testing.assert_array_equal(out, [9, 6, 3, 0])
    # 10 ranges in 4 sectors: sizes 2, 3, 2, 3
    np.testing.assert_array_equal(lidar_sectors(np.arange(10.0)[::-1], 4, 20.0), [8, 5, 3, 0])


@pytest.mark.parametrize("n, beams", [(360, 36), (360, 7), (10, 4), (97, 10), (5, 5)])
def test_sectors_are_contiguous_and_nearly_equal(n, beams):
    owner = []
    for i in range(n):  # which sector sees a single near return at beam i
        ranges = np.full(n, 5.0)
        ranges[i] = 1.0
        out = lidar_sectors(ranges, beams, 10.0)
        assert np.count_nonzero(out == 1.0) == 1
        owner.append(int(np.argmin(out)))
    assert owner == sorted(owner)  # contiguous, in order
    sizes = np.bincount(owner, minlength=beams)
    assert sizes.sum() == n and sizes.max() - sizes.min() <= 1


def test_sector_special_values_and_clipping():
    ranges = np.array([np.nan, np.inf, 12.0, 3.0, -np.inf, 4.0], np.float32)
    np.testing.assert_array_equal(lidar_sectors(ranges, 6, 10.0), [10, 10, 10, 3, 0, 4])
    np.testing.assert_array_equal(lidar_sectors(ranges, 3, 10.0), [10, 3, 0])
    with pytest.raises(ValueError):
        lidar_sectors(np.array([]), 4, 10.0)


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
    config = EnvConfig().replace(**{"depth.encoding": encoding, "depth.width": 16,
                                    "depth.height": 12})
    space = depth_space(config.depth)
    assert space.shape == (1, 12, 16)
    rng = np.random.default_rng(0)
    image = rng.uniform(-1.0, 20.0, (48, 64)).astype(np.float32)
    image[0, :5] = [np.inf, -np.inf, np.nan, 0.0, 5.0]
    obs = depth_observation(image, 16, 12, config.depth.max_depth_m, encoding)
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
