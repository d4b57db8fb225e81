"""Shortest collision-free paths in a world: the optimal path of SPL, and the detour filter of
the start-goal pairs of a kind.

The robot is a disc of ``robot_radius_m``; for a rectangular footprint callers pass the
circumscribed radius (``Footprint.bounding_radius_m``): a path that disc follows is free in any
heading, which a differential-drive robot turning in a doorway needs, and the sampler and the
engine check starts with the same radius. The world's clearance at the cell centres is
computed once per (world, resolution) (``clearance_grid``, shared by the radii) and becomes
an occupancy grid once per (world, radius, resolution): a cell is free when its centre lies
inside the bounds with ``clearance >= robot_radius_m`` (the obstacles inflated by the
radius). The search is Dijkstra on the 8-connected grid with corner cutting excluded (a
diagonal step needs both orthogonal neighbours free), vectorised by buckets one cell wide:
every step costs at least one cell, so all cells of a bucket are final at once
(``grid_search`` over ``grid_steps``, which the bridge's mapless explorer runs on the grid of
its own scans too). The cell path is then pulled taut by line of sight on the grid
(``taut_path``), which removes the 8-connected grid's bias (up to 8 % on a straight line at
22.5°).

Accuracy: the taut path bends at cell centres next to the inflated obstacles, so it lies within
about one cell of the true shortest path's bends; in open space it is the straight line. A start
or goal whose own cell is blocked (a goal closer to a wall than the radius, which the engine
allows) is joined to the nearest free cell by a straight segment that counts in the length.
"""

from __future__ import annotations

import math
from collections import OrderedDict
from collections.abc import Sequence

import numpy as np

from pic4rl_base.errors import require

from .taut_path import pull_taut
from .worlds.spec import WorldSpec

_SQRT2 = math.sqrt(2.0)
#: Octile over Euclidean length, at most (a straight line at 22.5°): the grid search's bound.
_OCTILE_BIAS = math.sqrt(4.0 - 2.0 * _SQRT2)
_CHUNK = 8192  # cell centres per clearance call: bounds the (points x obstacles) arrays
_CACHE = 256  # lengths and paths kept per planner (a query is asked again: the facts,
#               the runs of one pair)
RESOLUTION_M = 0.05  # the plans' grid cell, unless a caller names another



def segment_samples(a: np.ndarray, b: np.ndarray, step_m: float) -> tuple[np.ndarray,
                                                                          np.ndarray]:
    """Points every ``step_m`` or closer along each segment a[i]-b[i] (both (n, 2), or one a
    single point), ends included, and where each segment's points start: a per-point test
    reduced with ``np.logical_and.reduceat(ok, starts)`` says which segments pass whole."""
    a, b = np.broadcast_arrays(np.atleast_2d(a), np.atleast_2d(b))
    counts = np.ceil(np.hypot(*(b - a).T) / step_m).astype(np.int64) + 1
    seg = np.repeat(np.arange(len(a)), counts)
    starts = np.cumsum(counts) - counts
    t = (np.arange(counts.sum()) - starts[seg]) / np.maximum(counts - 1, 1)[seg]
    return a[seg] + (b[seg] - a[seg]) * t[:, None], starts


_CLEARANCES: OrderedDict[tuple[int, float], tuple[WorldSpec, np.ndarray]] = OrderedDict()


def clearance_grid(world: WorldSpec, resolution_m: float) -> np.ndarray:
    """The world's clearance (m) at the centres of its cells of ``resolution_m`` (ny x nx,
    read-only), computed once per (world, resolution) and kept (a few): the planners of one
    world for different radii (the global plan's margins, line of sight, the sampler's
    shortest path) threshold the same field, its most costly part."""
    key = (id(world), float(resolution_m))
    found = _CLEARANCES.get(key)
    if found is not None and found[0] is world:
        _CLEARANCES.move_to_end(key)
        return found[1]
    xmin, ymin, xmax, ymax = world.bounds
    nx = max(1, int((xmax - xmin) / resolution_m + 1e-9))
    ny = max(1, int((ymax - ymin) / resolution_m + 1e-9))
    xs = xmin + (np.arange(nx) + 0.5) * resolution_m
    ys = ymin + (np.arange(ny) + 0.5) * resolution_m
    centres = np.stack(np.meshgrid(xs, ys), axis=-1).reshape(-1, 2)
    clear = np.concatenate([world.clearance(centres[i:i + _CHUNK])
                            for i in range(0, len(centres), _CHUNK)]).reshape(ny, nx)
    clear.setflags(write=False)
    _CLEARANCES[key] = (world, clear)
    if len(_CLEARANCES) > 4:
        _CLEARANCES.popitem(last=False)
    return clear


