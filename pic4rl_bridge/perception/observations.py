"""Observation encoders: raw ranges and depth images reduced to what a policy is fed.

PIC4rl-gym reduces the 360 LiDAR ranges to a few sectors by taking each sector's minimum (the
nearest obstacle in that direction survives the reduction), and feeds depth as a small image.
A beam's sector follows from its direction in the robot's base frame (``ScanData``'s angles
and mount), not from its index, so that a scan published from 0 or over 270° means the same
to an agent as the one it was trained on; the sectors' layout is the agent's config.
The depth image is channel-first and, by default, ``uint8`` so that SB3 recognizes it as an
image and its ``CnnPolicy`` applies; ``float32`` keeps metres for custom networks.
"""

from __future__ import annotations

import math
from typing import Any, NamedTuple

import gymnasium as gym
import numpy as np

from pic4rl_base.geometry import Pose2D, wrap_angle

from ..config import DepthObsConfig, LidarObsConfig
from ..errors import ConfigError
from ..readings.frame import ScanData

#: A beam this close (rad) below a sector's start counts in that sector: a LaserScan's float32
#: fields put a beam meant to lie on a boundary up to ~6e-7 rad off it (the sim's included).
BOUNDARY_TOLERANCE_RAD = 1e-5
_FULL_CIRCLE = 2.0 * math.pi


def sector_index(base_angles: np.ndarray, beams: int, fov_deg: float) -> np.ndarray:
    """The sector (0 .. ``beams`` - 1) each beam direction (rad, base frame) falls in, -1
    outside the layout: ``beams`` sectors of equal width over ``fov_deg`` centred on the
    robot's forward axis, sector 0 starting at -``fov_deg`` / 2, counter-clockwise. A sector
    holds the beams from its start (``BOUNDARY_TOLERANCE_RAD`` below it included) up to the
    next one's; a layout narrower than 360° also keeps the beams on its far end."""
    fov = math.radians(fov_deg)
    rel = np.mod(np.asarray(base_angles, np.float64) + 0.5 * fov + BOUNDARY_TOLERANCE_RAD,
                 _FULL_CIRCLE)
    index = np.floor(rel * (beams / fov)).astype(np.intp)
    if fov_deg >= 360.0:
        return np.minimum(index, beams - 1)  # rel < 2 pi: only rounding reaches ``beams``
    index[(index >= beams) & (rel <= fov + 2.0 * BOUNDARY_TOLERANCE_RAD)] = beams - 1
    index[index >= beams] = -1
    return index


class _Sectors(NamedTuple):
    """How a scan's ranges reduce to sectors: ``order`` sorts the kept beams by sector (None:
    the scan's own order, all kept), ``starts`` is where each filled sector begins in it,
    ``filled`` the filled sectors (None: all)."""

    order: np.ndarray | None
    starts: np.ndarray
    filled: np.ndarray | None


_LAYOUTS: dict[tuple[Any, ...], _Sectors] = {}


def _sectors(scan: ScanData, beams: int, fov_deg: float) -> _Sectors:
    """``scan``'s sectors, remembered by its geometry (a sensor keeps one)."""
    key = (len(scan.ranges), scan.angle_min_rad, scan.angle_increment_rad, scan.mount.yaw,
           beams, fov_deg)
    found = _LAYOUTS.get(key)
    if found is None:
        if len(_LAYOUTS) >= 64:
            _LAYOUTS.clear()
        found = _LAYOUTS[key] = _layout(scan, beams, fov_deg)
    return found


def _layout(scan: ScanData, beams: int, fov_deg: float) -> _Sectors:
    n, step = len(scan.ranges), abs(scan.angle_increment_rad)
    if n == 0:
        raise ConfigError("scan: a LaserScan without ranges; lidar.sectors needs a beam each")
    index = sector_index(scan.base_angles(), beams, fov_deg)
    counts = np.bincount(index[index >= 0], minlength=beams)
    blind = [k for k in np.flatnonzero(counts == 0) if _in_view(scan, k, beams, fov_deg)]
    if blind:
        listed = ", ".join(str(k) for k in blind[:8]) + (", ..." if len(blind) > 8 else "")
        raise ConfigError(
            f"lidar.sectors: {beams} sectors of {fov_deg / beams:.3g} deg (lidar.fov_deg "
            f"{fov_deg:g}) need a beam each, but the scan's {n} beams "
            f"{math.degrees(step):.3g} deg apart leave sector(s) {listed} without one "
            "inside its field of view; use fewer sectors or a finer scan")
    kept = np.flatnonzero(index >= 0)
    order = kept[np.argsort(index[kept], kind="stable")]
    ordered = index[order]
    starts = np.flatnonzero(np.diff(ordered, prepend=-1))
    filled = ordered[starts]
    in_place = len(order) == n and bool(np.all(np.diff(index) >= 0))
    return _Sectors(None if in_place else order, starts,
                    None if len(filled) == beams else filled)


