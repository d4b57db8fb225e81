"""Area seen over time, from an exploration episode's scans and poses alone (nothing of the sim).

Whole scans cannot be kept for a long log (``scan_summary``), so the reader integrates each
chunk of scans into a ``pic4rl_base.seen_area.SeenGrid`` as it reads it (``SeenStream``: the
poses are read before the scans), keeping per scan only the count of cells it added; memory is
the grid, bounded by the area seen, and eight bytes a scan. ``Derived`` integrates an episode's
whole scans the same way (``seen_curve``), so both give the same numbers.

A scan is placed at the pose interpolated at its stamp (the LiDAR's mount applied); one outside
the poses' time span adds nothing. A beam's reach is its valid return, ``range_max`` where it
returned nothing within range (``+inf``: free that far), nothing for NaN or a return closer than
``range_min``. A scan is integrated only when the sensor has moved ``MOVE_CELLS`` cells or
turned ``TURN_RAD`` since the last one integrated, or ``PERIOD_S`` has passed: a scan from the
same place adds next to nothing and the work stays bounded for a robot standing still.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from pic4rl_base.geometry import Pose2D, wrap_angle
from pic4rl_base.seen_area import SeenGrid

from ...contract import EpisodeFacts, task_name
from ..series_kinds import PoseSeries, ScanSeries

#: Tasks (``task`` fact without its sensor) whose episodes get the area-seen columns.
EXPLORE_TASKS = frozenset({"explore"})
#: Side of a grid cell (m), as the bridge's occupancy grid.
SEEN_RESOLUTION_M = 0.05
#: A scan is integrated after the sensor moved this many cells, turned this far (rad), or
#: this long (s) passed since the last scan integrated: the time-to columns are late by at
#: most that much (0.4 s at 0.5 m/s), and a 2-hour log of a moving robot costs minutes.
MOVE_CELLS = 4
TURN_RAD = math.radians(10.0)
PERIOD_S = 1.0


def wants_seen(facts: EpisodeFacts) -> bool:
    """Whether this episode's area seen is integrated (an exploration task)."""
    return task_name(facts.task) in EXPLORE_TASKS


@dataclass(frozen=True)
class SeenCurve:
    """Area seen after each scan (sorted by stamp): ``area_m2`` cumulative, at ``resolution_m``."""

    t_ns: np.ndarray
    area_m2: np.ndarray
    resolution_m: float


def _reach(scan: ScanSeries) -> np.ndarray:
    """Per beam, how far it saw (m): its valid return, ``range_max`` for ``+inf``, else NaN."""
    ranges = np.asarray(scan.ranges, dtype=float)
    rmax = scan.range_max[:, None]
    valid = np.isfinite(ranges) & (ranges >= scan.range_min[:, None])
    reach = np.where(valid, np.minimum(ranges, rmax), np.nan)
    return np.where(np.isposinf(ranges), np.broadcast_to(rmax, ranges.shape), reach)


