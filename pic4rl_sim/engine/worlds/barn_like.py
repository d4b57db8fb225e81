"""The ``barn_like`` world: BARN-like obstacle fields drawn from a seed, as many as training
wants (ros_jackal: 5 to 250 training worlds took held-out success from 43 % to 74 %).

Perille et al. (2020) made BARN's worlds with a cellular automaton: each cell of a grid is
filled at random, then smoothed for a few steps (a cell fills when enough of its eight
neighbours are filled, and empties when too few are), and a world is kept only when a path
crosses it. Here the path is made, not searched for: after smoothing, a corridor
``corridor_cells`` wide is carved by a random walk from the field's bottom row to its top, so
every world has one. The frame is BARN's: the same 0.15 m cells, each filled cell a cylinder of
radius 0.075 m and 1 m high, the same enclosure (two side columns and a bottom row of
cylinders), a field of 28 x 30 cells above the start area, and the challenge's start and goal.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from pic4rl_base.schema import PROBABILITY, Range, check, param, to_params

from .arena import rng_for, walls
from .barn import start_and_goal
from .spec import Cylinder, WorldSpec

CELL_M = 0.15
RADIUS_M = 0.075
HEIGHT_M = 1.0
COLUMNS, ROWS = 28, 30  # the field's cells, inside the enclosure
_LEFT_X, _BOTTOM_Y, _FIELD_Y = -4.425, 0.075, 5.175  # BARN's enclosure and field (centres)
_WALL_ROWS = 64  # cylinders up each side column, from _BOTTOM_Y
_MARGIN_M = 2.0


@dataclass(frozen=True)
class BarnLikeParams:
    """The ``barn_like`` world: a BARN-like field from a seed (Perille et al.'s automaton)."""

    KIND: ClassVar[str] = "barn_like"
    fill_fraction: float = param(0.4, doc="share of the field's cells filled at random before "
                                 "smoothing", range=Range(0.0, 0.6))
    smoothing_steps: int = param(2, doc="cellular-automaton smoothing steps",
                                 range=Range(0, 10))
    fill_threshold: int = param(5, doc="an empty cell fills with at least this many of its 8 "
                                "neighbours filled; a filled one stays with one fewer",
                                range=Range(1, 8))
    corridor_cells: int = param(5, doc="width of the carved start-goal corridor, in 0.15 m "
                                "cells (5: 0.375 m from its centre line to the nearest "
                                "cylinder, above the Jackal's 0.333 m)", range=Range(5, COLUMNS))
    wander: float = param(0.5, doc="chance per row that the corridor steps one cell sideways",
                          range=PROBABILITY)

    def __post_init__(self) -> None:
        check(self, f"world.{self.KIND}.")


def _neighbours(grid: np.ndarray) -> np.ndarray:
    """How many of each cell's 8 neighbours are filled (outside the field counts empty)."""
    padded = np.pad(grid.astype(np.int8), 1)
    rows, cols = grid.shape
    return sum(padded[1 + dr:1 + dr + rows, 1 + dc:1 + dc + cols]
               for dr in (-1, 0, 1) for dc in (-1, 0, 1) if dr or dc)


def _carve(grid: np.ndarray, rng: np.random.Generator, width: int, wander: float) -> int:
    """Clear a ``width`` x ``width`` square (centred, clipped to the field) at each step of a
    walk from the bottom row to the top one (up a row each step, then one column sideways with
    chance ``wander``); returns the column it entered at."""
    rows, cols = grid.shape
    low, high = width // 2, cols - (width - width // 2)  # the squares' centres stay inside
    col = entry = int(rng.integers(low, high + 1))

    def clear(r: int, c: int) -> None:
        r0, c0 = max(r - width // 2, 0), c - width // 2
        grid[r0:max(r - width // 2 + width, 0), c0:c0 + width] = False

    for row in range(rows):
        clear(row, col)
        if rng.random() < wander:
            col = int(np.clip(col + (1 if rng.random() < 0.5 else -1), low, high))
            clear(row, col)
    return entry


def _enclosure() -> list[tuple[float, float]]:
    """BARN's side columns and bottom row of cylinders (centres, m)."""
    right_x = _LEFT_X + (COLUMNS + 1) * CELL_M
    sides = [(x, _BOTTOM_Y + k * CELL_M) for x in (_LEFT_X, right_x) for k in range(_WALL_ROWS)]
    bottom = [(_LEFT_X + (k + 1) * CELL_M, _BOTTOM_Y) for k in range(COLUMNS)]
    return sides + bottom


def barn_like(seed: int, p: BarnLikeParams) -> WorldSpec:
    """A BARN-like world for ``seed``: random fill, ``smoothing_steps`` of the automaton, a
    carved corridor; ``params`` keep what was drawn (``filled_fraction``, ``corridor_entry``)."""
    rng = rng_for(seed)
    grid = rng.random((ROWS, COLUMNS)) < p.fill_fraction
    for _ in range(p.smoothing_steps):
        n = _neighbours(grid)
        grid = np.where(grid, n >= p.fill_threshold - 1, n >= p.fill_threshold)
    entry = _carve(grid, rng, p.corridor_cells, p.wander)
    rows, cols = np.nonzero(grid)
    field = [(_LEFT_X + (c + 1) * CELL_M, _FIELD_Y + r * CELL_M) for r, c in zip(rows, cols)]
    cylinders = tuple(Cylinder(round(x, 6), round(y, 6), RADIUS_M, HEIGHT_M)
                      for x, y in _enclosure() + field)
    start, goal = start_and_goal()
    xs = [c.x for c in cylinders] + [start.x, goal[0]]
    ys = [c.y for c in cylinders] + [start.y, goal[1]]
    bounds = (min(xs) - _MARGIN_M, min(ys) - _MARGIN_M, max(xs) + _MARGIN_M, max(ys) + _MARGIN_M)
    params = {**to_params(p), "filled_fraction": float(grid.mean()), "corridor_entry": float(entry)}
    return WorldSpec(p.KIND, bounds, tuple(walls(bounds)), cylinders,
                     spawn_poses=(start,), goal_points=(goal,),
                     seed=seed, params=params)
