"""The mapless explorer's plan: a shortest path on an occupancy grid of the robot's own scans.

What the explorer baseline (``pic4rl_bridge.baselines.explorer``) follows and what a goToPose
observation with ``goal_input: explorer`` points along: both read only the scan (or the depth
image's pseudo-scan) and the pose, never the world, so the plan is the same in process,
through the sim node over ROS 2 and on a real robot. Each frame's returns mark an occupancy
grid (``pic4rl_bridge.perception.occupancy``: unknown is free, as nav2's rolling costmap
with ``track_unknown_space: false`` or D* Lite in unknown terrain plan optimistically). The
plan is the shortest path on that grid with the obstacles inflated by the footprint's
circumscribed radius plus ``margin_m`` (``narrow_margin_m`` at a cost when nothing else
passes: a narrow door), by ``pic4rl_sim.engine.paths``' vectorised grid search and taut pull.
It is kept until a newly seen obstacle blocks it or the robot is ``replan_distance_m`` off it:
a plan made anew at every step would flip between the two ways round an obstacle, and a plan
that flips is one neither a follower nor a student can keep to.

The search runs on a window of the grid (what was seen, the robot and the goal, with
``_PAD_CELLS`` round them), on a clearance field (distance to the nearest occupied cell,
capped) that new cells update in place; the window is rebuilt when something leaves it. With
``clear_free`` each scan first frees the cells its beams pass through (``OccupancyGrid.
clear_scan``): the field is recomputed round them, and the plan kept (a freed way is taken at
the next replan, so a walking person's trail neither blocks the plan nor makes it flip).
"""

from __future__ import annotations

import math

import numpy as np

from pic4rl_base.geometry import project
from pic4rl_sim.engine.paths import grid_search, grid_steps, segment_samples
from pic4rl_sim.engine.taut_path import pull_taut

from ..perception.occupancy import GRID_RESOLUTION_M, OccupancyGrid, sensed_scans
from ..readings.frame import SensorFrame
from ..robot_info import RobotInfo
from ..settings.baselines import ExplorerConfig

_PAD_CELLS = 60  # free cells round the window's content (3 m at 5 cm)
#: A cell with less clearance than the full margin (but the narrow one) costs this many times
#: its length: the plan squeezes through a narrow door only when going round costs more.
_NARROW_COST = 4.0
_SNAP_CELLS = 20  # a blocked start or goal joins the nearest free cell this near (1 m)
#: A plan hugs its inflated obstacles, and a wall seen again from elsewhere marks cells a cell
#: nearer (its face on a cell boundary, the beams' noise): a plan is blocked only when a new
#: cell leaves less than the narrow margin, less this, not at each such shave (which replanned
#: at every step along a corridor, flipping between two doors).
_SHAVE_M = 0.025


class _Clearance:
    """Distance (m) from each cell centre of a window of the grid to the nearest occupied
    cell's boundary (about: centre distance minus half a cell), capped at ``cap_m``."""

    def __init__(self, cells: np.ndarray, lo: np.ndarray, hi: np.ndarray, resolution_m: float,
                 cap_m: float) -> None:
        self.lo, self.hi, self.res, self.cap_m = lo, hi, resolution_m, cap_m
        w, h = (hi - lo).astype(int)
        self.clear = np.full((h, w), cap_m, dtype=np.float32)
        reach = int(math.ceil(cap_m / resolution_m + 0.5))
        dx, dy = np.meshgrid(np.arange(-reach, reach + 1), np.arange(-reach, reach + 1))
        d = np.hypot(dx, dy).ravel() * resolution_m - 0.5 * resolution_m
        near = d < cap_m
        self._offsets = np.column_stack((dx.ravel()[near], dy.ravel()[near]))
        self._dist = np.maximum(d[near], 0.0).astype(np.float32)
        self.add(cells)

    def holds(self, idx: np.ndarray) -> bool:
        """Whether every cell of ``idx`` (k, 2) lies inside the window."""
        return bool(((idx >= self.lo) & (idx < self.hi)).all())

    def add(self, cells: np.ndarray) -> None:
        """Occupied ``cells`` (k, 2, world indices) lower the clearance round them."""
        if not len(cells):
            return
        h, w = self.clear.shape
        local = cells - self.lo
        for (ox, oy), dist in zip(self._offsets, self._dist):
            x, y = local[:, 0] + ox, local[:, 1] + oy
            ok = (x >= 0) & (x < w) & (y >= 0) & (y < h)
            x, y = x[ok], y[ok]
            self.clear[y, x] = np.minimum(self.clear[y, x], dist)

    def remove(self, freed: np.ndarray, cells: np.ndarray) -> None:
        """``freed`` cells (k, 2) are no longer occupied, ``cells`` (the grid's, all occupied):
        the clearance within the cap of the freed ones is made anew from the occupied cells
        near them, as a new field would hold it."""
        if not len(freed):
            return
        h, w = self.clear.shape
        reach = int(np.abs(self._offsets).max()) if len(self._offsets) else 0
        lo = np.maximum(freed.min(axis=0) - self.lo - reach, 0)
        hi = np.minimum(freed.max(axis=0) - self.lo + reach + 1, (w, h))
        self.clear[lo[1]:hi[1], lo[0]:hi[0]] = self.cap_m
        local = cells - self.lo
        near = ((local >= lo - reach) & (local < hi + reach)).all(axis=1)
        self.add(cells[near])

    def at(self, xy: np.ndarray) -> np.ndarray:
        """The clearance of the cells of points ``xy`` (n, 2, m); 0 outside the window."""
        local = np.floor(np.asarray(xy) / self.res).astype(np.int64) - self.lo
        h, w = self.clear.shape
        ok = (local[:, 0] >= 0) & (local[:, 0] < w) & (local[:, 1] >= 0) & (local[:, 1] < h)
        out = np.zeros(len(local), dtype=np.float32)
        out[ok] = self.clear[local[ok, 1], local[ok, 0]]
        return out

    def visible(self, a: np.ndarray, b: np.ndarray, need_m: float) -> np.ndarray:
        """Whether each segment a[i]-b[i] (or from one point) keeps ``need_m`` of clearance
        at every half cell."""
        pts, starts = segment_samples(a, b, 0.5 * self.res)
        return np.logical_and.reduceat(self.at(pts) >= need_m, starts)


