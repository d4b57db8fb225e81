"""Planar motion: the body-frame velocity and the polylines every part of the sim shares (the
one pose type ``Pose2D``, the robot's ``Footprint``, angle wrapping and a yaw's quaternion are
``pic4rl_base.geometry``'s, shared with the bridge and the metrics)."""

from __future__ import annotations

from typing import NamedTuple

import numpy as np


class Twist2D(NamedTuple):
    """A planar velocity in the robot's body frame: forward and left (m/s), yaw rate (rad/s)."""

    vx: float = 0.0
    vy: float = 0.0
    wz: float = 0.0


# -- polylines (a row's centre line, a global plan) ------------------------------------------

def polyline_length(polyline: np.ndarray) -> float:
    """Length (m) of a polyline (n × 2)."""
    seg = np.diff(np.asarray(polyline, dtype=np.float64), axis=0)
    return float(np.hypot(seg[:, 0], seg[:, 1]).sum())


def point_along(polyline: np.ndarray, s: float) -> np.ndarray:
    """The point (x, y) of ``polyline`` (n × 2, m) at arc length ``s`` (m) from its first point,
    clipped to its ends."""
    line = np.asarray(polyline, dtype=np.float64)
    if len(line) == 1:
        return line[0].copy()
    seg = np.diff(line, axis=0)
    ends = np.concatenate(([0.0], np.cumsum(np.hypot(seg[:, 0], seg[:, 1]))))
    s = min(max(s, 0.0), float(ends[-1]))
    i = min(int(np.searchsorted(ends, s, side="right")) - 1, len(seg) - 1)
    length = ends[i + 1] - ends[i]
    t = (s - ends[i]) / length if length > 0 else 0.0
    return line[i] + t * seg[i]
