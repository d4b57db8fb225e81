"""Observation encoders: raw ranges and depth images reduced to what a policy is fed.

PIC4rl-gym reduces the 360 LiDAR ranges to a few sectors by taking each sector's minimum (the
nearest obstacle in that direction survives the reduction), and feeds depth as a small image.
The depth image is channel-first and, by default, ``uint8`` so that SB3 recognizes it as an
image and its ``CnnPolicy`` applies; ``float32`` keeps metres for custom networks.
"""

from __future__ import annotations

import math

import gymnasium as gym
import numpy as np
from pic4rl_sim.engine.geometry import Pose2D, wrap_angle

from ..config import DepthObsConfig


def lidar_sectors(ranges: np.ndarray, beams: int, max_range_m: float) -> np.ndarray:
    """``beams`` sector minima (m, float32, in [0, max_range_m]) of ``ranges``.

    NaN and ``+inf`` (no return) read as ``max_range_m``, ``-inf`` (too close) as 0. The
    ranges are split into contiguous sectors whose sizes differ by at most one; with more
    sectors than ranges, a sector holds the range at its start.
    """
    r = np.asarray(ranges, dtype=np.float64).ravel()
    if r.size == 0 or beams < 1:
        raise ValueError(f"lidar_sectors: needs ranges and beams >= 1, got {r.size} ranges "
                         f"and beams={beams}")
    r = np.nan_to_num(r, nan=max_range_m, posinf=max_range_m, neginf=0.0)
    starts = (np.arange(beams) * r.size) // beams
    return np.clip(np.minimum.reduceat(r, starts), 0.0, max_range_m).astype(np.float32)


def _resize(image: np.ndarray, width: int, height: int) -> np.ndarray:
    """``image`` (H × W) at ``height`` × ``width``: block means when both factors are
    integers, else the nearest pixel to each output pixel's centre."""
    h, w = image.shape
    if h % height == 0 and w % width == 0:
        return image.reshape(height, h // height, width, w // width).mean(axis=(1, 3))
    rows = ((np.arange(height) + 0.5) * h / height).astype(np.intp)
    cols = ((np.arange(width) + 0.5) * w / width).astype(np.intp)
    return image[np.ix_(rows, cols)]


def depth_observation(image: np.ndarray, width: int, height: int, max_depth_m: float,
                      encoding: str) -> np.ndarray:
    """A depth image (H × W, m) as a (1, height, width) observation.

    NaN and ``+inf`` read as ``max_depth_m``, ``-inf`` as 0; depths are clipped to
    [0, max_depth_m] before resizing (so a far pixel weighs as ``max_depth_m`` in a block
    mean). ``uint8``: ``round(d / max_depth_m * 255)``; ``float32``: metres.
    """
    d = np.asarray(image, dtype=np.float64)
    if d.ndim != 2:
        raise ValueError(f"depth_observation: expected an H x W image, got shape {d.shape}")
    d = np.nan_to_num(d, nan=max_depth_m, posinf=max_depth_m, neginf=0.0)
    d = _resize(np.clip(d, 0.0, max_depth_m), width, height)[None]
    if encoding == "uint8":
        return np.round(d / max_depth_m * 255.0).astype(np.uint8)
    if encoding == "float32":
        return d.astype(np.float32)
    raise ValueError(f"depth.encoding: {encoding!r} is invalid; expected uint8 or float32")


def depth_space(depth: DepthObsConfig) -> gym.spaces.Box:
    """The space of ``depth_observation`` under ``depth`` (the config's ``depth`` section)."""
    shape = (1, depth.height, depth.width)
    if depth.encoding == "uint8":
        return gym.spaces.Box(0, 255, shape, np.uint8)
    return gym.spaces.Box(0.0, depth.max_depth_m, shape, np.float32)


#: Observed target distances are clipped here (m): a finite bound for the observation space.
MAX_TARGET_DISTANCE_M = 1000.0
#: With ``normalize_observations``, goal distances are divided by this (m) and clipped to 1:
#: a policy's inputs then share one scale, which speeds up learning (RL-Zoo normalises too).
NORMALIZED_GOAL_DISTANCE_M = 10.0


def target_polar(pose: Pose2D, x: float, y: float) -> tuple[float, float]:
    """Distance (m) and bearing (rad, in [-pi, pi), left positive) of the point (x, y) seen
    from ``pose``."""
    dx, dy = x - pose.x, y - pose.y
    return math.hypot(dx, dy), wrap_angle(math.atan2(dy, dx) - pose.yaw)


def clipped_action(action: np.ndarray, size: int) -> np.ndarray:
    """``action`` as ``size`` float32 values clipped to [-1, 1]."""
    a = np.asarray(action, dtype=np.float32).ravel()
    if a.size != size:
        raise ValueError(f"expected an action of {size} values, got {a.size}")
    return np.clip(a, -1.0, 1.0)
