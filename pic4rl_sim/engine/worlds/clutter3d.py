"""The ``clutter3d`` world: obstacles a planar LiDAR cannot see, beside walls it can.

Why combining a LiDAR with a depth camera matters: low boxes stand wholly below the default
robot's LiDAR plane (the Jackal's, 0.3 m up), table tops and shelves stand above it on legs so
thin that a 360-beam LiDAR misses them beyond a metre or two, and walls (the arena's and a few
inside it) stand across it. Every obstacle is a box or cylinder in the ``WorldSpec``, so start
and goal sampling and path search (planar clearance, blind to height) keep off all of them,
the space under a table top included.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from pic4rl_base.errors import require
from pic4rl_base.schema import PROBABILITY, Range, check, param, to_params

from .arena import WALL_HEIGHT_M, WALL_THICKNESS_M, rng_for, walls
from .spec import Box, Cylinder, WorldSpec, clearance

#: The default robot's (Jackal's) LiDAR height: low boxes stay under it, tops over it.
LIDAR_PLANE_M = 0.3
TOP_THICKNESS_M = 0.04
SHELF_TOP_M = 1.8  # a shelf's body reaches this high
_MISSES = 2000  # draws rejected in a row before a count is declared too many for the arena


@dataclass(frozen=True)
class Clutter3dParams:
    """The ``clutter3d`` world: low boxes, tables and shelves on thin legs, and walls."""

    KIND: ClassVar[str] = "clutter3d"
    size_m: float = param(10.0, doc="side of the square arena inside the walls", unit="m",
                          range=Range(4.0, 100.0))
    low_boxes: int = param(6, doc="boxes wholly below the default LiDAR plane",
                           range=Range(0, 100))
    low_height_m: float = param(0.15, doc="height of every low box (the Jackal's body, "
                                "0.02-0.25 m, touches it)", unit="m",
                                range=Range(0.03, LIDAR_PLANE_M, hi_open=True))
    tables: int = param(4, doc="tables and shelves: a top above the LiDAR plane on four "
                        "legs", range=Range(0, 50))
    shelf_fraction: float = param(0.5, doc="share of them that are shelves, their body up to "
                                  f"{SHELF_TOP_M} m", range=PROBABILITY)
    top_z_m: float = param(0.45, doc="height of a table top's or shelf's underside",
                           unit="m", range=Range(LIDAR_PLANE_M, 1.5, lo_open=True))
    leg_radius_m: float = param(0.015, doc="radius of a table's or shelf's legs", unit="m",
                                range=Range(0.005, 0.1))
    inner_walls: int = param(3, doc="straight walls (1-3 m, full height) inside the arena",
                             range=Range(0, 30))
    min_gap_m: float = param(0.7, doc="least free gap between two obstacles, and to the "
                             "arena's walls", unit="m", range=Range(0.0, 5.0))

    def __post_init__(self) -> None:
        check(self, f"world.{self.KIND}.")
        require(self.min_gap_m <= self.size_m / 4, f"world.{self.KIND}.min_gap_m",
                self.min_gap_m, f"a value in [0.0, {self.size_m / 4}]")


def _legs(top: Box, radius_m: float) -> list[Cylinder]:
    """Four legs under ``top``'s corners, inside its outline, up to its underside."""
    cos, sin = math.cos(top.yaw_rad), math.sin(top.yaw_rad)
    hx, hy = top.size_x_m / 2 - radius_m, top.size_y_m / 2 - radius_m
    return [Cylinder(top.x + cos * sx * hx - sin * sy * hy, top.y + sin * sx * hx + cos * sy * hy,
                     radius_m, top.z_base_m, kind="post")
            for sx in (-1, 1) for sy in (-1, 1)]


def clutter3d(seed: int, p: Clutter3dParams) -> WorldSpec:
    """Walls inside the arena, then tables and shelves, then low boxes, each ``min_gap_m``
    from those placed and from the arena's walls; ``params`` keeps ``shelves_placed``."""
    rng, half = rng_for(seed), p.size_m / 2
    boxes: list[Box] = []
    legs: list[Cylinder] = []
    shelves = 0

    def place(draw_size: tuple[float, float], what: str, count: int) -> list[Box]:
        placed: list[Box] = []
        misses = 0
        while len(placed) < count:
            require(misses < _MISSES, f"world.{p.KIND}.{what}", count,
                    f"a count that fits the arena with min_gap_m={p.min_gap_m} "
                    f"(placed {len(placed)})")
            sx, sy = (float(rng.uniform(*draw_size)) for _ in range(2))
            yaw = float(rng.uniform(-math.pi, math.pi)) if what != "inner_walls" else 0.0
            if what == "inner_walls":
                sx, sy = (sx, WALL_THICKNESS_M) if rng.random() < 0.5 else (WALL_THICKNESS_M, sy)
            reach = 0.5 * math.hypot(sx, sy)
            limit = half - reach - p.min_gap_m
            x, y = (float(v) for v in rng.uniform(-1, 1, 2) * max(limit, 0.0))
            gap = clearance(np.array([[x, y]]), tuple(boxes), ())[0]
            if limit < 0 or gap < reach + p.min_gap_m:
                misses += 1
                continue
            misses = 0
            placed.append(Box(x, y, sx, sy, 1.0, yaw))
            boxes.append(placed[-1])
        return placed

    boxes_out: list[Box] = [Box(b.x, b.y, b.size_x_m, b.size_y_m, WALL_HEIGHT_M)
                            for b in place((1.0, 3.0), "inner_walls", p.inner_walls)]
    for b in place((0.6, 1.2), "tables", p.tables):
        shelf = rng.random() < p.shelf_fraction
        shelves += int(shelf)
        height = SHELF_TOP_M - p.top_z_m if shelf else TOP_THICKNESS_M
        top = Box(b.x, b.y, b.size_x_m, b.size_y_m, height, b.yaw_rad, p.top_z_m,
                  kind="furniture")
        boxes_out.append(top)
        legs += _legs(top, p.leg_radius_m)
    boxes_out += [Box(b.x, b.y, b.size_x_m, b.size_y_m, p.low_height_m, b.yaw_rad,
                      kind="obstacle") for b in place((0.3, 0.8), "low_boxes", p.low_boxes)]
    bounds = (-half, -half, half, half)
    return WorldSpec(p.KIND, bounds, tuple(walls(bounds) + boxes_out), tuple(legs), seed=seed,
                     params={**to_params(p), "shelves_placed": float(shelves)})
