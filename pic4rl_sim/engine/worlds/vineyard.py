"""The vineyard generator: vine rows that curve, vary in spacing and miss plants, posts at
their ends, and the lanes (centre lines) between them.

Rows are laid out along a *shape*: straight along x, or concentric arcs (``row_radius_m``), and
on top of either a seeded lateral wave (``bend_m``) that every row shares, as rows planted
along a field's contour do. The lanes between neighbouring rows are ``row_spacing_m`` wide give
or take a seeded ``spacing_jitter_m`` each, so one world already holds lanes of several widths
and bends, and another ``world_variant`` (seed) holds others: train on one, test on others.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from pic4rl_base.errors import require
from pic4rl_base.schema import FRACTION, NON_NEGATIVE, Range, check, param, to_params

from pic4rl_base.geometry import Pose2D
from .arena import rng_for, walls
from .spec import Box, Cylinder, WorldSpec

TRUNK_RADIUS_M = 0.05
TRUNK_HEIGHT_M = 1.2
CANOPY_WIDTH_M = 0.5
CANOPY_Z_BASE_M = 0.8
CANOPY_HEIGHT_M = 1.0
POST_RADIUS_M = 0.08
POST_HEIGHT_M = 1.8
POST_OFFSET_M = 0.6  # an end post stands this far beyond the row's last plant, in line
HEADLAND_M = 3.0  # free ground between the outermost posts and the vineyard's wall
LANE_STEP_M = 0.5
MIN_SPACING_M = CANOPY_WIDTH_M + 0.6  # a lane narrower than this leaves no room for a robot



@dataclass(frozen=True)
class VineyardParams:
    """The ``vineyard`` world: vine rows, straight or curved, and the lanes between them."""

    KIND: ClassVar[str] = "vineyard"
    rows: int = param(5, doc="number of vine rows", range=Range(2, 30))
    row_spacing_m: float = param(2.5, doc="distance between neighbouring rows: the mean over "
                                 "the lanes", unit="m", range=Range(MIN_SPACING_M, 20.0))
    spacing_jitter_m: float = param(0.0, doc="each lane's width is drawn uniformly in "
                                    "row_spacing_m +- this", unit="m",
                                    range=Range(0.0, 20.0 - MIN_SPACING_M))
    row_length_m: float = param(10.0, doc="length of the middle row", unit="m",
                                range=Range(1.0, 200.0))
    trunk_spacing_m: float = param(1.0, doc="distance between plants along a row", unit="m",
                                   range=Range(0.2, 200.0))
    gap_prob: float = param(0.1, doc="probability that a plant (trunk and its canopy) is "
                            "missing", range=FRACTION)
    row_radius_m: float = param(0.0, doc="radius of the innermost row's arc; 0 for straight "
                                "rows", unit="m", range=NON_NEGATIVE)
    bend_m: float = param(0.0, doc="amplitude of the rows' shared lateral wave, of seeded "
                          "wavelength (one to two row lengths) and phase; 0: no wave",
                          unit="m", range=Range(0.0, 50.0))

    def __post_init__(self) -> None:
        check(self, "world.vineyard.")
        jitter = self.row_spacing_m - MIN_SPACING_M
        require(self.spacing_jitter_m <= jitter, "world.vineyard.spacing_jitter_m",
                self.spacing_jitter_m, f"a value in [0.0, {jitter}]")
        require(self.trunk_spacing_m <= self.row_length_m, "world.vineyard.trunk_spacing_m",
                self.trunk_spacing_m, f"a value in [0.2, {self.row_length_m}]")
        require(self.bend_m <= 0.25 * self.row_length_m, "world.vineyard.bend_m", self.bend_m,
                f"a value in [0.0, {0.25 * self.row_length_m}]")
        require(self.row_radius_m == 0 or self.bend_m < self.row_radius_m,
                "world.vineyard.bend_m", self.bend_m,
                f"less than row_radius_m={self.row_radius_m} (the innermost row would fold)")


@dataclass(frozen=True)
class RowShape:
    """Where a row or lane lies: ``point(offset_m, t)`` is the point at fraction ``t`` of its
    length, ``offset_m`` from the middle row (positive to the left of the rows' direction
    when straight, outward when curved)."""

    length_m: float
    middle_radius_m: float  # 0: straight rows
    bend_m: float
    wavelength_m: float
    phase_rad: float

    def points(self, offset_m: float, n: int) -> np.ndarray:
        """``n + 1`` points from the start (t = 0) to the end (t = 1), (n + 1) x 2 (m)."""
        t = np.linspace(0.0, 1.0, n + 1)
        wave = self.bend_m * np.sin(2 * math.pi * t * self.length_m / self.wavelength_m
                                    + self.phase_rad)
        if self.middle_radius_m == 0:
            return np.column_stack([(t - 0.5) * self.length_m, offset_m + wave])
        span = self.length_m / self.middle_radius_m
        phi = 0.5 * math.pi + span * (0.5 - t)
        radius = self.middle_radius_m + offset_m + wave
        return np.column_stack([radius * np.cos(phi),
                                radius * np.sin(phi) - self.middle_radius_m])

    def length(self, offset_m: float) -> float:
        """The length (m) of the row or lane ``offset_m`` from the middle one."""
        pts = self.points(offset_m, 400)
        return float(np.hypot(*np.diff(pts, axis=0).T).sum())


def vineyard(seed: int, p: VineyardParams) -> WorldSpec:
    """Vine rows (trunks under canopy, plants missing at random, a post at each end) inside a
    far wall, and the lanes between them.

    Each lane starts at a spawn pose facing along it and ends at its goal point. ``params``
    keeps the drawn geometry: ``lane_width_<k>_m``, ``bend_wavelength_m``,
    ``bend_phase_rad`` and, for curved rows, ``arc_center_x_m``, ``arc_center_y_m``.
    """
    params: dict[str, float] = to_params(p)
    rows, row_spacing_m, spacing_jitter_m = p.rows, p.row_spacing_m, p.spacing_jitter_m
    row_length_m, row_radius_m, bend_m = p.row_length_m, p.row_radius_m, p.bend_m
    rng = rng_for(seed)
    widths = row_spacing_m + rng.uniform(-spacing_jitter_m, spacing_jitter_m, rows - 1)
    edges = np.concatenate([[0.0], np.cumsum(widths)])
    offsets = edges - 0.5 * (edges[0] + edges[-1])  # the middle row at offset 0
    middle_m = row_radius_m - offsets[0] if row_radius_m > 0 else 0.0
    require(row_radius_m == 0 or (row_radius_m > 0 and row_length_m <= math.pi * middle_m),
            "world.vineyard.row_radius_m", row_radius_m,
            "0 (straight rows), or a radius that bends the middle row by at most 180 degrees")
    shape = RowShape(row_length_m, middle_m, bend_m, row_length_m * float(rng.uniform(1, 2)),
                     float(rng.uniform(0, 2 * math.pi)))
    rows_xy = [shape.points(o, max(1, round(shape.length(o) / p.trunk_spacing_m)))
               for o in offsets]
    boxes, cylinders = _vine_rows(rng, rows_xy, p.gap_prob)
    lanes = [shape.points(o, max(2, math.ceil(shape.length(o) / LANE_STEP_M)))
             for o in 0.5 * (offsets[:-1] + offsets[1:])]
    spawns = tuple(Pose2D(float(p[0, 0]), float(p[0, 1]),
                          math.atan2(p[1, 1] - p[0, 1], p[1, 0] - p[0, 0])) for p in lanes)
    xy = np.array([(c.x, c.y) for c in cylinders])
    lo, hi = xy.min(axis=0) - HEADLAND_M, xy.max(axis=0) + HEADLAND_M
    bounds = (float(lo[0]), float(lo[1]), float(hi[0]), float(hi[1]))
    params.update({f"lane_width_{k}_m": float(w) for k, w in enumerate(widths)},
                  bend_wavelength_m=shape.wavelength_m, bend_phase_rad=shape.phase_rad)
    if middle_m > 0:
        params.update(arc_center_x_m=0.0, arc_center_y_m=-middle_m)
    lane_xy = tuple(tuple((float(x), float(y)) for x, y in p) for p in lanes)
    return WorldSpec("vineyard", bounds, tuple(walls(bounds) + boxes), tuple(cylinders),
                     spawn_poses=spawns, goal_points=tuple(p[-1] for p in lane_xy),
                     lanes=lane_xy, seed=seed, params=params)


def _vine_rows(rng: np.random.Generator, rows_xy: list[np.ndarray],
               gap_prob: float) -> tuple[list[Box], list[Cylinder]]:
    """Each row's plants (a trunk under a canopy box that reaches halfway to its neighbours),
    a few missing at random but never a row's end plants, and a post beyond each end."""
    boxes: list[Box] = []
    cylinders: list[Cylinder] = []
    for pts in rows_xy:
        keep = rng.random(len(pts)) >= gap_prob
        keep[[0, -1]] = True  # row ends stay visible
        ahead = np.vstack([pts[1:], 2 * pts[-1] - pts[-2]])
        behind = np.vstack([2 * pts[0] - pts[1], pts[:-1]])
        for (x, y), a, b in zip(pts[keep], ahead[keep], behind[keep]):
            d = 0.5 * (a - b)  # from halfway behind to halfway ahead
            cylinders.append(Cylinder(float(x), float(y), TRUNK_RADIUS_M, TRUNK_HEIGHT_M,
                                      kind="trunk"))
            boxes.append(Box(float(x), float(y), float(np.hypot(*d)), CANOPY_WIDTH_M,
                             CANOPY_HEIGHT_M, float(math.atan2(d[1], d[0])), CANOPY_Z_BASE_M,
                             kind="canopy"))
        for end, inner in ((pts[0], pts[1]), (pts[-1], pts[-2])):
            u = (end - inner) / np.hypot(*(end - inner))
            post = end + POST_OFFSET_M * u
            cylinders.append(Cylinder(float(post[0]), float(post[1]), POST_RADIUS_M,
                                      POST_HEIGHT_M, kind="post"))
    return boxes, cylinders
