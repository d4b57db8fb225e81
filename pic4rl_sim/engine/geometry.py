"""Planar poses and footprints: the few shapes every part of the sim shares."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from ..errors import require


class Pose2D(NamedTuple):
    """A planar pose: position (m) and heading (rad, counter-clockwise from +x)."""

    x: float
    y: float
    yaw: float = 0.0


class Twist2D(NamedTuple):
    """A planar velocity in the robot's body frame: forward and left (m/s), yaw rate (rad/s)."""

    vx: float = 0.0
    vy: float = 0.0
    wz: float = 0.0


@dataclass(frozen=True)
class Footprint:
    """Robot footprint centred on the base frame: a circle, or a rectangle along the body axes."""

    radius_m: float | None = None
    length_m: float | None = None
    width_m: float | None = None

    def __post_init__(self) -> None:
        is_circle = self.radius_m is not None
        is_rect = self.length_m is not None and self.width_m is not None
        require(is_circle != is_rect, "footprint", self, "radius_m, or length_m and width_m")
        for name in ("radius_m", "length_m", "width_m"):
            value = getattr(self, name)
            if value is not None:
                ok = math.isfinite(value) and value > 0
                require(ok, f"footprint.{name}", value, "a positive number of metres")

    @property
    def is_circle(self) -> bool:
        return self.radius_m is not None

    @property
    def bounding_radius_m(self) -> float:
        """Radius of the smallest circle around the footprint (m)."""
        if self.radius_m is not None:
            return self.radius_m
        return 0.5 * math.hypot(self.length_m, self.width_m)  # type: ignore[arg-type]


def yaw_to_quaternion(yaw: float) -> tuple[float, float, float, float]:
    """Quaternion ``(x, y, z, w)`` of a rotation by ``yaw`` about +z (ROS order)."""
    return (0.0, 0.0, math.sin(0.5 * yaw), math.cos(0.5 * yaw))


def wrap_angle(angle: float) -> float:
    """``angle`` wrapped to [-pi, pi)."""
    return (angle + math.pi) % (2.0 * math.pi) - math.pi


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
