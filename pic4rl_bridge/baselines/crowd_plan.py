"""The privileged planner's plan around people (issue 41 item 4): the world's map with each
person of the ``people`` reading blocked where they stand now, searched and pulled taut as
the world's plan is (``pic4rl_sim.engine.paths``), so that the planner replans around a crowd
instead of driving its world plan through it.

Each person is a disc of ``keep_off_m`` (the robot's circumscribed radius plus the planner's
``people_margin_m``) around their current position: moving people are not predicted; at a fixed
period (``PlannerController``'s ``people_replan_s``) the plan ahead is checked against where they
stand then (``blocks``) and made again round them when one is in its way. A person nearer than that
to the robot or the goal is blocked only up to a cell short of it, or no path could leave the
robot's cell or reach the goal: the plan then leads away from them. The grid is the world's
clearance at the cell centres (``clearance_grid``, computed once per world), thresholded at the
robot's radius plus a plan margin; the search is ``grid_search`` (Dijkstra, no corner cutting) and
the cell path is pulled taut (``pull_taut``) with a line of sight that keeps both the world's
clearance and each person's disc.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from pic4rl_sim.engine.paths import (
    RESOLUTION_M,
    clearance_grid,
    grid_search,
    grid_steps,
    planner_for,
    segment_samples,
)
from pic4rl_sim.engine.taut_path import pull_taut
from pic4rl_sim.engine.worlds.spec import WorldSpec


def people_discs(people_xy: np.ndarray, start: np.ndarray, goal: np.ndarray,
                 keep_off_m: float) -> np.ndarray:
    """The blocked discs (k × 3: x, y, radius, m): ``keep_off_m`` round each person, shrunk
    to a cell short of the start or the goal where they stand nearer; a person whose disc
    would vanish so is left out."""
    xy = np.asarray(people_xy, dtype=float).reshape(-1, 2)
    near = np.minimum(np.hypot(*(xy - start).T), np.hypot(*(xy - goal).T)) - RESOLUTION_M
    radius = np.minimum(keep_off_m, near)
    keep = radius > 0
    return np.column_stack((xy[keep], radius[keep]))


def blocks(path: np.ndarray, along_m: float, xy: Sequence[float], people_xy: np.ndarray,
           keep_off_m: float) -> bool:
    """Whether a person's disc (``people_discs``, from the robot at ``xy`` to the path's end,
    a cell smaller: a plan round them bends on the grid's cells) lies on the part of ``path``
    (k × 2) beyond ``along_m`` (the robot's projection on it) or on the way there."""
    start = np.asarray(xy[:2], dtype=float)
    discs = people_discs(people_xy, start, path[-1], keep_off_m - RESOLUTION_M)
    if not len(discs):
        return False
    cumulative = np.r_[0.0, np.cumsum(np.hypot(*np.diff(path, axis=0).T))]
    ahead = np.vstack((start, path[cumulative > along_m]))
    if len(ahead) < 2:
        return False
    pts, _ = segment_samples(ahead[:-1], ahead[1:], 0.5 * RESOLUTION_M)
    return not bool(_outside_discs(pts, discs).all())


def _outside_discs(pts: np.ndarray, discs: np.ndarray) -> np.ndarray:
    """Whether each point of ``pts`` (n × 2) lies outside every disc."""
    if not len(discs):
        return np.ones(len(pts), dtype=bool)
    gap = np.hypot(pts[:, None, 0] - discs[None, :, 0], pts[:, None, 1] - discs[None, :, 1])
    return (gap >= discs[None, :, 2]).all(axis=1)


def _snap(free: np.ndarray, cell: tuple[int, int]) -> tuple[int, int] | None:
    """``cell`` (row, column of the padded grid) if free, else the nearest free cell."""
    if free[cell]:
        return cell
    rows, cols = np.nonzero(free)
    if not len(rows):
        return None
    best = int(np.argmin((rows - cell[0]) ** 2 + (cols - cell[1]) ** 2))
    return int(rows[best]), int(cols[best])


def _plan(world: WorldSpec, start: np.ndarray, goal: np.ndarray, radius_m: float,
          discs: np.ndarray) -> np.ndarray | None:
    """The path (k × 2) a disc of ``radius_m`` takes from ``start`` to ``goal`` round the
    world's obstacles and ``discs``; ``None`` when there is none."""
    clear = clearance_grid(world, RESOLUTION_M)
    ny, nx = clear.shape
    xmin, ymin = world.bounds[:2]
    xs = xmin + (np.arange(nx) + 0.5) * RESOLUTION_M
    ys = ymin + (np.arange(ny) + 0.5) * RESOLUTION_M
    free = np.zeros((ny + 2, nx + 2), dtype=bool)  # one blocked cell of padding all round
    inner = clear >= radius_m
    for x, y, r in discs:  # each person's window of cells
        cols = slice(max(int((x - r - xmin) / RESOLUTION_M), 0),
                     min(math.ceil((x + r - xmin) / RESOLUTION_M) + 1, nx))
        rows = slice(max(int((y - r - ymin) / RESOLUTION_M), 0),
                     min(math.ceil((y + r - ymin) / RESOLUTION_M) + 1, ny))
        inside = np.hypot(xs[None, cols] - x, ys[rows, None] - y) < r
        inner[rows, cols] &= ~inside
    free[1:-1, 1:-1] = inner

    def cell(p: np.ndarray) -> tuple[int, int]:
        return (int(np.clip((p[1] - ymin) // RESOLUTION_M, 0, ny - 1)) + 1,
                int(np.clip((p[0] - xmin) // RESOLUTION_M, 0, nx - 1)) + 1)

    s, g = _snap(free, cell(start)), _snap(free, cell(goal))
    if s is None or g is None:
        return None
    width = nx + 2
    cells = grid_search(free.ravel(), grid_steps(free), s[0] * width + s[1],
                        g[0] * width + g[1])
    if cells is None or not len(cells):
        return None
    rows, cols = np.divmod(cells, width)
    centres = np.column_stack((xmin + (cols - 0.5) * RESOLUTION_M,
                               ymin + (rows - 0.5) * RESOLUTION_M))
    sight = planner_for(world, robot_radius_m=radius_m, resolution_m=RESOLUTION_M)

    def visible(a: np.ndarray, b: np.ndarray) -> np.ndarray:  # as ``PathPlanner.visible``
        pts, starts = segment_samples(a, b, 0.5 * RESOLUTION_M)
        ok = sight.clearance_at(pts) >= radius_m - 1e-9
        return np.logical_and.reduceat(ok & _outside_discs(pts, discs), starts)

    pts = np.vstack((start, centres[1:-1], goal))
    return np.asarray(pull_taut(pts, visible, corner_radius_m=max(radius_m, RESOLUTION_M),
                                step_m=RESOLUTION_M))


def plan_around_people(world: WorldSpec, start_xy: Sequence[float], goal_xy: Sequence[float],
                       people_xy: np.ndarray, *, robot_radius_m: float,
                       margins_m: Sequence[float], keep_off_m: float) -> np.ndarray | None:
    """A plan (k × 2, m) from ``start_xy`` to ``goal_xy`` that keeps the first positive one
    of ``margins_m`` beyond ``robot_radius_m`` from the world's obstacles with which a path
    round the people's discs (``people_discs``) exists; ``None`` when the people close
    every way (the caller keeps the world's plan). A way round people that brushes the walls
    (margin 0, which the world's plan takes only through a narrow door) is none: in 20
    crowd episodes it traded people contacts for wall collisions (4)."""
    start, goal = np.asarray(start_xy[:2], dtype=float), np.asarray(goal_xy[:2], dtype=float)
    discs = people_discs(people_xy, start, goal, keep_off_m)
    for margin in [m for m in margins_m if m > 0] or margins_m[:1]:
        path = _plan(world, start, goal, robot_radius_m + margin, discs)
        if path is not None:
            return path
    return None