class PathPlanner:
    """Shortest-path lengths between points of one world for a disc robot; build it once
    (tens of milliseconds), query it per episode. The last queries' lengths and paths are
    kept."""

    def __init__(self, world: WorldSpec, *, robot_radius_m: float,
                 resolution_m: float = RESOLUTION_M) -> None:
        require(math.isfinite(robot_radius_m) and robot_radius_m >= 0, "paths.robot_radius_m",
                robot_radius_m, "a finite radius >= 0 m")
        require(math.isfinite(resolution_m) and resolution_m > 0, "paths.resolution_m",
                resolution_m, "a positive cell size in m")
        self.world, self.robot_radius_m, self.resolution_m = world, robot_radius_m, resolution_m
        clear = clearance_grid(world, resolution_m)
        self.ny, self.nx = clear.shape
        clear = clear.ravel()
        # One blocked cell of padding all round: neighbours never leave the array.
        self.width = self.nx + 2
        free = np.zeros((self.ny + 2, self.width), dtype=bool)
        free[1:-1, 1:-1] = (clear >= robot_radius_m).reshape(self.ny, self.nx)
        self.free = free.ravel()
        # Clearance at the centres for line of sight, interpolated: clipped where it no longer
        # matters (no inf), negative outside the outermost centres.
        top = robot_radius_m + 2.0 * resolution_m
        self._clear = np.full(free.shape, -top)
        self._clear[1:-1, 1:-1] = np.minimum(clear, top).reshape(self.ny, self.nx)
        self._steps = grid_steps(free)
        self._free_cells = np.flatnonzero(self.free)
        self._cache: OrderedDict[tuple[float, ...], float] = OrderedDict()
        self._paths: OrderedDict[tuple[float, ...], np.ndarray | None] = OrderedDict()

    # -- points and cells -------------------------------------------------------------------

    def _cell(self, xy: np.ndarray) -> np.ndarray:
        """Flat padded index of the cell holding each point of ``xy`` (n, 2), clipped inside."""
        xmin, ymin = self.world.bounds[:2]
        ix = np.clip(np.floor((xy[:, 0] - xmin) / self.resolution_m), 0, self.nx - 1)
        iy = np.clip(np.floor((xy[:, 1] - ymin) / self.resolution_m), 0, self.ny - 1)
        return ((iy + 1) * self.width + ix + 1).astype(np.int64)

    def _centre(self, cells: np.ndarray) -> np.ndarray:
        iy, ix = np.divmod(np.asarray(cells), self.width)
        xmin, ymin = self.world.bounds[:2]
        return np.stack([xmin + (ix - 0.5) * self.resolution_m,
                         ymin + (iy - 0.5) * self.resolution_m], axis=-1)

    def _snap(self, xy: np.ndarray, what: str) -> int:
        """The point's cell, or the free cell whose centre is nearest (-1: none free)."""
        xmin, ymin, xmax, ymax = self.world.bounds
        if not (xmin <= xy[0] <= xmax and ymin <= xy[1] <= ymax):
            raise ValueError(f"paths: {what} ({xy[0]:.3f}, {xy[1]:.3f}) is outside the bounds "
                             f"{self.world.bounds} of world {self.world.name!r}")
        cell = int(self._cell(xy[None])[0])
        if self.free[cell] or not len(self._free_cells):
            return cell if self.free[cell] else -1
        d = np.hypot(*(self._centre(self._free_cells) - xy).T)
        return int(self._free_cells[int(np.argmin(d))])

    def clearance_at(self, xy: np.ndarray) -> np.ndarray:
        """Clearance (m) at points ``xy`` (n, 2), interpolated bilinearly between cell centres
        (exact at the centres; clipped to a little more than the radius)."""
        xmin, ymin = self.world.bounds[:2]
        fx = np.clip((xy[:, 0] - xmin) / self.resolution_m + 0.5, 0.0, self.nx + 0.999999)
        fy = np.clip((xy[:, 1] - ymin) / self.resolution_m + 0.5, 0.0, self.ny + 0.999999)
        ix, iy = fx.astype(np.int64), fy.astype(np.int64)
        wx, wy = fx - ix, fy - iy
        c = self._clear
        return ((c[iy, ix] * (1 - wx) + c[iy, ix + 1] * wx) * (1 - wy)
                + (c[iy + 1, ix] * (1 - wx) + c[iy + 1, ix + 1] * wx) * wy)

    def visible(self, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        """Whether the disc can move straight from each point of ``a`` to the same row of
        ``b`` (both (n, 2), or one a single point): the interpolated clearance is at least the
        radius every half cell along the way."""
        pts, starts = segment_samples(a, b, 0.5 * self.resolution_m)
        ok = self.clearance_at(pts) >= self.robot_radius_m - 1e-9
        return np.logical_and.reduceat(ok, starts)

    # -- queries --------------------------------------------------------------------------

    def length(self, start_xy: Sequence[float], goal_xy: Sequence[float], *,
               max_length_m: float = math.inf) -> float:
        """The shortest collision-free path's length (m) from ``start_xy`` to ``goal_xy``;
        ``math.inf`` when there is none, or (with ``max_length_m``) none that short."""
        # Exact coordinates: a key rounded to the mm once answered a pair 0.06 mm apart with
        # the length of another (found by the open-space property test).
        key = (float(start_xy[0]), float(start_xy[1]), float(goal_xy[0]), float(goal_xy[1]))
        if key in self._cache:
            self._cache.move_to_end(key)
            found = self._cache[key]
            return found if found <= max_length_m else math.inf
        points = self.path(start_xy, goal_xy, max_length_m=max_length_m)
        if points is None:
            return math.inf  # longer than max_length_m (not cached: unknown how much)
        found = (float(np.hypot(*np.diff(points, axis=0).T).sum()) if len(points)
                 else math.inf)
        self._cache[key] = found
        if len(self._cache) > _CACHE:
            self._cache.popitem(last=False)
        return found if found <= max_length_m else math.inf

    def path(self, start_xy: Sequence[float], goal_xy: Sequence[float], *,
             max_length_m: float = math.inf) -> np.ndarray | None:
        """The taut path's points (k, 2) from start to goal; empty (0, 2) when there is no
        path, ``None`` when the search stopped at ``max_length_m`` without reaching the goal.
        ``ValueError`` for a point outside the world's bounds. The last queries' paths are
        kept (a copy is returned): the runs of one start-goal pair plan the same path."""
        key = (float(start_xy[0]), float(start_xy[1]), float(goal_xy[0]), float(goal_xy[1]),
               float(max_length_m))
        if key in self._paths:
            self._paths.move_to_end(key)
        else:
            self._paths[key] = self._search(start_xy, goal_xy, max_length_m)
            if len(self._paths) > _CACHE:
                self._paths.popitem(last=False)
        found = self._paths[key]
        return None if found is None else found.copy()

    def _search(self, start_xy: Sequence[float], goal_xy: Sequence[float],
                max_length_m: float) -> np.ndarray | None:
        start = np.array(start_xy[:2], dtype=float)
        goal = np.array(goal_xy[:2], dtype=float)
        s, g = self._snap(start, "start"), self._snap(goal, "goal")
        if s < 0 or g < 0:
            return np.zeros((0, 2))
        fits = self.clearance_at(np.array([start, goal])) >= self.robot_radius_m
        fits &= self.free[self._cell(np.array([start, goal]))]
        if fits.all() and self.visible(start, goal)[0]:
            return np.array([start, goal])  # in sight: the straight line is the shortest path
        limit = max_length_m * _OCTILE_BIAS / self.resolution_m + 4.0  # cells, loose
        cells = grid_search(self.free, self._steps, s, g, limit)
        if cells is None or not len(cells):
            return cells if cells is None else np.zeros((0, 2))
        centres = list(self._centre(cells))
        # An end where the disc fits replaces its cell's centre; another is joined to its
        # (snapped) cell by a straight segment that counts in the length.
        first = start if fits[0] else centres[0]
        last = goal if fits[1] else centres[-1]
        taut = list(pull_taut(np.array([first, *centres[1:-1], last]), self.visible,
                               corner_radius_m=max(self.robot_radius_m, self.resolution_m),
                               step_m=self.resolution_m))
        return np.array(([] if fits[0] else [start]) + taut + ([] if fits[1] else [goal]))

#: A grid move: its flat offset, its cost (cells) and the flat mask of cells it may leave.
Step = tuple[int, float, np.ndarray]


def grid_steps(free: np.ndarray) -> list[Step]:
    """The 8 moves on the padded occupancy grid ``free`` (h x w, its border blocked), with
    corner cutting excluded (a diagonal move needs both orthogonal neighbours free)."""
    steps = []
    h, w = free.shape
    for dy in (-1, 0, 1):
        for dx in (-1, 0, 1):
            if dx == dy == 0:
                continue
            ok = np.zeros_like(free)
            inner = (slice(1, h - 1), slice(1, w - 1))
            moved = (slice(1 + dy, h - 1 + dy), slice(1 + dx, w - 1 + dx))
            allowed = free[inner] & free[moved]
            if dx and dy:  # no corner cutting: both orthogonal neighbours free
                allowed &= free[1 + dy:h - 1 + dy, 1:w - 1] & free[1:h - 1, 1 + dx:w - 1 + dx]
            ok[inner] = allowed
            steps.append((dy * w + dx, _SQRT2 if dx and dy else 1.0, ok.ravel()))
    return steps


def grid_search(free: np.ndarray, steps: list[Step], s: int, g: int,
                limit_cells: float = math.inf,
                weights: np.ndarray | None = None) -> np.ndarray | None:
    """Cells of a shortest 8-connected path from ``s`` to ``g`` (flat indices of the padded
    grid whose flat mask is ``free`` and moves ``steps``: ``grid_steps``); empty when none,
    ``None`` when the distance exceeds ``limit_cells``. Dijkstra by buckets one cell wide; a
    move into a cell costs its length times the cell's flat ``weights`` (each >= 1, so that
    the buckets stay exact; ``None``: 1)."""
    dist = np.full(free.size, np.inf)
    parent = np.full(free.size, -1, dtype=np.int64)
    dist[s] = 0.0
    buckets: dict[int, list[np.ndarray]] = {0: [np.array([s], dtype=np.int64)]}
    while buckets:
        bucket = min(buckets)
        if bucket > limit_cells:
            return None
        front = np.unique(np.concatenate(buckets.pop(bucket)))
        front = front[dist[front] >= bucket]  # drop cells settled in an earlier bucket
        if dist[g] < bucket + 1:
            break
        moves = [(front[m] + off, np.full(int(m.sum()), cost), front[m])
                 for off, cost, ok in steps if (m := ok[front]).any()]
        if not moves:
            continue
        nb, nd, par = (np.concatenate(x) for x in zip(*moves))
        nd = dist[par] + (nd if weights is None else nd * weights[nb])
        better = nd < dist[nb]
        if not better.any():
            continue
        nb, nd, par = nb[better], nd[better], par[better]
        order = np.lexsort((nd, nb))  # per cell, its shortest offer first
        nb, nd, par = nb[order], nd[order], par[order]
        first = np.r_[True, nb[1:] != nb[:-1]]
        nb, nd, par = nb[first], nd[first], par[first]
        dist[nb], parent[nb] = nd, par
        which = nd.astype(np.int64)
        for b in np.unique(which):
            buckets.setdefault(int(b), []).append(nb[which == b])
    if not math.isfinite(dist[g]):
        return np.zeros(0, dtype=np.int64)
    cells = [g]
    while cells[-1] != s:
        cells.append(int(parent[cells[-1]]))
    return np.array(cells[::-1], dtype=np.int64)


_PLANNERS: OrderedDict[tuple[int, float, float], PathPlanner] = OrderedDict()


def planner_for(world: WorldSpec, *, robot_radius_m: float,
                resolution_m: float = RESOLUTION_M) -> PathPlanner:
    """The planner of (world, radius, resolution), built on first use and kept (a few)."""
    key = (id(world), float(robot_radius_m), float(resolution_m))
    found = _PLANNERS.get(key)
    if found is None or found.world is not world:
        found = PathPlanner(world, robot_radius_m=robot_radius_m, resolution_m=resolution_m)
        _PLANNERS[key] = found
        if len(_PLANNERS) > 8:
            _PLANNERS.popitem(last=False)
    return found


def shortest_path_length(world: WorldSpec, start_xy: Sequence[float], goal_xy: Sequence[float],
                         *, robot_radius_m: float, resolution_m: float = RESOLUTION_M) -> float:
    """Length (m) of the shortest path a disc of ``robot_radius_m`` can follow from
    ``start_xy`` to ``goal_xy`` in ``world``; ``math.inf`` when there is none."""
    planner = planner_for(world, robot_radius_m=robot_radius_m, resolution_m=resolution_m)
    return planner.length(start_xy, goal_xy)


#: Clearances (m) a global plan keeps beyond the robot's circumscribed radius, tried in turn
#: until one leaves a path: a path followed with a tracking error of a few centimetres still
#: clears door frames and the env's collision tolerance. With the Jackal, 0 gave 9 collisions
#: in 50 test-kind pairs and 0.064 (obstacles inflated by 0.40 m) none; a small round robot
#: (the Burger) needed more than 0.064, as it has no slack between footprint and circle.
PLAN_MARGINS_M = (0.15, 0.064, 0.0)


def plan_path(world: WorldSpec, start_xy: Sequence[float], goal_xy: Sequence[float], *,
              robot_radius_m: float, margins_m: Sequence[float] = PLAN_MARGINS_M) -> np.ndarray:
    """A global plan (k × 2, m) from ``start_xy`` to ``goal_xy`` that keeps the first of
    ``margins_m`` beyond ``robot_radius_m`` from every obstacle with which a path exists (a
    door narrower than that needs a smaller one); empty (0 × 2) when there is none."""
    for margin in margins_m:
        path = planner_for(world, robot_radius_m=robot_radius_m + margin).path(start_xy, goal_xy)
        if path is not None and len(path):
            return path
    return np.zeros((0, 2))
