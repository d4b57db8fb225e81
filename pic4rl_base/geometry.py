"""Planar geometry the metrics, the sim and the bridge share: the one pose type, a robot's
footprint and its distance to points, a scan's points from its sensor's mount, angle wrapping,
a yaw as a quaternion and back, and the projection of points onto a polyline.

``Pose2D`` is every pose: the robot's, a start, a sensor's mount in the base frame (the
``scan_mount`` of ``EpisodeFacts``). ``Footprint`` is the sim's robot specs' footprint and the
value type of another ``EpisodeFacts`` field (the facts themselves, their encoding and decoding
are the bag contract's, ``contract``). The sim and the bridge import them from here
(pic4rl_metrics may import no other pic4rl package; this module loads only numpy), so each is
written once:
``wrap_angle`` for every heading difference, ``yaw_to_quaternion`` for every published pose and
``yaw_from_quaternion`` for every decoded one, ``scan_points`` for the env's collisions, the
renderer, the occupancy grid and the metrics' clearance, ``Footprint.signed_distance`` for the
env's, the planner's and the metrics' collisions, ``project`` for the row follower, the planner
and the tasks' progress, the same projection as the row metrics'.
"""

from __future__ import annotations

import json
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, fields
from typing import Any, NamedTuple

import numpy as np

from .errors import ConfigError


class Pose2D(NamedTuple):
    """A planar pose: position (m) and heading (rad, counter-clockwise from +x)."""

    x: float
    y: float
    yaw: float = 0.0


@dataclass(frozen=True)
class Footprint:
    """Robot footprint centred on the base frame (m): a circle (``radius_m``), or a rectangle
    along the body axes (``length_m`` along x and ``width_m`` along y, both needed)."""

    radius_m: float | None = None
    length_m: float | None = None
    width_m: float | None = None

    def __post_init__(self) -> None:
        sides = (self.length_m, self.width_m)
        circle = self.radius_m is not None and sides == (None, None)
        rectangle = self.radius_m is None and None not in sides
        if not (circle or rectangle):
            msg = f"footprint: {self!r} is invalid; expected radius_m, or length_m and width_m"
            raise ConfigError(msg)
        for name in ("radius_m", "length_m", "width_m"):
            value = getattr(self, name)
            if value is not None and not (math.isfinite(value) and value > 0):
                msg = f"footprint.{name}: {value!r} is invalid; expected a positive number of "
                raise ConfigError(msg + "metres")

    @property
    def is_circle(self) -> bool:
        return self.radius_m is not None

    @property
    def bounding_radius_m(self) -> float:
        """Radius of the smallest circle around the footprint (m)."""
        if self.radius_m is not None:
            return self.radius_m
        return 0.5 * math.hypot(self.length_m, self.width_m)  # type: ignore[arg-type]

    @classmethod
    def parse(cls, value: Any, *, source: str = "facts") -> Footprint:
        """Parse ``{"radius_m": r}``, ``{"length_m": l, "width_m": w}``, their JSON, a number
        (a radius), ``"circle:R"`` or ``"rect:LxW"``."""
        if isinstance(value, Footprint):
            return value
        try:
            if isinstance(value, (int, float)):
                return cls(radius_m=float(value))
            if isinstance(value, str):
                text = value.strip()
                if text.startswith("{"):
                    return cls.parse(json.loads(text), source=source)
                kind, _, size = text.partition(":")
                if kind == "circle":
                    return cls(radius_m=float(size))
                if kind in ("rect", "rectangle"):
                    length, width = size.lower().split("x")
                    return cls(length_m=float(length), width_m=float(width))
                return cls(radius_m=float(text))
            if isinstance(value, Mapping):
                unknown = set(value) - {f.name for f in fields(cls)}
                if unknown:
                    msg = f"{source}: unknown keys {sorted(unknown)!r}"
                    raise ConfigError(msg)
                return cls(**{k: float(v) for k, v in value.items()})
        except ConfigError as err:
            raise ConfigError(f"{source}: {err}") from err
        except (ValueError, TypeError) as err:
            cause: Exception | None = err
        else:
            cause = None
        msg = (
            f"{source}: cannot read footprint {value!r}; expected a radius in metres, "
            "'circle:R', 'rect:LxW' or {'length_m': L, 'width_m': W}"
        )
        raise ConfigError(msg) from cause

    def signed_distance(self, points: np.ndarray) -> np.ndarray:
        """Signed distance (m) of points (..., 2, base frame) from the footprint's boundary,
        shape (...): positive outside, negative inside. Planners pass many poses' points at
        once (float32 stays float32; the coordinates may be strided views)."""
        p = np.asarray(points)
        p = p if p.dtype in (np.float32, np.float64) else p.astype(np.float64)
        return self.signed_distance_xy(p[..., 0], p[..., 1])

    def signed_distance_xy(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        """``signed_distance`` of the points with coordinates ``x`` and ``y`` (same shape)."""
        if self.radius_m is not None:
            return np.sqrt(x * x + y * y) - self.radius_m
        qx = np.abs(x) - 0.5 * self.length_m  # type: ignore[operator]  # beyond each face
        qy = np.abs(y) - 0.5 * self.width_m  # type: ignore[operator]
        ox, oy = np.maximum(qx, 0.0), np.maximum(qy, 0.0)
        return np.sqrt(ox * ox + oy * oy) + np.minimum(np.maximum(qx, qy), 0.0)




def sensor_to_base(forward: Any, left: Any, mount: Sequence[float]) -> tuple[Any, Any]:
    """Points ``forward`` and ``left`` (m, arrays of one shape) of a sensor mounted at ``mount``
    (x, y, yaw in the base frame: a ``Pose2D``), as base-frame x, y."""
    mx, my, myaw = mount
    c, s = math.cos(myaw), math.sin(myaw)
    return mx + c * forward - s * left, my + s * forward + c * left


def scan_points(ranges: Any, angles: Any, mount: Sequence[float]) -> tuple[Any, Any]:
    """Returns at ``ranges`` (m) along beam ``angles`` (rad, the scan's frame; shapes that
    broadcast) of a scanner mounted at ``mount``, as base-frame x and y; a NaN range gives NaN
    points (callers drop or keep them)."""
    return sensor_to_base(ranges * np.cos(angles), ranges * np.sin(angles), mount)


def wrap_angle(angle: Any) -> Any:
    """``angle`` (rad; a float or an array) wrapped to [-pi, pi)."""
    return (angle + math.pi) % (2.0 * math.pi) - math.pi


def yaw_to_quaternion(yaw: float) -> tuple[float, float, float, float]:
    """Quaternion ``(x, y, z, w)`` of a rotation by ``yaw`` about +z (ROS order)."""
    return (0.0, 0.0, math.sin(0.5 * yaw), math.cos(0.5 * yaw))


def yaw_from_quaternion(x: float, y: float, z: float, w: float) -> float:
    """Yaw (rad, in [-pi, pi]) of a quaternion: the rotation about +z of a planar robot."""
    return math.atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z))


