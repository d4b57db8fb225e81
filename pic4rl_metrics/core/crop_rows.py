"""A crop lane read from a planar scan: the nearest row on each side fitted with a line, and
the lane's middle between them.

Real fields have no recorded centre line, so the row metrics of a bag without one measure the
robot's offset from the middle of the rows its scan sees (``docs/metrics.md``), and the
classical row follower (``pic4rl_bridge.row_followers``) steers by the same fit. Points are in
the robot's base frame (x ahead, y left, m); pure numpy.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np


@dataclass(frozen=True)
class LaneWindow:
    """Which points make a row: ahead of ``-behind_m`` and short of ``ahead_m``; on each side
    those within ``band_m`` of the nearest one, when that is within ``max_half_width_m`` (a
    nearest point farther out is the next row, seen through a gap)."""

    ahead_m: float = 3.0
    behind_m: float = 0.5
    band_m: float = 0.8
    max_half_width_m: float = 1.8
    min_span_m: float = 1.0  # a side's points spanning less give its distance, no slope


class LaneFit(NamedTuple):
    """The lane's middle line ``y = offset_m + x tan(heading_rad)`` in the base frame, and the
    lane's width (m) between the two rows' lines at the robot."""

    offset_m: float
    heading_rad: float
    width_m: float

    @property
    def deviation_m(self) -> float:
        """The robot's signed distance from the middle line (m, positive left of it)."""
        return -self.offset_m * math.cos(self.heading_rad)


def fit_side(x: np.ndarray, y: np.ndarray, sign: float,
             window: LaneWindow) -> tuple[float, float] | None:
    """The nearest row on one side (``sign`` +1 left, -1 right) as ``(a, b)`` of
    ``y = a + b x``, or ``None`` when no point makes one."""
    ys = y * sign
    inside = (x > -window.behind_m) & (x < window.ahead_m) & (ys > 0.05) & np.isfinite(ys)
    if not inside.any():
        return None
    x, ys = x[inside], ys[inside]
    if ys.min() > window.max_half_width_m:
        return None
    near = ys < ys.min() + window.band_m
    x, ys = x[near], ys[near]
    if np.ptp(x) < window.min_span_m:
        return sign * float(np.mean(ys)), 0.0
    b, a = np.polyfit(x, ys, 1)
    return sign * float(a), sign * float(b)


def fit_lane(x: np.ndarray, y: np.ndarray, width_m: float = math.nan,
             window: LaneWindow = LaneWindow()) -> LaneFit | None:
    """The lane around the robot from points ``x``, ``y`` (m, base frame): between the two
    rows when both are seen; from one row and ``width_m`` (the last width seen) when the
    other is not; ``None`` otherwise."""
    x, y = np.asarray(x, dtype=np.float64).ravel(), np.asarray(y, dtype=np.float64).ravel()
    return _lane(fit_side(x, y, 1.0, window), fit_side(x, y, -1.0, window), width_m)


def _lane(left: tuple[float, float] | None, right: tuple[float, float] | None,
          width_m: float) -> LaneFit | None:
    """The lane between the rows ``left`` and ``right`` (``fit_side``), see ``fit_lane``."""
    if left is not None and right is not None:
        slope = 0.5 * (left[1] + right[1])
        return LaneFit(0.5 * (left[0] + right[0]), math.atan(slope), left[0] - right[0])
    if not math.isfinite(width_m) or (left is None and right is None):
        return None
    (a, b), sign = (left, 1.0) if left is not None else (right, -1.0)  # type: ignore[misc]
    return LaneFit(a - sign * 0.5 * width_m, math.atan(b), width_m)


def lane_sides(x: np.ndarray, y: np.ndarray, window: LaneWindow = LaneWindow()) -> np.ndarray:
    """Per scan (rows of ``x``, ``y``: its points in the base frame, NaN where a beam has no
    return), the rows it sees: ``(a, b)`` of the left and the right one (``fit_side``), NaN
    for a side not seen; (n, 4)."""
    out = np.full((len(x), 4), math.nan)
    for i in range(len(x)):
        xi, yi = np.asarray(x[i], dtype=np.float64), np.asarray(y[i], dtype=np.float64)
        for col, sign in ((0, 1.0), (2, -1.0)):
            side = fit_side(xi, yi, sign, window)
            if side is not None:
                out[i, col:col + 2] = side
    return out


def deviations(sides: np.ndarray) -> np.ndarray:
    """Per scan, from its ``lane_sides``, the robot's signed distance from the lane's middle
    (m); NaN until both rows have been seen once, and where no row is seen."""
    out = np.full(len(sides), math.nan)
    width = math.nan
    for i, (la, lb, ra, rb) in enumerate(sides.tolist()):
        left = None if math.isnan(la) else (la, lb)
        right = None if math.isnan(ra) else (ra, rb)
        fit = _lane(left, right, width)
        if fit is not None:
            width = fit.width_m
            out[i] = fit.deviation_m
    return out


def lane_deviations(x: np.ndarray, y: np.ndarray,
                    window: LaneWindow = LaneWindow()) -> np.ndarray:
    """Per scan (rows of ``x``, ``y``: its points in the base frame, NaN where a beam has no
    return), the robot's signed distance from the lane's middle (m); NaN until both rows have
    been seen once, and where no row is seen."""
    return deviations(lane_sides(x, y, window))