class SeenStream:
    """Scans integrated as they come (``add``, a chunk at a time, in arrival order), each placed
    by ``clock(start, n)``: the stamps (ns, the poses' time base) of the ``n`` scans from
    arrival index ``start``."""

    def __init__(self, pose: PoseSeries, mount: Pose2D | None,
                 clock: Callable[[int, int], np.ndarray]) -> None:
        self.grid = SeenGrid(SEEN_RESOLUTION_M)
        self.mount = mount or Pose2D(0.0, 0.0)
        self.clock = clock
        t0 = int(pose.t_ns[0])
        self._t0, self._pose_t = t0, (pose.t_ns - t0).astype(float)
        self._x, self._y, self._yaw = pose.x, pose.y, np.unwrap(pose.yaw)
        self._last: tuple[float, float, float, float] | None = None  # x, y, yaw, t (s)
        self._stamps: list[np.ndarray] = []
        self._added: list[np.ndarray] = []
        #: The last scan passed over while no later one was integrated (arrival index and its
        #: placed beams): integrated at the end, so the final area is every scan's.
        self._skipped: tuple[int, float, float, float, np.ndarray, np.ndarray] | None = None

    def add(self, block: ScanSeries, start: int) -> None:
        t_ns = np.asarray(self.clock(start, len(block)), dtype=np.int64)
        added = np.zeros(len(block), dtype=np.int32)
        at = (t_ns - self._t0).astype(float)
        inside = (at >= self._pose_t[0]) & (at <= self._pose_t[-1])
        x, y = np.interp(at, self._pose_t, self._x), np.interp(at, self._pose_t, self._y)
        yaw = np.interp(at, self._pose_t, self._yaw)
        m = self.mount
        sx = x + m.x * np.cos(yaw) - m.y * np.sin(yaw)
        sy = y + m.x * np.sin(yaw) + m.y * np.cos(yaw)
        heading = yaw + m.yaw
        reach = _reach(block)
        for i in np.flatnonzero(inside):
            if self._due(sx[i], sy[i], heading[i], at[i] * 1e-9):
                added[i] = self.grid.add(sx[i], sy[i], heading[i], block.angles[i], reach[i])
                self._skipped = None
            else:
                self._skipped = (start + i, sx[i], sy[i], heading[i], block.angles[i].copy(),
                                 reach[i].copy())
        self._stamps.append(t_ns)
        self._added.append(added)

    def _due(self, x: float, y: float, yaw: float, t_s: float) -> bool:
        last = self._last
        due = (last is None or math.hypot(x - last[0], y - last[1])
               >= MOVE_CELLS * SEEN_RESOLUTION_M or abs(wrap_angle(yaw - last[2])) >= TURN_RAD
               or t_s - last[3] >= PERIOD_S)
        if due:
            self._last = (x, y, yaw, t_s)
        return due

    def curve(self, t_ns: np.ndarray, keep: np.ndarray) -> SeenCurve | None:
        """The area seen after each scan at ``keep`` (arrival indices, in stamp order), whose
        stamps are ``t_ns[keep]``; None when those differ from the stamps the scans were
        placed by (a clock jump repaired after reading) or no scan was kept."""
        if not self._stamps or not len(keep):
            return None
        placed = np.concatenate(self._stamps)
        if not np.array_equal(placed[keep], np.asarray(t_ns)[keep]):
            return None
        added = np.concatenate(self._added)
        if self._skipped is not None:
            index, *scan = self._skipped
            added[index] += self.grid.add(*scan)
            self._skipped = None
        cells = np.cumsum(added[keep])
        return SeenCurve(placed[keep], cells * SEEN_RESOLUTION_M**2, SEEN_RESOLUTION_M)


def reader_stream(facts: EpisodeFacts, pose: PoseSeries, samples: Any,
                  offset: int | None) -> SeenStream | None:
    """The stream for a scan topic's ``samples`` (``timebase.Samples``: header stamps, receive
    times) as the reader fills them; None unless the episode is an exploration."""
    if not wants_seen(facts):
        return None

    def clock(start: int, n: int) -> np.ndarray:
        stamp = np.asarray(samples.stamp[start:start + n], dtype=np.int64)
        recv = np.asarray(samples.recv[start:start + n], dtype=np.int64)
        return np.where(stamp != 0, stamp, recv + (offset or 0))

    return SeenStream(pose, facts.scan_mount, clock)


def seen_curve(scan: Any, pose: PoseSeries, facts: EpisodeFacts) -> SeenCurve | None:
    """An exploration episode's area seen: its reader's (a ``ScanSummary``'s ``seen``), else
    integrated from its whole scans (``ScanSeries``); None for another task or no scan."""
    if scan is None or not wants_seen(facts):
        return None
    if not isinstance(scan, ScanSeries):
        return scan.seen
    stream = SeenStream(pose, facts.scan_mount, lambda start, n: scan.t_ns[start:start + n])
    stream.add(scan, 0)
    return stream.curve(scan.t_ns, np.argsort(scan.t_ns, kind="stable"))