# -- polylines (a row's centre line, a global plan) ------------------------------------------

def _nearest_on_polyline(
    line: np.ndarray, xy: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """For points ``xy`` (n × 2, m) and a polyline (k × 2): the index of the nearest segment,
    the fraction along it, the segments' lengths (m) and the signed distance (m, positive left
    of the line's direction)."""
    a, seg = line[:-1], np.diff(line, axis=0)
    lengths = np.hypot(seg[:, 0], seg[:, 1])
    rel = xy[:, None, :] - a[None]
    along = rel[..., 0] * seg[:, 0] + rel[..., 1] * seg[:, 1]
    t = np.clip(along / np.maximum(lengths**2, 1e-18), 0.0, 1.0)
    gap = rel - t[..., None] * seg
    dist = np.hypot(gap[..., 0], gap[..., 1])
    i = np.argmin(dist, axis=1)
    rows = np.arange(len(xy))
    near, step = rel[rows, i], seg[i]
    left = step[:, 0] * near[:, 1] - step[:, 1] * near[:, 0] >= 0.0
    nearest = dist[rows, i]
    return i, t[rows, i], lengths, np.where(left, nearest, -nearest)


def project(polyline: np.ndarray, xy: Sequence[float]) -> tuple[float, float]:
    """The point of ``polyline`` (n × 2, m) closest to ``xy``: its arc length from the first
    point (m) and the signed distance to it (m, positive left of the line's direction)."""
    line = np.asarray(polyline, dtype=np.float64)
    i, t, lengths, offset = _nearest_on_polyline(
        line, np.asarray(xy, dtype=np.float64).reshape(1, 2))
    k = int(i[0])
    return float(lengths[:k].sum() + t[0] * lengths[k]), float(offset[0])


def distance_to_polyline(x: np.ndarray, y: np.ndarray, line: np.ndarray) -> np.ndarray:
    """Signed distance (m) of points to a polyline (k, 2); positive on the line's left."""
    xy = np.column_stack([np.asarray(x, float), np.asarray(y, float)])
    return _nearest_on_polyline(np.asarray(line, dtype=np.float64), xy)[3]
