"""Synthetic robot motion and worlds whose metrics are known by hand, for ``synthetic``'s bags.

A circle has curvature ``1/r``, a constant-jerk ramp known accelerations, a wall at 2 m a
2 m clearance: tests check metrics against these analytic answers, and the benchmark builds
bags of a chosen size from them.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from pic4rl_base.geometry import wrap_angle


@dataclass(frozen=True)
class Track:
    """Robot motion sampled at ``t_s`` (s from episode start): pose (m, rad) and body twist
    (``vx``, ``vy`` in m/s, ``wz`` in rad/s)."""

    t_s: np.ndarray
    x: np.ndarray
    y: np.ndarray
    yaw: np.ndarray
    vx: np.ndarray
    vy: np.ndarray
    wz: np.ndarray

    def __post_init__(self) -> None:
        for name in ("t_s", "x", "y", "yaw", "vx", "vy", "wz"):
            object.__setattr__(self, name, np.asarray(getattr(self, name), dtype=np.float64))
        n = len(self.t_s)
        lengths = {name: len(getattr(self, name)) for name in ("x", "y", "yaw", "vx", "vy", "wz")}
        if n == 0 or any(length != n for length in lengths.values()):
            msg = f"track: every array needs len(t_s)={n} > 0 samples, got {lengths!r}"
            raise ValueError(msg)
        if np.any(np.diff(self.t_s) <= 0):
            msg = "track: t_s must be strictly increasing"
            raise ValueError(msg)

    def __len__(self) -> int:
        return len(self.t_s)

    def truncated(self, n: int) -> Track:
        """The first ``n`` samples (an episode that ended early)."""
        return Track(*(getattr(self, k)[:n] for k in ("t_s", "x", "y", "yaw", "vx", "vy", "wz")))


def _times(duration_s: float, dt_s: float) -> np.ndarray:
    """Sample times ``0, dt, 2 dt, ...`` up to ``duration_s`` inclusive (within rounding)."""
    if not (dt_s > 0 and duration_s >= 0):
        msg = f"need dt_s > 0 and duration_s >= 0, got dt_s={dt_s!r}, duration_s={duration_s!r}"
        raise ValueError(msg)
    return np.arange(math.floor(duration_s / dt_s + 1e-9) + 1) * dt_s


def straight_line(
    speed_mps: float,
    duration_s: float,
    dt_s: float = 0.1,
    *,
    start: tuple[float, float, float] = (0.0, 0.0, 0.0),
) -> Track:
    """Constant speed along the start heading: path length ``speed * duration``, no turning."""
    t = _times(duration_s, dt_s)
    x0, y0, yaw0 = start
    ones = np.ones_like(t)
    return Track(
        t, x0 + speed_mps * t * math.cos(yaw0), y0 + speed_mps * t * math.sin(yaw0),
        yaw0 * ones, speed_mps * ones, 0 * ones, 0 * ones,
    )  # fmt: skip


def circle(
    radius_m: float,
    speed_mps: float,
    duration_s: float,
    dt_s: float = 0.1,
    *,
    center: tuple[float, float] = (0.0, 0.0),
) -> Track:
    """Counter-clockwise circle starting at its lowest point heading +x (yaw 0).

    Positions lie exactly on the circle, yaw is the tangent, ``wz = speed / radius``.
    """
    if radius_m <= 0:
        msg = f"circle: radius_m={radius_m!r} must be positive"
        raise ValueError(msg)
    t = _times(duration_s, dt_s)
    heading = speed_mps / radius_m * t
    ones = np.ones_like(t)
    return Track(
        t, center[0] + radius_m * np.sin(heading), center[1] - radius_m * np.cos(heading),
        wrap_angle(heading), speed_mps * ones, 0 * ones, speed_mps / radius_m * ones,
    )  # fmt: skip


def speed_ramp(jerk_mps3: float, duration_s: float, dt_s: float = 0.1) -> Track:
    """Straight along +x from rest with constant jerk: ``a = j t``, ``v = j t²/2``,
    ``x = j t³/6``."""
    t = _times(duration_s, dt_s)
    zeros = np.zeros_like(t)
    return Track(t, jerk_mps3 * t**3 / 6, zeros, zeros, 0.5 * jerk_mps3 * t**2, zeros, zeros)


def turn_in_place(rate_radps: float, duration_s: float, dt_s: float = 0.1) -> Track:
    """At the origin, turning at a constant ``rate_radps`` from yaw 0: no path, heading
    ``rate * t`` (an explorer's first look round)."""
    t = _times(duration_s, dt_s)
    zeros = np.zeros_like(t)
    return Track(t, zeros, zeros, wrap_angle(rate_radps * t), zeros, zeros, zeros + rate_radps)


def from_waypoints(
    points: Sequence[tuple[float, float]],
    speed_mps: float,
    dt_s: float = 0.1,
    *,
    yaw_rate_radps: float | None = None,
) -> Track:
    """Piecewise-linear path through ``points`` at constant speed, yaw along each segment.

    With ``yaw_rate_radps`` the robot stops at each corner and turns in place at that rate
    (as a differential drive does); without it the heading jumps at corners and ``wz`` is 0.
    The last sample is the last point, even when the duration is not a multiple of ``dt_s``.
    """
    pts = np.asarray(points, dtype=np.float64)
    if pts.ndim != 2 or pts.shape[1] != 2 or len(pts) < 2 or speed_mps <= 0:
        msg = f"from_waypoints: need >= 2 points (x, y) and speed_mps > 0, got {points!r}"
        raise ValueError(msg)
    seg = np.diff(pts, axis=0)
    keep = np.hypot(seg[:, 0], seg[:, 1]) > 0
    starts, seg = pts[:-1][keep], seg[keep]
    if not len(seg):
        msg = f"from_waypoints: the points {points!r} never move"
        raise ValueError(msg)
    headings = np.arctan2(seg[:, 1], seg[:, 0])
    # Phases: (start time, duration, x0, y0, yaw0, vx, wz), each a move or a turn in place.
    phases: list[tuple[float, ...]] = []
    clock = 0.0
    for i, (p, d, heading) in enumerate(zip(starts, seg, headings)):
        if i > 0 and yaw_rate_radps:
            turn = float(wrap_angle(heading - headings[i - 1]))
            rate = math.copysign(abs(yaw_rate_radps), turn)
            phases.append((clock, abs(turn) / abs(yaw_rate_radps), *p, headings[i - 1], 0, rate))
            clock += phases[-1][1]
        phases.append((clock, float(np.hypot(*d)) / speed_mps, *p, heading, speed_mps, 0.0))
        clock += phases[-1][1]
    t = _times(clock, dt_s)
    if clock - t[-1] > 1e-9:
        t = np.append(t, clock)
    table = np.asarray(phases)
    idx = np.clip(np.searchsorted(table[:, 0], t, side="right") - 1, 0, len(table) - 1)
    t0, _, x0, y0, yaw0, vx, wz = table[idx].T
    tau = t - t0
    yaw = yaw0 + wz * tau
    return Track(
        t, x0 + vx * tau * np.cos(yaw0), y0 + vx * tau * np.sin(yaw0), wrap_angle(yaw),
        vx, np.zeros_like(t), wz,
    )  # fmt: skip


@dataclass(frozen=True)
class Obstacles:
    """A 2D world for ray casting: cylinders ``(cx, cy, r)`` and walls ``(x0, y0, x1, y1)`` (m)."""

    circles: tuple[tuple[float, float, float], ...] = ()
    segments: tuple[tuple[float, float, float, float], ...] = ()


def square_room(side_m: float) -> Obstacles:
    """Four walls of a square room centred on the origin: free floor ``side_m²``."""
    h = 0.5 * side_m
    return Obstacles(segments=((-h, -h, h, -h), (h, -h, h, h), (h, h, -h, h), (-h, h, -h, -h)))


def corridor(x0_m: float, x1_m: float, width_m: float) -> Obstacles:
    """Two parallel walls from ``x0_m`` to ``x1_m`` at ``y = ±width_m / 2``, open at both ends."""
    h = 0.5 * width_m
    return Obstacles(segments=((x0_m, -h, x1_m, -h), (x0_m, h, x1_m, h)))


def front_sector(ranges: np.ndarray, fov_rad: float) -> np.ndarray:
    """A full-circle scan (``cast_scan``'s default bearings) seen through a sensor of field of
    view ``fov_rad`` centred ahead: the beams outside it NaN (no reading)."""
    n = len(ranges)
    bearing = np.linspace(-math.pi, math.pi - 2 * math.pi / n, n)
    return np.where(np.abs(bearing) <= 0.5 * fov_rad + 1e-9, ranges, np.nan).astype(np.float32)


def cast_scan(
    x: float,
    y: float,
    yaw: float,
    obstacles: Obstacles,
    *,
    n_beams: int = 360,
    angle_min: float = -math.pi,
    angle_max: float | None = None,
    range_min: float = 0.05,
    range_max: float = 10.0,
) -> np.ndarray:
    """Exact ranges (m, float32) of a 2D LiDAR at ``(x, y, yaw)``: ``n_beams`` bearings evenly
    from ``angle_min`` to ``angle_max`` inclusive, by default the full circle in steps of
    ``2 pi / n_beams`` (as ``write_episode_bag`` records them).

    As real drivers do (REP 117): ``+inf`` where nothing lies within ``range_max``, ``-inf``
    where the nearest hit is closer than ``range_min``.
    """
    if angle_max is None:
        angle_max = math.pi - 2 * math.pi / n_beams
    bearing = yaw + np.linspace(angle_min, angle_max, n_beams)
    dx, dy = np.cos(bearing)[:, None], np.sin(bearing)[:, None]
    best = np.full(n_beams, np.inf)
    if obstacles.circles:
        c = np.asarray(obstacles.circles, dtype=np.float64)
        ox, oy = c[:, 0] - x, c[:, 1] - y
        b = dx * ox + dy * oy  # distance along the ray to the point nearest the centre
        disc = b**2 - (ox**2 + oy**2 - c[:, 2] ** 2)
        root = np.sqrt(np.where(disc >= 0, disc, np.nan))
        near, far = b - root, b + root
        hit = np.where(near >= 0, near, np.where(far >= 0, far, np.inf))  # NaN: a miss
        best = np.minimum(best, hit.min(axis=1))
    if obstacles.segments:
        s = np.asarray(obstacles.segments, dtype=np.float64)
        ax, ay = s[:, 0] - x, s[:, 1] - y
        ex, ey = s[:, 2] - s[:, 0], s[:, 3] - s[:, 1]
        denom = dx * ey - dy * ex
        with np.errstate(divide="ignore", invalid="ignore"):
            t = (ax * ey - ay * ex) / denom  # along the ray
            u = (ax * dy - ay * dx) / denom  # along the segment, 0..1
        ok = (denom != 0) & (t >= 0) & (u >= 0) & (u <= 1)
        best = np.minimum(best, np.where(ok, t, np.inf).min(axis=1))
    ranges = np.where(best > range_max, np.inf, best)
    return np.where(ranges < range_min, -np.inf, ranges).astype(np.float32)
