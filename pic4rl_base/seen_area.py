"""The floor a range sensor has seen: its scans integrated into a world-fixed grid (pure numpy).

Area seen is what an exploring robot is judged by, from its bags (``pic4rl_metrics``' coverage
columns) and, for a reward of newly seen area, live; one routine serves both, so it lives in
the base. A cell (``resolution_m`` wide, indices ``floor(xy / resolution_m)``) is seen by a scan
when its centre lies inside the scan's outline: the ends of neighbouring beams joined by
straight edges (a polygon, exact for walls), a beam without neighbours seen to half the scan's
median beam spacing either side (so a sensor's field of view ends at its outer beams); or when
the centre is within one cell of the sensor. The grid grows
to hold what is seen; its memory is that of the area's bounding box (one byte a cell).

A robot's scans are counted in time order by ``SeenTrack``, thinned: a scan from where the last
one was adds next to nothing, so one is integrated only once the sensor has moved
``MOVE_CELLS`` cells, turned ``TURN_RAD`` or ``PERIOD_S`` has passed, which bounds the work for
a long log or a robot standing still. The bags' metric and the live explore task both count
with it, from the same beams (``beam_reach``), so a coverage target the task saw reached reads
the same from the episode's bag.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from .geometry import wrap_angle

#: Neighbouring beams at most this many median spacings apart are joined by a straight edge.
GAP = 1.5
#: ``SeenTrack`` integrates a scan after the sensor moved this many cells, turned this far
#: (rad), or this long (s) passed since the last scan integrated: a time to a share of the
#: area is late by at most that much (0.4 s at 0.5 m/s).
MOVE_CELLS = 4
TURN_RAD = math.radians(10.0)
PERIOD_S = 1.0


def beam_reach(ranges: np.ndarray, range_min: Any, range_max: Any) -> np.ndarray:
    """Per beam, how far it saw (m): its return when finite and at least ``range_min``
    (capped at ``range_max``), ``range_max`` for ``+inf`` (nothing within range: free that
    far), NaN for NaN, ``-inf`` or a return closer than ``range_min``. The limits broadcast
    against ``ranges`` (a scan's scalars, or a column per scan)."""
    ranges = np.asarray(ranges, dtype=float)
    valid = np.isfinite(ranges) & (ranges >= range_min)
    reach = np.where(valid, np.minimum(ranges, range_max), np.nan)
    return np.where(np.isposinf(ranges), np.broadcast_to(range_max, ranges.shape), reach)


class SeenGrid:
    """Cells seen so far; ``add`` integrates one scan and returns how many cells it added."""

    def __init__(self, resolution_m: float) -> None:
        if not resolution_m > 0:
            raise ValueError(f"SeenGrid: resolution_m={resolution_m!r}; expected > 0")
        self.resolution_m = float(resolution_m)
        self.count = 0
        self._seen = np.zeros((0, 0), dtype=bool)  # [row = y index, col = x index]
        self._origin = np.zeros(2, dtype=np.int64)  # (x, y) index of cell [0, 0]

    @property
    def area_m2(self) -> float:
        return self.count * self.resolution_m**2

    @property
    def bounds_m(self) -> tuple[float, float, float, float]:
        """(xmin, ymin, xmax, ymax) (m) of the cells the grid holds (seen or not); all 0 when
        empty."""
        rows, cols = self._seen.shape
        lo = self._origin * self.resolution_m
        return (float(lo[0]), float(lo[1]), float(lo[0] + cols * self.resolution_m),
                float(lo[1] + rows * self.resolution_m))

    def seen_at(self, xy: np.ndarray) -> np.ndarray:
        """Whether the cell of each point of ``xy`` (n, 2, m) has been seen."""
        idx = np.floor(np.asarray(xy, dtype=float) / self.resolution_m).astype(np.int64)
        local = idx - self._origin
        rows, cols = self._seen.shape
        inside = (local[:, 0] >= 0) & (local[:, 0] < cols) & (local[:, 1] >= 0) & (
            local[:, 1] < rows)
        out = np.zeros(len(local), dtype=bool)
        out[inside] = self._seen[local[inside, 1], local[inside, 0]]
        return out

    def add(self, x: float, y: float, yaw: float, bearing: np.ndarray, reach_m: np.ndarray) -> int:
        """Integrate one scan from a sensor at ``(x, y)`` heading ``yaw`` (m, rad): per beam,
        its bearing from the heading (rad) and how far it saw (m; NaN or <= 0: nothing)."""
        bearing, reach = np.asarray(bearing, dtype=float), np.asarray(reach_m, dtype=float)
        ok = np.isfinite(bearing) & np.isfinite(reach) & (reach > 0)
        if not ok.any():
            return 0
        bearing, reach = wrap_angle(bearing[ok]), reach[ok]
        order = np.argsort(bearing)
        bearing, reach = bearing[order], reach[order]
        res = self.resolution_m
        ends_x, ends_y = x + reach * np.cos(yaw + bearing), y + reach * np.sin(yaw + bearing)
        low = np.floor(np.array([min(ends_x.min(), x), min(ends_y.min(), y)]) / res)
        high = np.floor(np.array([max(ends_x.max(), x), max(ends_y.max(), y)]) / res)
        low, high = low.astype(np.int64), high.astype(np.int64)
        self._fit(low, high)
        r0, c0 = low[1] - self._origin[1], low[0] - self._origin[0]
        window = self._seen[r0:r0 + high[1] - low[1] + 1, c0:c0 + high[0] - low[0] + 1]
        rows, cols = np.nonzero(~window)  # only the cells not seen yet are tested
        dx = (cols + low[0] + 0.5) * res - x
        dy = (rows + low[1] + 0.5) * res - y
        dist = np.hypot(dx, dy)
        rel = wrap_angle(np.arctan2(dy, dx) - yaw)
        seen = (dist <= res) | (dist <= _limit(bearing, reach, rel))
        window[rows[seen], cols[seen]] = True
        new = int(np.count_nonzero(seen))
        self.count += new
        return new

    def _fit(self, low: np.ndarray, high: np.ndarray) -> None:
        """Grow the grid (doubling, so growth costs little) to hold indices ``low..high``."""
        rows, cols = self._seen.shape
        top = self._origin + np.array([cols, rows])
        if rows and (low >= self._origin).all() and (high < top).all():
            return
        if not rows:
            new_low, new_top = low, high + 1
        else:
            size = top - self._origin
            new_low = np.minimum(low, self._origin - np.where(low < self._origin, size, 0))
            new_top = np.maximum(high + 1, top + np.where(high >= top, size, 0))
        grown = np.zeros((int(new_top[1] - new_low[1]), int(new_top[0] - new_low[0])), dtype=bool)
        r0, c0 = self._origin[1] - new_low[1], self._origin[0] - new_low[0]
        grown[r0:r0 + rows, c0:c0 + cols] = self._seen
        self._seen, self._origin = grown, new_low


class SeenTrack:
    """A sensor's scans, offered in time order, counted into ``grid`` thinned (the module's
    docstring): ``offer`` integrates a scan that is due and holds one that is not, ``flush``
    integrates the one held last, so the final area is every scan's. Sensors of one robot each
    have their track, on one ``grid`` (a fused count)."""

    def __init__(self, grid: SeenGrid) -> None:
        self.grid = grid
        self._last: tuple[float, float, float, int] | None = None  # x, y, yaw, t_ns integrated
        #: The last scan passed over since one was integrated: ``add``'s arguments.
        self.held: tuple[float, float, float, np.ndarray, np.ndarray] | None = None

    def offer(self, t_ns: int, x: float, y: float, yaw: float, bearing: np.ndarray,
              reach_m: np.ndarray) -> int:
        """A scan stamped ``t_ns`` from a sensor at ``(x, y)`` heading ``yaw`` (``SeenGrid.add``'s
        beams): integrated when due (the cells added), else held (0)."""
        last = self._last
        if (last is None
                or math.hypot(x - last[0], y - last[1]) >= MOVE_CELLS * self.grid.resolution_m
                or abs(wrap_angle(yaw - last[2])) >= TURN_RAD
                or int(t_ns) - last[3] >= PERIOD_S * 1e9):
            self._last, self.held = (x, y, yaw, int(t_ns)), None
            return self.grid.add(x, y, yaw, bearing, reach_m)
        self.held = (x, y, yaw, np.array(bearing, dtype=float), np.array(reach_m, dtype=float))
        return 0

    def flush(self) -> int:
        """Integrate the scan held, if any (the cells added)."""
        held, self.held = self.held, None
        return 0 if held is None else self.grid.add(*held)


def _limit(bearing: np.ndarray, reach: np.ndarray, rel: np.ndarray) -> np.ndarray:
    """How far a scan saw at bearings ``rel``: between two neighbouring beams (no farther
    apart than ``GAP`` spacings), the straight edge joining their ends, so a wall is traced
    exactly however slanted; else the nearest beam's reach within half a spacing of it, and
    nothing (-1) beyond (outside the field of view, across a run of beams without a reading)."""
    n, spacing = len(bearing), _spacing(bearing)
    after = np.searchsorted(bearing, rel) % n
    before = (after - 1) % n
    span = (bearing[after] - bearing[before]) % (2 * np.pi)
    into = (rel - bearing[before]) % (2 * np.pi)
    near_before = into <= span - into
    gap = np.where(near_before, into, span - into)
    nearest = np.where(near_before, reach[before], reach[after])
    limit = np.where(gap <= 0.5 * spacing + 1e-9, nearest, -1.0)
    rb, ra = reach[before], reach[after]
    with np.errstate(divide="ignore", invalid="ignore"):
        edge = rb * ra * np.sin(span) / (rb * np.sin(into) + ra * np.sin(span - into))
    joined = (span > 0) & (span <= GAP * spacing)
    return np.where(joined, edge, limit)


def _spacing(bearing: np.ndarray) -> float:
    """The median spacing (rad) of sorted bearings, counting the wrap round the circle only
    for a scan that goes nearly all the way round; 0 for a single beam."""
    if len(bearing) < 2:
        return 0.0
    steps = np.diff(bearing)
    wrap = bearing[0] + 2 * np.pi - bearing[-1]
    median = float(np.median(steps))
    return max(median, float(wrap)) if wrap <= 1.5 * median else median
