"""Raw samples of a topic onto the episode's time base, sorted and cleaned, as series.

Time base: message header stamps. Headerless messages (``Twist``, the outcome ``String``) are
moved onto it by the median offset between the pose topic's header stamps and its bag
receive times; a topic whose header stamps are all zero falls back to receive times (with a
warning). Samples are sorted by stamp, exact repeats dropped (the last received wins), and
non-finite poses dropped, each noted in the warnings.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .series_kinds import CmdSeries, PointSeries, PoseSeries, ScanSeries


class Samples:
    """Samples of one topic: header stamps (0 when headerless), receive times, payload."""

    def __init__(self) -> None:
        self.stamp: list[int] = []
        self.recv: list[int] = []
        self.rows: list[Any] = []
        #: Frame id of the first message with a header ("" when headerless).
        self.frame = ""
        self.has_header = False


def _timeline(topic: Samples, offset_ns: int | None) -> np.ndarray:
    stamps = np.asarray(topic.stamp, dtype=np.int64)
    recv = np.asarray(topic.recv, dtype=np.int64)
    if stamps.size and stamps.any():
        return stamps
    return recv + (offset_ns or 0)


def _zero_stamps(topic: Samples, name: str, warnings: list[str]) -> None:
    """Warn when a topic with headers has only zero stamps (its receive times stand in)."""
    if topic.has_header and topic.stamp and not any(topic.stamp):
        warnings.append(f"{name}: header stamps are zero; using bag receive times")


def _order(t_ns: np.ndarray, name: str, warnings: list[str]) -> np.ndarray:
    """Indices that sort by stamp and keep the last of exact repeats."""
    if t_ns.size == 0:
        return np.zeros(0, dtype=np.intp)
    backwards = int(np.sum(np.diff(t_ns) < 0))
    if backwards:
        warnings.append(f"{name}: {backwards} stamp(s) went backwards; samples sorted by stamp")
    order = np.argsort(t_ns, kind="stable")
    sorted_t = t_ns[order]
    last_of_run = np.append(sorted_t[1:] != sorted_t[:-1], True)
    repeats = int(np.sum(~last_of_run))
    if repeats:
        warnings.append(f"{name}: {repeats} repeated stamp(s); kept the last message of each")
    return order[last_of_run]


def pose_series(raw: Samples, name: str, warnings: list[str]) -> tuple[PoseSeries, int | None]:
    """Pose series and the header-minus-receive offset (ns) it defines."""
    stamps = np.asarray(raw.stamp, dtype=np.int64)
    recv = np.asarray(raw.recv, dtype=np.int64)
    if stamps.any():
        offset = int(np.median(stamps - recv))
    else:
        warnings.append(f"{name}: header stamps are zero; using bag receive times")
        offset = 0
    t_ns = _timeline(raw, 0)
    rows = np.asarray(raw.rows, dtype=float).reshape(-1, 6)
    finite = np.isfinite(rows[:, :3]).all(axis=1)
    if not finite.all():
        warnings.append(f"{name}: {int(np.sum(~finite))} pose(s) with NaN/inf dropped")
    t_ns, rows = t_ns[finite], rows[finite]
    keep = _order(t_ns, name, warnings)
    t_ns, rows = t_ns[keep], rows[keep]
    twist_known = ~np.isnan(rows[:, 3:]).all(axis=1)  # types without a twist give NaN
    has_twist = rows.size > 0 and twist_known.all() and np.isfinite(rows[:, 3:]).all()
    if twist_known.any() and not has_twist:
        bad = int(np.sum(~np.isfinite(rows[:, 3:]).all(axis=1)))
        warnings.append(f"{name}: {bad} twist(s) with NaN/inf; velocities from pose differences")
    twist = (rows[:, 3], rows[:, 4], rows[:, 5]) if has_twist else (None, None, None)
    return PoseSeries(t_ns, rows[:, 0], rows[:, 1], rows[:, 2], *twist), offset


def _sorted(raw: Samples, offset: int, name: str, warnings: list[str]) -> tuple[np.ndarray, list[Any]]:
    """Stamps on the pose time base and the payload rows, sorted and de-duplicated."""
    _zero_stamps(raw, name, warnings)
    t_ns = _timeline(raw, offset)
    keep = _order(t_ns, name, warnings)
    return t_ns[keep], [raw.rows[i] for i in keep]


def scan_series(raw: Samples, offset: int, warnings: list[str]) -> ScanSeries | None:
    if not raw.rows:
        return None
    t_ns, rows = _sorted(raw, offset, "scan", warnings)
    width = max(len(r[0]) for r in rows)
    if width == 0:
        warnings.append(f"scan: all {len(rows)} LaserScan messages have no ranges; "
                        "scan metrics are NaN")
        return None
    ranges = np.full((len(rows), width), np.nan, dtype=np.float32)
    angles = np.full((len(rows), width), np.nan)
    for i, (rng, amin, ainc, _, _) in enumerate(rows):
        ranges[i, : len(rng)] = rng
        angles[i, : len(rng)] = amin + ainc * np.arange(len(rng))
    rmin = np.array([r[3] for r in rows], dtype=float)
    rmax = np.array([r[4] for r in rows], dtype=float)
    return ScanSeries(t_ns, ranges, angles, rmin, rmax)


def cmd_series(raw: Samples, offset: int, warnings: list[str]) -> CmdSeries | None:
    if not raw.rows:
        return None
    t_ns, rows = _sorted(raw, offset, "cmd_vel", warnings)
    v = np.asarray(rows, dtype=float)
    return CmdSeries(t_ns, v[:, 0], v[:, 1], v[:, 2])


def point_series(raw: Samples, offset: int, warnings: list[str]) -> PointSeries | None:
    if not raw.rows:
        return None
    t_ns, rows = _sorted(raw, offset, "person", warnings)
    p = np.asarray(rows, dtype=float)
    return PointSeries(t_ns, p[:, 0], p[:, 1])
