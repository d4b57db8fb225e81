"""Per-scan figures the metrics use, reduced from the beams while a bag is read.

A long log's scans would fill memory: 720 beams at 40 Hz are 7 MB a minute as float32, and
several times that once placed as points. The obstacle metrics need of each scan only its
nearest valid return, the sum and count of its valid returns, its footprint margin and, for a
vineyard episode without a centre line, the crop rows it sees (``rows``); ``summarize``
computes them from a chunk of whole scans (``ScanSeries``), with the footprint and LiDAR mount
of the episode's facts. The reader summarizes its scans in chunks as it reads them
(``ScanStream``) and keeps the beams only when asked (plots, videos), or a bounded, evenly
spread sample of whole scans beside the summary (``sample``: the report's maps); ``Derived``
summarizes an episode built in memory the same way, so both give the same numbers.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, replace
from typing import Any, NamedTuple

import numpy as np

from pic4rl_base.geometry import Footprint, Pose2D

from ..contract import EpisodeFacts
from .crop_rows import lane_sides
from .series_kinds import ScanSeries
from .tasks.seen import SeenCurve, SeenStream

NAN = float("nan")
#: Scans decoded before they are reduced to their summary (a few MB of beams at a time).
CHUNK = 1024
#: The task whose scans are fitted with crop rows when its facts give no centre line.
ROW_TASK = "vineyard"


def _row_min(values: np.ndarray) -> np.ndarray:
    """Per row, the smallest finite value; NaN for a row without one (also for 0 columns)."""
    low = np.min(np.where(np.isfinite(values), values, np.inf), axis=1, initial=np.inf)
    return np.where(np.isinf(low), NAN, low)


class ScanClearance(NamedTuple):
    """Per-scan obstacle figures (m); NaN for a scan with no valid beam."""

    nearest_m: np.ndarray  # nearest valid return (from the sensor)
    range_mean_m: np.ndarray  # mean of valid returns
    margin_m: np.ndarray  # signed distance of the nearest return to the footprint


def scan_clearance(
    scan: ScanSeries, facts: EpisodeFacts, ranges: np.ndarray | None = None
) -> ScanClearance:
    """Nearest obstacle per scan, and its signed distance to the footprint when one is known
    (scan points placed by ``facts.scan_mount``, the base origin when unknown)."""
    summary = summarize(scan, facts, ranges)
    return ScanClearance(summary.nearest_m, summary.range_mean_m, summary.margin_m)


def wants_lanes(facts: EpisodeFacts) -> bool:
    """Whether the row metrics fit crop rows to this episode's scans."""
    return facts.task == ROW_TASK and facts.row_centerline is None


@dataclass(frozen=True)
class ScanSummary:
    """What the metrics use of each scan (sorted by stamp as ``ScanSeries``), and the footprint
    and mount its margins and rows were computed with."""

    t_ns: np.ndarray
    range_min: np.ndarray
    range_max: np.ndarray
    nearest_m: np.ndarray  # nearest valid return, NaN without one
    range_sum_m: np.ndarray  # sum of the valid returns
    n_valid: np.ndarray  # count of the valid returns
    margin_m: np.ndarray  # footprint margin (NaN without a footprint or a valid return)
    lanes: np.ndarray | None  # (n, 4) crop rows seen (``rows.lane_sides``), None: not fitted
    footprint: Footprint | None = None
    mount: Pose2D | None = None
    #: A few whole scans evenly spread over the episode (``ScanStream(sample=n)``), sorted by
    #: stamp, for drawing maps; not indexed like the arrays above. None: not kept.
    sample: ScanSeries | None = None
    #: An exploration episode's area seen over time (``tasks.seen``), integrated while read.
    seen: SeenCurve | None = None

    def __len__(self) -> int:
        return len(self.t_ns)

    @property
    def range_mean_m(self) -> np.ndarray:
        with np.errstate(all="ignore"):
            return np.where(self.n_valid > 0, self.range_sum_m / np.maximum(self.n_valid, 1), NAN)

    def made_for(self, facts: EpisodeFacts) -> bool:
        """Computed with ``facts``' footprint, mount and (need of) crop rows."""
        return (self.footprint == facts.footprint and self.mount == facts.scan_mount
                and (self.lanes is not None) == wants_lanes(facts))

    def take(self, index: np.ndarray) -> ScanSummary:
        """The scans at ``index`` (an ordering, a selection)."""
        arrays = {name: getattr(self, name)[index] for name in _ARRAYS}
        return replace(self, **arrays, lanes=None if self.lanes is None else self.lanes[index])


_ARRAYS = ("t_ns", "range_min", "range_max", "nearest_m", "range_sum_m", "n_valid", "margin_m")


def summarize(scan: ScanSeries, facts: EpisodeFacts,
              ranges: np.ndarray | None = None) -> ScanSummary:
    """The summary of whole scans (``ranges``: their ``valid_ranges()`` when known already)."""
    ranges = scan.valid_ranges() if ranges is None else ranges
    valid = np.isfinite(ranges)
    mount = facts.scan_mount or Pose2D(0.0, 0.0)
    margin = np.full(len(scan), NAN)
    lanes = None
    if facts.footprint is not None or wants_lanes(facts):
        x, y = scan.points(mount, ranges)
        if facts.footprint is not None:
            margin = _row_min(facts.footprint.signed_distance_xy(x, y))
        if wants_lanes(facts):
            lanes = lane_sides(x, y)
    return ScanSummary(
        np.asarray(scan.t_ns, dtype=np.int64), np.asarray(scan.range_min, dtype=float),
        np.asarray(scan.range_max, dtype=float), _row_min(ranges),
        np.where(valid, ranges, 0).sum(axis=1), valid.sum(axis=1), margin, lanes,
        facts.footprint, facts.scan_mount)


