"""Raw samples of a topic onto the episode's time base, sorted and cleaned, as series.

Time base: message header stamps. Headerless messages (``Twist``, the outcome ``String``) are
moved onto it by the median offset between the pose topic's header stamps and its bag
receive times; a topic whose header stamps are all zero falls back to receive times (with a
warning). Samples are sorted by stamp, exact repeats dropped (the last received wins), and
non-finite poses dropped, each noted in the warnings.

One rule guards the time of every topic, here and nowhere else: a sensor topic recorded from
two publishers, or whose stamps jump back more than once, holds two sources (two simulators or
robots in one ROS domain) and the bag is refused as corrupt (``CorruptBagError``); a single
jump back is the clock's, repaired in arrival order so that no difference spans it
(``repair_clock``, docs/metrics.md "Clock jumps and mixed sources"). What the pose series
then shows (two tracks, speeds no robot reaches) is judged by ``plausibility``.
"""

from __future__ import annotations

from typing import Any, NamedTuple

import numpy as np

from ..errors import CorruptBagError
from .plausibility import PLAUSIBLE_SPEED_MPS
from .scan_summary import ScanStream, ScanSummary
from .series_kinds import CmdSeries, PeopleSeries, PointSeries, PoseSeries, ScanSeries

#: A header stamp this far (ns) behind the one received before it is no reordered message:
#: the topic's clock jumped back, or a second source publishes it.
JUMP_NS = 500_000_000


class Samples:
    """Samples of one topic: header stamps (0 when headerless), receive times, payload."""

    def __init__(self) -> None:
        self.stamp: list[int] = []
        self.recv: list[int] = []
        self.rows: list[Any] = []
        #: Frame id of the first message with a header ("" when headerless).
        self.frame = ""
        self.has_header = False
        #: The topic read (for the warnings that name it).
        self.topic = ""


#: Roles whose topic one publisher feeds on one robot: more are two sources (``one_source``).
#: Commands may have several (a joystick and a planner through a mux), transforms do.
ONE_SOURCE_ROLES = frozenset({"pose", "scan", "person"})


def one_source(topic: str, publishers: int) -> None:
    """Refuse a sensor topic that the bag records from more than one publisher."""
    if publishers > 1:
        msg = (f"{topic}: {publishers} publishers recorded (offered QoS profiles or "
               "connections): two sources of one stream, as two simulators or robots in one ROS "
               "domain give; refused as corrupt, not scored")
        raise CorruptBagError(msg)


class ClockJump(NamedTuple):
    """A repaired jump back: the last message before it (arrival order), and the topic's
    median period (ns) the later stamps now follow it by."""

    index: int
    period_ns: int


def _clusters(t_ns: np.ndarray) -> str:
    """The two groups of stamps either side of their widest gap, as text (s)."""
    ordered = np.sort(t_ns) * 1e-9
    cut = int(np.argmax(np.diff(ordered))) + 1
    low, high = ordered[:cut], ordered[cut:]
    return f"{low[0]:.2f}-{low[-1]:.2f} s and {high[0]:.2f}-{high[-1]:.2f} s"