def _in_view(scan: ScanData, sector: int, beams: int, fov_deg: float) -> bool:
    """Whether ``sector`` overlaps the arc the scan's beams span (all of it for a scan that
    goes round)."""
    n, step = len(scan.ranges), abs(scan.angle_increment_rad)
    if n * step >= _FULL_CIRCLE - BOUNDARY_TOLERANCE_RAD:
        return True
    first, last = scan.base_angles()[[0, -1]]
    span = (n - 1) * step
    width = math.radians(fov_deg) / beams
    start = -0.5 * math.radians(fov_deg) + sector * width
    u = (start - min(first, last)) % _FULL_CIRCLE  # the sector's start, from the arc's
    return u <= span or u + width - _FULL_CIRCLE > BOUNDARY_TOLERANCE_RAD


def lidar_sectors(scan: ScanData, lidar: LidarObsConfig) -> np.ndarray:
    """``lidar.sectors`` sector minima (m, float32, in [0, lidar.clip_m]) of ``scan``, by
    each beam's direction in the base frame over the layout of ``sector_index``.

    NaN and ``+inf`` (no return) read as ``clip_m``, ``-inf`` (too close) as 0; a sector
    outside the scan's field of view reads as no return. A scan that leaves a sector inside its
    field of view without a beam is refused (``ConfigError``). For the built-in LiDARs (beams
    from -pi, evenly round the circle) the sectors are the scan's beams split in order into
    equal runs.
    """
    beams, far = lidar.sectors, lidar.clip_m
    layout = _sectors(scan, beams, lidar.fov_deg)
    r = np.nan_to_num(np.asarray(scan.ranges, dtype=np.float64), nan=far, posinf=far,
                      neginf=0.0)
    if layout.order is not None:
        r = r[layout.order]
    minima = np.minimum.reduceat(r, layout.starts)
    if layout.filled is not None:
        out = np.full(beams, far)
        out[layout.filled] = minima
        minima = out
    return np.clip(minima, 0.0, far).astype(np.float32)


def _resize(image: np.ndarray, width: int, height: int) -> np.ndarray:
    """``image`` (H × W) at ``height`` × ``width``: block means when both factors are
    integers, else the nearest pixel to each output pixel's centre."""
    h, w = image.shape
    if h % height == 0 and w % width == 0:
        return image.reshape(height, h // height, width, w // width).mean(axis=(1, 3))
    rows = ((np.arange(height) + 0.5) * h / height).astype(np.intp)
    cols = ((np.arange(width) + 0.5) * w / width).astype(np.intp)
    return image[np.ix_(rows, cols)]


def depth_observation(image: np.ndarray, width: int, height: int, clip_m: float,
                      encoding: str) -> np.ndarray:
    """A depth image (H × W, m) as a (1, height, width) observation.

    NaN and ``+inf`` read as ``clip_m``, ``-inf`` as 0; depths are clipped to [0, clip_m]
    before resizing (so a far pixel weighs as ``clip_m`` in a block mean). ``uint8``:
    ``round(d / clip_m * 255)``; ``float32``: metres.
    """
    d = np.asarray(image, dtype=np.float64)
    if d.ndim != 2:
        raise ValueError(f"depth_observation: expected an H x W image, got shape {d.shape}")
    d = np.nan_to_num(d, nan=clip_m, posinf=clip_m, neginf=0.0)
    d = _resize(np.clip(d, 0.0, clip_m), width, height)[None]
    if encoding == "uint8":
        return np.round(d / clip_m * 255.0).astype(np.uint8)
    if encoding == "float32":
        return d.astype(np.float32)
    raise ValueError(f"depth.encoding: {encoding!r} is invalid; expected uint8 or float32")


def depth_space(depth: DepthObsConfig) -> gym.spaces.Box:
    """The space of ``depth_observation`` under ``depth`` (the config's ``depth`` section)."""
    shape = (1, depth.obs_height, depth.obs_width)
    if depth.encoding == "uint8":
        return gym.spaces.Box(0, 255, shape, np.uint8)
    return gym.spaces.Box(0.0, depth.clip_m, shape, np.float32)


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