def concat(parts: Sequence[ScanSummary]) -> ScanSummary:
    """Chunks' summaries (one at least) as one."""
    arrays = {name: np.concatenate([getattr(p, name) for p in parts]) for name in _ARRAYS}
    lanes = None if parts[0].lanes is None else np.concatenate([p.lanes for p in parts])
    return replace(parts[0], **arrays, lanes=lanes)


def scan_block(rows: Sequence[Any], t_ns: Sequence[int]) -> ScanSeries:
    """Decoded scans (``roles``' payload: ranges, angle_min, angle_increment, range_min,
    range_max) as one ``ScanSeries``, padded with NaN to the widest."""
    width = max((len(r[0]) for r in rows), default=0)
    ranges = np.full((len(rows), width), np.nan, dtype=np.float32)
    angles = np.full((len(rows), width), np.nan)
    for i, (rng, amin, ainc, _, _) in enumerate(rows):
        ranges[i, : len(rng)] = rng
        angles[i, : len(rng)] = amin + ainc * np.arange(len(rng))
    rmin = np.array([r[3] for r in rows], dtype=float)
    rmax = np.array([r[4] for r in rows], dtype=float)
    return ScanSeries(np.asarray(t_ns, dtype=np.int64), ranges, angles, rmin, rmax)


class ScanStream:
    """A scan topic's payloads as the reader appends them (``append``, like a list): reduced
    to their ``ScanSummary`` every ``CHUNK`` scans, and kept whole too when ``full``; with
    ``sample`` (and not ``full``), at most that many whole scans are kept beside the summary
    (``ScanSummary.sample``), evenly spread over the stream: every ``stride``-th payload is
    kept, and the stride doubles (every other kept one dropped) whenever more than twice
    ``sample`` are held, so memory stays bounded whatever the log's length. ``seen``: each
    chunk is also integrated into the area seen (``ScanSummary.seen``)."""

    def __init__(self, facts: EpisodeFacts, *, full: bool = False, sample: int = 0,
                 seen: SeenStream | None = None) -> None:
        self.facts, self.full, self.sample, self.seen = facts, full, max(0, sample), seen
        self._kept: list[tuple[int, Any]] = []  # (arrival index, payload) of the sample
        self._stride = 1
        self.width = 0  # the most beams of a scan
        self._count = 0
        self._pending: list[Any] = []
        self._parts: list[ScanSummary] = []
        self._blocks: list[ScanSeries] = []

    def __len__(self) -> int:
        return self._count

    def append(self, row: Any) -> None:
        if self.sample and not self._count % self._stride:
            self._kept.append((self._count, row))
            if len(self._kept) > 2 * self.sample:
                self._kept, self._stride = self._kept[::2], 2 * self._stride
        self._pending.append(row)
        self._count += 1
        if len(self._pending) >= CHUNK:
            self._flush()

    def _flush(self) -> None:
        if not self._pending:
            return
        block = scan_block(self._pending, np.zeros(len(self._pending), dtype=np.int64))
        self.width = max(self.width, block.ranges.shape[1])
        self._parts.append(summarize(block, self.facts))
        if self.seen is not None:
            self.seen.add(block, self._count - len(self._pending))
        if self.full:
            self._blocks.append(block)
        self._pending = []

    def finish(self, t_ns: np.ndarray, keep: np.ndarray) -> ScanSummary | ScanSeries:
        """The scans at ``keep`` (indices in arrival order), stamped ``t_ns`` (arrival order):
        whole when ``full``, else their summary."""
        self._flush()
        if self.full:
            ranges = np.full((self._count, self.width), np.nan, dtype=np.float32)
            angles = np.full((self._count, self.width), np.nan)
            start = 0
            for block in self._blocks:
                n, w = block.ranges.shape
                ranges[start:start + n, :w], angles[start:start + n, :w] = block.ranges, block.angles
                start += n
            rmin = np.concatenate([b.range_min for b in self._blocks])
            rmax = np.concatenate([b.range_max for b in self._blocks])
            return ScanSeries(t_ns[keep], ranges[keep], angles[keep], rmin[keep], rmax[keep])
        summary = concat(self._parts)
        t_ns = np.asarray(t_ns, dtype=np.int64)
        seen = None if self.seen is None else self.seen.curve(t_ns, keep)
        return replace(summary.take(keep), t_ns=t_ns[keep], sample=self._sample(t_ns, keep),
                       seen=seen)

    def _sample(self, t_ns: np.ndarray, keep: np.ndarray) -> ScanSeries | None:
        """The kept payloads among ``keep`` (in its order): every other one until at most
        ``sample`` remain, so they stay evenly spaced (between half of ``sample`` and it)."""
        payload = dict(self._kept)
        chosen = np.asarray(keep)[np.isin(keep, list(payload))]
        if not len(chosen):
            return None
        while len(chosen) > self.sample:
            chosen = chosen[::2]
        return scan_block([payload[int(i)] for i in chosen], t_ns[chosen])