class ExplorerPlan:
    """The explorer's plan for goToPose (see the module's docstring): ``update`` marks a
    frame's returns and gives the plan with the robot's place on it; ``reset`` forgets the
    grid."""

    def __init__(self, robot: RobotInfo, config: ExplorerConfig | None = None, *,
                 sensors: tuple[str, ...] = (), depth_rows: int = 0) -> None:
        self.robot, self.config = robot, config or ExplorerConfig()
        #: what the grid marks (``sensed_scans``): the agent's observed sensors, fused
        self.sensors, self.depth_rows = tuple(sensors), depth_rows
        self.radius_m = robot.footprint.bounding_radius_m
        self.grid = OccupancyGrid(GRID_RESOLUTION_M)
        self.plans = 0  # paths planned since the plan was made
        self.reset()

    def reset(self) -> None:
        """Forget the grid and the plan (a new episode)."""
        self.grid.reset()
        self._field: _Clearance | None = None
        self._path: np.ndarray | None = None
        self._goal: tuple[float, float] | None = None
        self._need_m = 0.0
        self._samples = np.zeros((0, 2))
        self._sample_s = self._sample_ok = np.zeros(0)
        self._seen: tuple[int, object] | None = None

    @property
    def path(self) -> np.ndarray | None:
        """The plan (k × 2, m), or ``None`` before the first frame."""
        return self._path

    def observe(self, frame: SensorFrame) -> np.ndarray:
        """Mark ``frame``'s returns (once per frame; with ``clear_free`` after freeing what its
        beams pass through); the cells new to the grid (k, 2)."""
        key = (frame.stamp_ns, frame.pose)
        scans = sensed_scans(frame, self.robot, self.sensors, self.depth_rows)
        if not scans or self._seen == key:
            return np.zeros((0, 2), dtype=np.int64)
        self._seen = key
        if self.config.clear_free:
            freed = np.concatenate([self.grid.clear_scan(scan, frame.pose) for scan in scans])
        new = np.concatenate([self.grid.mark_scan(scan, frame.pose) for scan in scans])
        if self.config.clear_free and self._field is not None and len(freed):
            if self._field.holds(freed):
                self._field.remove(freed, self.grid.cells)
            else:
                self._field = None
        if self._field is not None and len(new):
            if self._field.holds(new):
                self._field.add(new)
            else:
                self._field = None
        return new

    def update(self, frame: SensorFrame,
               goal: tuple[float, float] | None = None) -> tuple[np.ndarray, float]:
        """The plan to ``goal`` (default: the frame's) after ``frame`` (marked, planned anew
        when needed) and the arc length (m) of the robot's projection on it. Calling it twice
        with one frame changes nothing."""
        goal = goal or frame.goal
        if goal is None:
            raise ValueError("ExplorerPlan: the frame has no goal")
        new = self.observe(frame)
        xy = np.array([frame.pose.x, frame.pose.y])
        goal = (float(goal[0]), float(goal[1]))
        path = self._path
        s = offset = 0.0
        if path is not None and len(path) > 1:
            s, offset = project(path, (float(xy[0]), float(xy[1])))
        if (path is None or goal != self._goal or abs(offset) > self.config.replan_distance_m
                or self._field is None or not self._field.holds(self._cell(np.array([xy])))
                or (len(new) and self._blocked(s))):
            path = self._replan(xy, goal)
            s = 0.0
        return path, s

    def visible(self, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        """Whether each segment a-b[i] keeps the plan's clearance (after ``update``)."""
        assert self._field is not None  # made by update
        return self._field.visible(a, b, self._need_m)

    # -- planning -----------------------------------------------------------------------------

    def _cell(self, xy: np.ndarray) -> np.ndarray:
        return np.floor(xy / self.grid.resolution_m).astype(np.int64)

    def _blocked(self, s: float) -> bool:
        """Whether a newly seen obstacle took the clearance of the plan ahead (``s`` on)."""
        if self._field is None or not len(self._samples):
            return True
        ahead = self._sample_ok & (self._sample_s >= s - self.grid.resolution_m)
        return bool((ahead & (self._field.at(self._samples) < self._need_m - _SHAVE_M)).any())

    def _make_field(self, xy: np.ndarray, goal: tuple[float, float],
                    pad: int = _PAD_CELLS) -> _Clearance:
        cells = self.grid.cells
        ends = self._cell(np.array([xy, goal]))
        both = np.concatenate((cells, ends)) if len(cells) else ends
        lo, hi = both.min(axis=0) - pad, both.max(axis=0) + 1 + pad
        cap = self.radius_m + self.config.margin_m + 0.1
        return _Clearance(cells, lo, hi, self.grid.resolution_m, cap)

    def _replan(self, xy: np.ndarray, goal: tuple[float, float]) -> np.ndarray:
        self.plans += 1
        if self._field is None or not self._field.holds(self._cell(np.array([xy, goal]))):
            self._field = self._make_field(xy, goal)
        field = self._field
        need = self.radius_m + min(self.config.margin_m, self.config.narrow_margin_m)
        path = self._search(field, xy, np.array(goal), need)
        if path is None:  # the way round may pass beyond the window: a wider one
            self._field = field = self._make_field(xy, goal, 4 * _PAD_CELLS)
            path = self._search(field, xy, np.array(goal), need)
        squeeze = self.config.squeeze_radius_m
        if path is None and 0 < squeeze < need:  # a gap only the footprint, aligned, fits
            need = squeeze
            path = self._search(field, xy, np.array(goal), need)
        if path is None:  # no way round what was seen: straight on, the walls will tell
            path = np.array([xy, goal])
        self._path, self._goal, self._need_m = path, goal, need
        seg = np.hypot(*np.diff(path, axis=0).T)
        s = np.arange(0.0, float(seg.sum()), 0.5 * field.res)
        cum = np.r_[0.0, np.cumsum(seg)]
        self._samples = np.column_stack([np.interp(s, cum, path[:, k]) for k in (0, 1)])
        self._sample_s = s
        self._sample_ok = field.at(self._samples) >= need
        return path

    def _search(self, field: _Clearance, xy: np.ndarray, goal: np.ndarray,
                need_m: float) -> np.ndarray | None:
        """The taut shortest path from ``xy`` to ``goal`` keeping ``need_m`` of clearance, a
        cell with less than the full margin costing ``_NARROW_COST`` times its length (its
        ends joined to the nearest free cells when they have less); ``None``: none."""
        free = np.zeros((field.clear.shape[0] + 2, field.clear.shape[1] + 2), dtype=bool)
        free[1:-1, 1:-1] = field.clear >= need_m
        wide_m = self.radius_m + self.config.margin_m
        weights = np.ones(free.shape)
        weights[1:-1, 1:-1][field.clear < wide_m] = _NARROW_COST
        width = free.shape[1]
        ends = []
        for point in (xy, goal):
            cell = self._snap(free, self._cell(point) - field.lo + 1)
            if cell is None:
                return None
            ends.append(cell)
        (sx, sy), (gx, gy) = ends
        cells = grid_search(free.ravel(), grid_steps(free), sy * width + sx, gy * width + gx,
                            weights=weights.ravel())
        if cells is None or not len(cells):
            return None
        iy, ix = np.divmod(cells, width)
        centres = (np.column_stack((ix, iy)) - 1 + field.lo + 0.5) * field.res
        pts = np.vstack((xy, centres, goal))
        taut = pull_taut(pts, lambda a, b: field.visible(a, b, wide_m),
                         corner_radius_m=max(wide_m, field.res), step_m=field.res)
        return np.asarray(taut)

    @staticmethod
    def _snap(free: np.ndarray, cell: np.ndarray) -> tuple[int, int] | None:
        """``cell`` (x, y of the padded window) if free, else the nearest free cell within
        ``_SNAP_CELLS``; ``None`` when none."""
        x, y = int(cell[0]), int(cell[1])
        if free[y, x]:
            return x, y
        y0, x0 = max(y - _SNAP_CELLS, 0), max(x - _SNAP_CELLS, 0)
        near = free[y0:y + _SNAP_CELLS + 1, x0:x + _SNAP_CELLS + 1]
        iy, ix = np.nonzero(near)
        if not len(iy):
            return None
        best = int(np.argmin((iy + y0 - y) ** 2 + (ix + x0 - x) ** 2))
        return int(ix[best] + x0), int(iy[best] + y0)
