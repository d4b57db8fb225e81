"""Worlds as data: the static obstacles, the arena, a walking person, where to start.

A ``WorldSpec`` is what the engine turns into MuJoCo geoms and what start/goal sampling,
markers and tasks read; generators in ``worlds`` make them from a seed. Obstacles are
boxes and vertical cylinders, so 2D clearance is exact and cheap (``clearance``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from pic4rl_base.errors import require

from pic4rl_base.geometry import Pose2D


@dataclass(frozen=True)
class Box:
    """A box standing on ``z_base_m``: centre (m), full sizes (m), yaw (rad)."""

    x: float
    y: float
    size_x_m: float
    size_y_m: float
    height_m: float
    yaw_rad: float = 0.0
    z_base_m: float = 0.0
    kind: str = "wall"  # wall | furniture | canopy | obstacle: colours and markers only

    def __post_init__(self) -> None:
        for key in ("size_x_m", "size_y_m", "height_m"):
            value = getattr(self, key)
            require(math.isfinite(value) and value > 0, f"box.{key}", value, "a positive size")


@dataclass(frozen=True)
class Cylinder:
    """A vertical cylinder standing on ``z_base_m``: centre (m), radius (m), height (m)."""

    x: float
    y: float
    radius_m: float
    height_m: float
    z_base_m: float = 0.0
    kind: str = "obstacle"  # obstacle | trunk | post | person

    def __post_init__(self) -> None:
        for key in ("radius_m", "height_m"):
            value = getattr(self, key)
            require(math.isfinite(value) and value > 0, f"cylinder.{key}", value, "a positive size")


@dataclass(frozen=True)
class PersonSpec:
    """A person (a cylinder) walking a closed loop of waypoints: leg i (waypoint i to i + 1)
    at ``leg_speeds_m_s[i]``, or every leg at ``speed_m_s`` when none are given."""

    waypoints: tuple[tuple[float, float], ...]
    speed_m_s: float = 0.6
    radius_m: float = 0.25
    height_m: float = 1.7
    leg_speeds_m_s: tuple[float, ...] = ()

    def __post_init__(self) -> None:
        require(len(self.waypoints) >= 2, "person.waypoints", self.waypoints, "two or more points")
        require(self.speed_m_s >= 0, "person.speed_m_s", self.speed_m_s, "a speed >= 0")
        legs = self.leg_speeds_m_s
        require(not legs or (len(legs) == len(self.waypoints)
                             and all(math.isfinite(v) and v > 0 for v in legs)),
                "person.leg_speeds_m_s", legs,
                f"() or one speed > 0 per leg ({len(self.waypoints)} legs)")

    def pose_at(self, t_s: float) -> tuple[Pose2D, tuple[float, float]]:
        """Pose (facing the walking direction) and world velocity (m/s) at time ``t_s``."""
        pts = np.asarray(self.waypoints + self.waypoints[:1], dtype=float)
        seg = np.diff(pts, axis=0)
        lengths = np.hypot(seg[:, 0], seg[:, 1])
        speeds = np.asarray(self.leg_speeds_m_s or (self.speed_m_s,) * len(lengths))
        if lengths.sum() == 0 or speeds.min() == 0:
            yaw = math.atan2(seg[0, 1], seg[0, 0]) if lengths[0] > 0 else 0.0
            return Pose2D(float(pts[0, 0]), float(pts[0, 1]), yaw), (0.0, 0.0)
        durations = lengths / speeds
        ends = np.cumsum(durations)
        t = t_s % float(ends[-1])
        i = min(int(np.searchsorted(ends, t, side="right")), len(lengths) - 1)
        u = seg[i] / lengths[i] if lengths[i] > 0 else np.zeros(2)
        p = pts[i] + u * speeds[i] * (t - float(ends[i] - durations[i]))
        yaw = math.atan2(u[1], u[0])
        return Pose2D(float(p[0]), float(p[1]), yaw), (float(u[0] * speeds[i]),
                                                        float(u[1] * speeds[i]))

    def positions(self, until_s: float, step_s: float = 0.02) -> np.ndarray:
        """Where the person is (k × 2, m) every ``step_s`` from time 0 to ``until_s``."""
        times = np.arange(0.0, until_s + 0.5 * step_s, step_s)
        return np.array([self.pose_at(float(t))[0][:2] for t in times]).reshape(-1, 2)


@dataclass(frozen=True)
class MovingObstacles:
    """Cylinders moving on smooth random trajectories inside ``field`` (xmin, ymin, xmax, ymax:
    their centres stay ``radius_m`` inside it, bouncing off its edges): where each starts (m),
    its heading (rad) and mean speed (m/s), the speeds' range (m/s) and the trajectories'
    correlation time (s); ``engine.crowd.movers`` moves them."""

    field: tuple[float, float, float, float]
    starts: tuple[tuple[float, float], ...]
    headings_rad: tuple[float, ...]
    speeds_m_s: tuple[float, ...]
    speed_range_m_s: tuple[float, float]
    turn_time_s: float
    radius_m: float = 0.15
    height_m: float = 1.0

    def __post_init__(self) -> None:
        n = len(self.starts)
        require(len(self.headings_rad) == n and len(self.speeds_m_s) == n, "moving.speeds_m_s",
                self.speeds_m_s, f"one heading and one speed per obstacle ({n})")
        lo, hi = self.speed_range_m_s
        require(0 < lo <= hi and all(lo <= v <= hi for v in self.speeds_m_s),
                "moving.speeds_m_s", self.speeds_m_s, f"speeds in [{lo}, {hi}] m/s, 0 < lo")


@dataclass(frozen=True)
class WorldSpec:
    """A world: arena bounds, static obstacles, optional person, spawn hints.

    ``spawn_poses``/``goal_points`` restrict sampling to those candidates (a vineyard's lane
    ends); empty means anywhere inside ``bounds`` with clearance. ``lanes`` are centre lines
    between crop rows (vineyard). ``mjcf_path`` is a user's MJCF file the engine builds on;
    its obstacles were read into ``boxes``/``cylinders`` for sampling and markers. ``moving``
    are obstacles that the engine moves (``dynbarn``), absent from ``clearance``.
    """

    name: str
    bounds: tuple[float, float, float, float]  # xmin, ymin, xmax, ymax (m)
    boxes: tuple[Box, ...] = ()
    cylinders: tuple[Cylinder, ...] = ()
    person: PersonSpec | None = None
    spawn_poses: tuple[Pose2D, ...] = ()
    goal_points: tuple[tuple[float, float], ...] = ()
    lanes: tuple[tuple[tuple[float, float], ...], ...] = ()
    mjcf_path: Path | None = None
    seed: int = 0
    params: dict[str, float] = field(default_factory=dict, compare=False)
    moving: MovingObstacles | None = None

    def __post_init__(self) -> None:
        xmin, ymin, xmax, ymax = self.bounds
        require(xmin < xmax and ymin < ymax, "world.bounds", self.bounds,
                "(xmin, ymin, xmax, ymax) with xmin < xmax and ymin < ymax")

    def clearance(self, xy: np.ndarray) -> np.ndarray:
        """Distance (m) from each point of ``xy`` (shape (n, 2)) to the nearest static obstacle,
        in the plane; negative inside one. ``inf`` when the world has no obstacles."""
        return clearance(xy, self.boxes, self.cylinders)


def clearance(xy: np.ndarray, boxes: tuple[Box, ...],
              cylinders: tuple[Cylinder, ...]) -> np.ndarray:
    """Signed planar distance (m) from points ``xy`` (n, 2) to the nearest box or cylinder."""
    xy = np.atleast_2d(np.asarray(xy, dtype=float))
    best = np.full(len(xy), np.inf)
    if cylinders:
        c = np.array([(o.x, o.y, o.radius_m) for o in cylinders])
        d = np.hypot(xy[:, None, 0] - c[None, :, 0], xy[:, None, 1] - c[None, :, 1]) - c[None, :, 2]
        best = np.minimum(best, d.min(axis=1))
    if boxes:
        b = np.array([(o.x, o.y, o.size_x_m / 2, o.size_y_m / 2, o.yaw_rad) for o in boxes])
        dx = xy[:, None, 0] - b[None, :, 0]
        dy = xy[:, None, 1] - b[None, :, 1]
        cos, sin = np.cos(b[:, 4]), np.sin(b[:, 4])
        lx = np.abs(cos * dx + sin * dy) - b[:, 2]  # point in the box frame, minus half sizes
        ly = np.abs(-sin * dx + cos * dy) - b[:, 3]
        outside = np.hypot(np.maximum(lx, 0), np.maximum(ly, 0))
        inside = np.minimum(np.maximum(lx, ly), 0)
        best = np.minimum(best, (outside + inside).min(axis=1))
    return best
