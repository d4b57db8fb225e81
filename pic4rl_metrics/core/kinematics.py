"""Math on time series: time-weighted means, derivatives over real time steps, geometry.

Pure numpy, no I/O. Times are int nanoseconds in, seconds out. Derivatives divide by the real
time difference of each pair of samples (never by a nominal rate); callers pass strictly
increasing stamps (``reader`` sorts and de-duplicates them).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from pic4rl_base.geometry import wrap_angle

from .series import PoseSeries

NS = 1e-9


def seconds(t_ns: np.ndarray, t0_ns: int | None = None) -> np.ndarray:
    """Seconds since ``t0_ns`` (default: the first stamp), as float64."""
    t_ns = np.asarray(t_ns, dtype=np.int64)
    if t_ns.size == 0:
        return np.zeros(0)
    origin = int(t_ns[0]) if t0_ns is None else int(t0_ns)
    return (t_ns - origin).astype(np.float64) * NS


def time_mean(t_s: np.ndarray, values: np.ndarray) -> float:
    """Time-weighted mean of point samples (trapezoid rule); NaN samples are left out.

    A single sample is its own mean; no sample gives NaN.
    """
    t_s, values = _finite_pairs(t_s, values)
    if values.size == 0:
        return float("nan")
    if values.size == 1 or t_s[-1] <= t_s[0]:
        return float(np.mean(values))
    return float(np.trapezoid(values, t_s) / (t_s[-1] - t_s[0]))


def time_std(t_s: np.ndarray, values: np.ndarray) -> float:
    """Time-weighted standard deviation of point samples (trapezoid rule)."""
    t_s, values = _finite_pairs(t_s, values)
    if values.size == 0:
        return float("nan")
    mean = time_mean(t_s, values)
    return float(np.sqrt(max(time_mean(t_s, (values - mean) ** 2), 0.0)))


def interval_mean(dt_s: np.ndarray, values: np.ndarray) -> float:
    """Mean of values that each hold over one interval of length ``dt_s`` (weights = dt)."""
    dt_s = np.asarray(dt_s, dtype=float)
    values = np.asarray(values, dtype=float)
    keep = np.isfinite(values)
    if not keep.any():
        return float("nan")
    total = dt_s[keep].sum()
    if total <= 0:
        return float(np.mean(values[keep]))
    return float(np.sum(values[keep] * dt_s[keep]) / total)


def _finite_pairs(t_s: np.ndarray, values: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    t_s = np.asarray(t_s, dtype=float)
    values = np.asarray(values, dtype=float)
    keep = np.isfinite(values)
    return t_s[keep], values[keep]


class Derivative(NamedTuple):
    """Finite difference between consecutive samples, placed at interval midpoints."""

    t_ns: np.ndarray  # midpoints (ns)
    dt_s: np.ndarray  # interval lengths (s)
    value: np.ndarray  # (n-1,) or (n-1, k)


def differentiate(t_ns: np.ndarray, values: np.ndarray) -> Derivative:
    """``(v[i+1] - v[i]) / (t[i+1] - t[i])`` at the midpoint of each interval.

    ``values`` may be (n,) or (n, k). Stamps must be strictly increasing.
    """
    t_ns = np.asarray(t_ns, dtype=np.int64)
    values = np.asarray(values, dtype=float)
    if t_ns.size < 2:
        shape = (0,) + values.shape[1:]
        return Derivative(np.zeros(0, np.int64), np.zeros(0), np.zeros(shape))
    dt_ns = np.diff(t_ns)
    dt_s = dt_ns.astype(float) * NS
    delta = np.diff(values, axis=0)
    scale = dt_s if values.ndim == 1 else dt_s[:, None]
    return Derivative(t_ns[:-1] + dt_ns // 2, dt_s, delta / scale)


class VelocitySeries(NamedTuple):
    """Body-frame velocity (m/s, rad/s) of the robot over time."""

    t_ns: np.ndarray
    vx: np.ndarray
    vy: np.ndarray
    wz: np.ndarray

    @property
    def speed(self) -> np.ndarray:
        """Linear speed |(vx, vy)| (m/s)."""
        return np.hypot(self.vx, self.vy)


def velocity_series(pose: PoseSeries) -> VelocitySeries:
    """The source's own twist when it has one, else differences of consecutive poses.

    Pose differences give the world-frame velocity at each interval midpoint, rotated into
    the body frame by the mean heading of the interval; yaw rate is the unwrapped yaw
    difference over the real time step.
    """
    if pose.vx is not None and pose.wz is not None:
        vy = pose.vy if pose.vy is not None else np.zeros_like(pose.vx)
        return VelocitySeries(pose.t_ns, pose.vx, vy, pose.wz)
    d = differentiate(pose.t_ns, np.column_stack([pose.x, pose.y, np.unwrap(pose.yaw)]))
    if d.t_ns.size == 0:
        empty = np.zeros(0)
        return VelocitySeries(d.t_ns, empty, empty, empty)
    yaw_mid = np.unwrap(pose.yaw)[:-1] + 0.5 * np.diff(np.unwrap(pose.yaw))
    cos, sin = np.cos(yaw_mid), np.sin(yaw_mid)
    vx = cos * d.value[:, 0] + sin * d.value[:, 1]
    vy = -sin * d.value[:, 0] + cos * d.value[:, 1]
    return VelocitySeries(d.t_ns, vx, vy, d.value[:, 2])


def path_length(x: np.ndarray, y: np.ndarray) -> float:
    """Sum of Euclidean distances between consecutive positions (m)."""
    if len(x) < 2:
        return 0.0
    return float(np.sum(np.hypot(np.diff(x), np.diff(y))))


def resample_by_distance(x: np.ndarray, y: np.ndarray, min_step_m: float) -> np.ndarray:
    """Indices of positions kept so that consecutive kept points are >= ``min_step_m`` apart.

    Removes the jitter of a standing robot before turning angles are measured.
    """
    if len(x) == 0:
        return np.zeros(0, dtype=int)
    keep = [0]
    lx, ly = x[0], y[0]
    for i in range(1, len(x)):
        if np.hypot(x[i] - lx, y[i] - ly) >= min_step_m:
            keep.append(i)
            lx, ly = x[i], y[i]
    return np.asarray(keep, dtype=int)


class PathTurning(NamedTuple):
    """Turning of the path's direction at each interior vertex of a resampled path."""

    turn_rad: np.ndarray  # |change of direction| at each vertex (rad)
    step_m: np.ndarray  # mean length of the two segments around each vertex (m)


def path_turning(x: np.ndarray, y: np.ndarray, min_step_m: float = 0.01) -> PathTurning:
    """Direction changes of the path after resampling at ``min_step_m``."""
    idx = resample_by_distance(np.asarray(x, float), np.asarray(y, float), min_step_m)
    px, py = np.asarray(x, float)[idx], np.asarray(y, float)[idx]
    dx, dy = np.diff(px), np.diff(py)
    if dx.size < 2:
        return PathTurning(np.zeros(0), np.zeros(0))
    heading = np.arctan2(dy, dx)
    seg = np.hypot(dx, dy)
    return PathTurning(np.abs(wrap_angle(np.diff(heading))), 0.5 * (seg[:-1] + seg[1:]))


def bearing_in_body(
    x: np.ndarray, y: np.ndarray, yaw: np.ndarray, tx: np.ndarray, ty: np.ndarray
) -> np.ndarray:
    """Bearing (rad, in [-pi, pi), left positive) of targets (tx, ty) seen from each pose."""
    return wrap_angle(np.arctan2(np.asarray(ty) - y, np.asarray(tx) - x) - yaw)
