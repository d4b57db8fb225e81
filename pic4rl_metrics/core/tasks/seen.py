"""Area seen over time, from an exploration episode's scans and poses alone (nothing of the sim).

Whole scans cannot be kept for a long log (``scan_summary``), so the reader integrates each
chunk of scans into a ``pic4rl_base.seen_area.SeenGrid`` as it reads it (``SeenStream``: the
poses are read before the scans), keeping per scan only the count of cells it added; memory is
the grid, bounded by the area seen, and eight bytes a scan. ``Derived`` integrates an episode's
whole scans the same way (``seen_curve``), so both give the same numbers.

A scan is placed at the pose interpolated at its stamp (the LiDAR's mount applied); one outside
the poses' time span adds nothing. A beam's reach is its valid return, ``range_max`` where it
returned nothing within range (``+inf``: free that far), nothing for NaN or a return closer than
``range_min`` (``pic4rl_base.seen_area.beam_reach``). The scans are counted by
``pic4rl_base.seen_area.SeenTrack``, thinned as the live explore task counts them (a scan is
integrated once the sensor has moved, turned or waited enough since the last one), so an
episode the task ended at its coverage target reads that coverage from its bag.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from pic4rl_base.geometry import Pose2D
from pic4rl_base.seen_area import SeenGrid, SeenTrack, beam_reach

from ...contract import EpisodeFacts, task_name
from ..series_kinds import PoseSeries, ScanSeries

#: Tasks (``task`` fact without its sensor) whose episodes get the area-seen columns.
EXPLORE_TASKS = frozenset({"explore"})
#: Side of a grid cell (m), as the bridge's occupancy grid.
SEEN_RESOLUTION_M = 0.05


def wants_seen(facts: EpisodeFacts) -> bool:
    """Whether this episode's area seen is integrated (an exploration task)."""
    return task_name(facts.task) in EXPLORE_TASKS


@dataclass(frozen=True)
class SeenCurve:
    """Area seen after each scan (sorted by stamp): ``area_m2`` cumulative, at ``resolution_m``."""

    t_ns: np.ndarray
    area_m2: np.ndarray
    resolution_m: float


class SeenStream:
    """Scans integrated as they come (``add``, a chunk at a time, in arrival order), each placed
    by ``clock(start, n)``: the stamps (ns, the poses' time base) of the ``n`` scans from
    arrival index ``start``."""

    def __init__(self, pose: PoseSeries, mount: Pose2D | None,
                 clock: Callable[[int, int], np.ndarray]) -> None:
        self.track = SeenTrack(SeenGrid(SEEN_RESOLUTION_M))
        self.mount = mount or Pose2D(0.0, 0.0)
        self.clock = clock
        t0 = int(pose.t_ns[0])
        self._t0, self._pose_t = t0, (pose.t_ns - t0).astype(float)
        self._x, self._y, self._yaw = pose.x, pose.y, np.unwrap(pose.yaw)
        self._stamps: list[np.ndarray] = []
        self._added: list[np.ndarray] = []
        self._held = -1  # arrival index of the scan the track holds (its cells come at the end)

    @property
    def grid(self) -> SeenGrid:
        """The cells seen by the scans integrated so far."""
        return self.track.grid

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
        reach = beam_reach(block.ranges, block.range_min[:, None], block.range_max[:, None])
        for i in np.flatnonzero(inside):
            added[i] = self.track.offer(int(t_ns[i]), float(sx[i]), float(sy[i]),
                                        float(heading[i]), block.angles[i], reach[i])
            if self.track.held is not None:
                self._held = start + i
        self._stamps.append(t_ns)
        self._added.append(added)

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
        if self.track.held is not None:
            added[self._held] += self.track.flush()
            self._added = [added]
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