def repair_clock(t_ns: np.ndarray, topic: str,
                 warnings: list[str]) -> tuple[np.ndarray, ClockJump | None]:
    """Stamps in arrival order, with one jump of the clock repaired.

    A stamp ``JUMP_NS`` or more behind the one received before it is a jump back. Two or more
    are two sources interleaved: ``CorruptBagError``. One is a late message when the stamps
    return past the jump's top with a step forward of ``JUMP_NS`` or more (sorting puts it in
    place); else the clock jumped, and the later stamps are moved forward to follow the
    earlier ones by the topic's median period, with a warning naming the topic and the jump.
    """
    if t_ns.size < 2:
        return t_ns, None
    step = np.diff(t_ns)
    back = np.flatnonzero(step <= -JUMP_NS)
    if back.size > 1:
        msg = (f"{topic}: header stamps jump back {back.size} times (by up to "
               f"{-int(step[back].min()) * 1e-9:.2f} s; stamps in {_clusters(t_ns)}): two "
               "sources interleaved, as two simulators or robots in one ROS domain give; "
               "refused as corrupt, not scored")
        raise CorruptBagError(msg)
    if back.size == 0:
        return t_ns, None
    i = int(back[0])
    top, after = int(t_ns[i]), t_ns[i + 1:]
    past = np.flatnonzero(after >= top)
    if past.size and past[0] > 0 and after[past[0]] - after[past[0] - 1] >= JUMP_NS:
        return t_ns, None
    forward = step[step > 0]
    period = int(np.median(forward)) if forward.size else 0
    shift = top - int(after[0]) + period
    repaired = t_ns.copy()
    repaired[i + 1:] += shift
    warnings.append(
        f"{topic}: clock jumped back {(top - int(after[0])) * 1e-9:.3f} s after message {i + 1} "
        f"of {t_ns.size} ({(top - int(t_ns[0])) * 1e-9:.3f} s in); its {after.size} later "
        f"stamps moved {shift * 1e-9:+.3f} s to follow on, so no length, speed or "
        "acceleration spans the jump")
    return repaired, ClockJump(i, period)


def _one_robot(topic: str, rows: np.ndarray, recv: np.ndarray, jump: ClockJump) -> None:
    """Refuse a pose that leaps across a clock jump faster than a robot moves: the later
    stamps are another robot's (a second simulator's), not this one's after a clock step."""
    i = jump.index
    (x0, y0), (x1, y1) = rows[i, :2], rows[i + 1, :2]
    if not np.isfinite([x0, y0, x1, y1]).all():
        return
    gap_s = max(jump.period_ns, int(recv[i + 1]) - int(recv[i])) * 1e-9
    leap = float(np.hypot(x1 - x0, y1 - y0))
    if leap > PLAUSIBLE_SPEED_MPS * gap_s:
        msg = (f"{topic}: the pose leaps {leap:.2f} m in {gap_s:.3f} s where its stamps jump "
               "back: two sources, as two simulators or robots in one ROS domain give; refused "
               "as corrupt, not scored")
        raise CorruptBagError(msg)


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
    rows = np.asarray(raw.rows, dtype=float).reshape(-1, 6)
    t_ns, jump = repair_clock(_timeline(raw, 0), name, warnings)
    if jump is not None:
        _one_robot(name, rows, recv, jump)
        offset = int(np.median(t_ns - recv))
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
    t_ns, keep = _kept(raw, offset, name, warnings)
    return t_ns[keep], [raw.rows[i] for i in keep]


def _kept(raw: Samples, offset: int, name: str, warnings: list[str]) -> tuple[np.ndarray, np.ndarray]:
    """Stamps on the pose time base (arrival order, a clock jump repaired) and the indices
    that sort and de-duplicate them."""
    _zero_stamps(raw, name, warnings)
    t_ns, _ = repair_clock(_timeline(raw, offset), raw.topic or name, warnings)
    return t_ns, _order(t_ns, name, warnings)


def scan_series(raw: Samples, offset: int, warnings: list[str]) -> ScanSummary | ScanSeries | None:
    """The scans (a ``ScanStream`` the reader filled) as their summary, or whole when the
    stream kept them."""
    stream = raw.rows
    if not len(stream):
        return None
    t_ns, keep = _kept(raw, offset, "scan", warnings)
    series = stream.finish(t_ns, keep)
    if stream.width == 0:
        warnings.append(f"scan: all {len(keep)} LaserScan messages have no ranges; "
                        "scan metrics are NaN")
        return None
    return series


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


def people_series(raw: Samples, offset: int, warnings: list[str]) -> PeopleSeries | None:
    """The people's positions, a message's i-th pose in column i (NaN-padded)."""
    if not raw.rows:
        return None
    t_ns, rows = _sorted(raw, offset, "people", warnings)
    width = max(map(len, rows), default=0)
    xy = np.full((len(rows), width, 2), np.nan)
    for i, row in enumerate(rows):
        xy[i, :len(row)] = np.asarray(row, dtype=float).reshape(-1, 2)
    return PeopleSeries(t_ns, xy[:, :, 0], xy[:, :, 1])
