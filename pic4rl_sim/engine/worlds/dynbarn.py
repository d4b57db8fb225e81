"""The ``dynbarn`` world: a dynamic BARN (after DynaBARN, Nair et al. 2022), a ``barn_like``
field with ``moving_count`` cylinders moving on smooth random trajectories through it.

The static part is a ``barn_like`` world of the same variant and parameters (its automaton at a
lower fill by default, so that the moving obstacles make the difficulty). The moving ones start
anywhere in BARN's field (28 x 30 cells, between the enclosure's side columns) at a heading
and a mean speed drawn in ``[speed_min_m_s, speed_max_m_s]``, all from the variant; the engine
moves them (``engine.crowd.movers``: speed and turn rate vary smoothly with correlation time
``turn_time_s``, and they bounce off the field's edges), its random stream seeded by the
variant and the episode's seed. The start and goal are BARN's, below and above the field, so
the robot must cross it. ``params`` carry ``reference_path_length_m``, the static field's
shortest path from start to goal for a disc of a cell's radius, which marks the world as
BARN's for the BARN score (docs/metrics.md). ``TEST_SCENES`` are its 60 held-out test scenes.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import ClassVar

import numpy as np

from pic4rl_base.errors import require
from pic4rl_base.schema import Range, param, redefault

from . import barn_like as grid
from .arena import rng_for
from .barn_like import BarnLikeParams, barn_like
from .spec import MovingObstacles, WorldSpec

#: The held-out test scenes (``world_variant``s 0, 5, ..., 295, 60 of them): never trained on.
TEST_SCENES = tuple(range(0, 300, 5))
#: The field the moving obstacles stay in (xmin, ymin, xmax, ymax, m): BARN's 28 x 30 cells,
#: inside the enclosure's side columns.
FIELD = (grid._LEFT_X + grid.CELL_M / 2, grid._FIELD_Y - grid.CELL_M / 2,
         grid._LEFT_X + (grid.COLUMNS + 0.5) * grid.CELL_M,
         grid._FIELD_Y + (grid.ROWS - 0.5) * grid.CELL_M)
_SPEEDS = Range(0.1, 1.5)


@dataclass(frozen=True)
class DynBarnParams(BarnLikeParams):
    """The ``dynbarn`` world: a BARN-like field crossed by obstacles on smooth random paths."""

    KIND: ClassVar[str] = "dynbarn"
    fill_fraction: float = redefault(BarnLikeParams, "fill_fraction", 0.35)
    moving_count: int = param(6, doc="number of moving cylinders in the field",
                              range=Range(0, 40))
    moving_radius_m: float = param(0.15, doc="radius of each moving cylinder", unit="m",
                                   range=Range(0.075, 0.5))
    speed_min_m_s: float = param(0.1, doc="slowest speed of a moving obstacle", unit="m/s",
                                 range=_SPEEDS)
    speed_max_m_s: float = param(1.5, doc="fastest speed of a moving obstacle (each one's mean "
                                 "speed is drawn uniformly between the two)", unit="m/s",
                                 range=_SPEEDS)
    turn_time_s: float = param(2.0, doc="correlation time of the speed and turn rate: longer "
                               "is smoother and straighter (turn rate std: 1 rad / this)",
                               unit="s", range=Range(0.2, 20.0))

    def __post_init__(self) -> None:
        super().__post_init__()
        require(self.speed_min_m_s <= self.speed_max_m_s, "world.dynbarn.speed_min_m_s",
                self.speed_min_m_s, f"a speed in [0.1, speed_max_m_s={self.speed_max_m_s}] m/s")


def _reference_path_m(world: WorldSpec) -> float:
    """The static field's shortest path from start to goal for a disc of a cell's radius
    (0.075 m: no squeezing between diagonal neighbours, like a path of free cells), searched
    on a 0.1 m grid between the enclosure's columns from just below the start to just above the
    goal (a sixth of a 0.05 m grid over the whole world: a suite builds 60 worlds)."""
    from ..paths import PathPlanner  # the grid search, loaded only when a world is built

    start, goal = world.spawn_poses[0], world.goal_points[0]
    band = (FIELD[0], start.y - 0.5, FIELD[2], goal[1] + 0.5)
    path = PathPlanner(WorldSpec("field", band, cylinders=world.cylinders),
                       robot_radius_m=grid.RADIUS_M, resolution_m=0.1).path(start[:2], goal)
    return float(np.hypot(*np.diff(path, axis=0).T).sum())


def dynbarn(seed: int, p: DynBarnParams) -> WorldSpec:
    """The ``barn_like`` world of ``seed`` with ``p.moving_count`` moving cylinders drawn from
    the variant; ``params`` add ``reference_path_length_m``."""
    static = barn_like(seed, BarnLikeParams(p.fill_fraction, p.smoothing_steps,
                                            p.fill_threshold, p.corridor_cells, p.wander))
    rng = rng_for(seed + 1_000_003)  # apart from the field's own stream
    n, r = p.moving_count, p.moving_radius_m
    xmin, ymin, xmax, ymax = FIELD
    starts = rng.uniform((xmin + r, ymin + r), (xmax - r, ymax - r), (n, 2))
    moving = MovingObstacles(
        FIELD, tuple((float(x), float(y)) for x, y in starts),
        tuple(float(h) for h in rng.uniform(-math.pi, math.pi, n)),
        tuple(float(v) for v in rng.uniform(p.speed_min_m_s, p.speed_max_m_s, n)),
        (p.speed_min_m_s, p.speed_max_m_s), p.turn_time_s, radius_m=r)
    params = {**static.params, "moving_count": float(n), "moving_radius_m": r,
              "speed_min_m_s": p.speed_min_m_s, "speed_max_m_s": p.speed_max_m_s,
              "turn_time_s": p.turn_time_s,
              "reference_path_length_m": _reference_path_m(static)}
    return replace(static, name=p.KIND, moving=moving, params=params)
