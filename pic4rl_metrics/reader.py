"""Read one bag into an ``Episode``: only the topics the metrics need, only once.

Time base: message header stamps. Headerless messages (``Twist``, the outcome ``String``) are
moved onto it by the median offset between the pose topic's header stamps and its bag
receive times; a topic whose header stamps are all zero falls back to receive times (with a
warning). Samples are sorted by stamp, exact repeats dropped (the last received wins), and
non-finite poses dropped, each noted in ``Episode.warnings``. A fact or an outcome that cannot
be read is left out with a warning: the metrics that do not need it stay. The LiDAR's mount is
read from ``/tf_static`` when the facts do not give it.
"""

from __future__ import annotations

import json
import math
import struct
from collections import defaultdict
from collections.abc import Callable
from functools import lru_cache
from pathlib import Path
from typing import Any

import numpy as np
from apsw import Error as SqliteError
from rosbags.interfaces import Connection, MessageDefinitionFormat
from rosbags.rosbag2 import Reader, ReaderError
from rosbags.serde import SerdeError
from rosbags.typesys import (
    Stores,
    TypesysError,
    get_types_from_idl,
    get_types_from_msg,
    get_typestore,
)
from rosbags.typesys.store import Typestore

from .contract import TF_STATIC_TOPIC, EpisodeFacts, parse_facts, parse_outcome_event, typestore
from .errors import BagError, ConfigError, EpisodeError, TopicError
from .facts import Mount
from .series import CmdSeries, Episode, PointSeries, PoseSeries, ScanSeries
from .topics import TopicMap

ODOMETRY = "nav_msgs/msg/Odometry"
POSE_STAMPED = "geometry_msgs/msg/PoseStamped"
POSE_COV = "geometry_msgs/msg/PoseWithCovarianceStamped"
TWIST = "geometry_msgs/msg/Twist"
TWIST_STAMPED = "geometry_msgs/msg/TwistStamped"
LASER_SCAN = "sensor_msgs/msg/LaserScan"
STRING = "std_msgs/msg/String"
TF_MESSAGE = "tf2_msgs/msg/TFMessage"

SUPPORTED_POSE_MSGS = frozenset({ODOMETRY, POSE_STAMPED, POSE_COV})
SUPPORTED_CMD_MSGS = frozenset({TWIST, TWIST_STAMPED})

#: What a damaged storage file or message raises while rosbags reads it: sqlite's errors
#: (rosbags reads .db3 through apsw), short reads and absurd lengths in MCAP records, and
#: CDR that does not match its type.
_DAMAGE = (
    SqliteError, SerdeError, TypesysError, struct.error, EOFError, OverflowError, MemoryError,
    AssertionError, ValueError, IndexError, KeyError,
)

@lru_cache(maxsize=64)
def _typestore_for(msgtype: str, msgdef_format: MessageDefinitionFormat, msgdef: str) -> Typestore:
    """The typestore that decodes ``msgtype`` as the bag defines it.

    The contract's ``typestore()`` (whose decoders are generated once per process; also for
    bags that embed no definitions, rosbag2 before Iron: the layouts of the types above are the
    same in every ROS 2 distribution) unless the bag embeds a definition that differs from
    Jazzy's; cached on the definition text, so opening many bags
    does not rebuild types and decoders for each (rosbags' ``AnyReader`` does).
    """
    jazzy = typestore()
    if msgdef_format == MessageDefinitionFormat.NONE:
        return jazzy
    if msgdef_format == MessageDefinitionFormat.MSG:
        types = get_types_from_msg(msgdef, msgtype)
    else:
        sep = "=" * 80 + "\n"
        parts = msgdef.split(sep)[1:] if msgdef.startswith(f"{sep}IDL: ") else []
        types = {}
        for idl in [part.split("\n", 1)[1] for part in parts] or [msgdef]:
            types.update(get_types_from_idl(idl))
    own = get_typestore(Stores.EMPTY)
    own.register(types)
    known = msgtype in jazzy.fielddefs
    same = known and own.hash_rihs01(msgtype) == jazzy.hash_rihs01(msgtype)
    return jazzy if same else own


def _stamp_ns(header: Any) -> int:
    return int(header.stamp.sec) * 1_000_000_000 + int(header.stamp.nanosec)


def _yaw(q: Any) -> float:
    return math.atan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z))


def _tf_rows(msg: Any, _msgtype: str) -> list[tuple[str, str, float, float, float]]:
    """(parent, child, x, y, yaw) of each transform of a ``TFMessage``."""
    rows = []
    for tf in msg.transforms:
        t, q = tf.transform.translation, tf.transform.rotation
        rows.append((tf.header.frame_id.lstrip("/"), tf.child_frame_id.lstrip("/"), t.x, t.y, _yaw(q)))
    return rows


def _pose_row(msg: Any, msgtype: str) -> tuple[float, ...]:
    """(x, y, yaw, vx, vy, wz) of a pose message; NaN twist when the type has none."""
    pose = msg.pose if msgtype == POSE_STAMPED else msg.pose.pose
    p, q = pose.position, pose.orientation
    if msgtype == ODOMETRY:
        t = msg.twist.twist
        return (p.x, p.y, _yaw(q), t.linear.x, t.linear.y, t.angular.z)
    return (p.x, p.y, _yaw(q), math.nan, math.nan, math.nan)


class _Topic:
    """Samples of one topic: header stamps (0 when headerless), receive times, payload."""

    def __init__(self) -> None:
        self.stamp: list[int] = []
        self.recv: list[int] = []
        self.rows: list[Any] = []
        #: Frame id of the first message with a header ("" when headerless).
        self.frame = ""
        self.has_header = False


def _timeline(topic: _Topic, offset_ns: int | None) -> np.ndarray:
    stamps = np.asarray(topic.stamp, dtype=np.int64)
    recv = np.asarray(topic.recv, dtype=np.int64)
    if stamps.size and stamps.any():
        return stamps
    return recv + (offset_ns or 0)


def _zero_stamps(topic: _Topic, name: str, warnings: list[str]) -> None:
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


class _BagContents:
    """Raw samples of the mapped topics of one bag, read in one pass."""

    def __init__(self, path: Path, topic_map: TopicMap) -> None:
        self.path = path
        self.topics: dict[str, _Topic] = defaultdict(_Topic)
        self.custom: dict[str, str] = {}
        self.notes: list[str] = []
        try:
            with Reader(path) as reader:
                self.available = {c.topic: c.msgtype for c in reader.connections}
                self.custom = dict(reader.storage.metadata.custom or {})
                self.pose_topic = self._choose_pose_topic(topic_map)
                wanted = self._wanted(topic_map)
                self._read(reader, [c for c in reader.connections if c.topic in wanted], wanted)
        except (ReaderError, OSError) as err:
            msg = f"{str(path)!r}: cannot open bag: {err}"
            raise BagError(msg) from err
        except _DAMAGE as err:
            msg = f"{str(path)!r}: damaged bag or message: {type(err).__name__}: {err}"
            raise BagError(msg) from err

    def _choose_pose_topic(self, topic_map: TopicMap) -> str:
        for topic in topic_map.pose:
            if topic in self.available:
                msgtype = self.available[topic]
                if msgtype not in SUPPORTED_POSE_MSGS:
                    msg = (
                        f"{str(self.path)!r}: pose topic {topic!r} has type {msgtype!r}; "
                        f"expected one of {sorted(SUPPORTED_POSE_MSGS)}"
                    )
                    raise TopicError(msg)
                return topic
        odometry = sorted(t for t, ty in self.available.items() if ty == ODOMETRY)
        if "pose" not in topic_map.explicit and len(odometry) == 1:
            self.notes.append(
                f"none of the pose topics {list(topic_map.pose)} is in the bag; "
                f"using its only Odometry topic {odometry[0]!r}"
            )
            return odometry[0]
        candidates = sorted(t for t, ty in self.available.items() if ty in SUPPORTED_POSE_MSGS)
        hint = f"; pose-like topics in it: {candidates} (pass --pose-topic)" if candidates else ""
        msg = (
            f"{str(self.path)!r}: none of the pose topics {list(topic_map.pose)} is in the bag"
            f"{hint}; it has {sorted(self.available) or 'no topics'}"
        )
        raise TopicError(msg)

    def _wanted(self, topic_map: TopicMap) -> dict[str, str]:
        """Topic -> role for every mapped topic present; explicit roles must be present."""
        roles = {
            "scan": (topic_map.scan, {LASER_SCAN}),
            "cmd_vel": (topic_map.cmd_vel, SUPPORTED_CMD_MSGS),
            "goal": (topic_map.goal, SUPPORTED_POSE_MSGS),
            "person": (topic_map.person, SUPPORTED_POSE_MSGS),
            "facts": (topic_map.facts, {STRING}),
            "outcome": (topic_map.outcome, {STRING}),
            "tf_static": (TF_STATIC_TOPIC if topic_map.scan is not None else None, {TF_MESSAGE}),
        }
        wanted = {self.pose_topic: "pose"}
        for role, (topic, types) in roles.items():
            if topic is None:
                continue
            if topic not in self.available:
                if role in topic_map.explicit:
                    msg = (
                        f"{str(self.path)!r}: {role} topic {topic!r} is not in the bag; "
                        f"it has {sorted(self.available)}"
                    )
                    raise TopicError(msg)
                continue
            if self.available[topic] not in types:
                msg = (
                    f"{str(self.path)!r}: {role} topic {topic!r} has type "
                    f"{self.available[topic]!r}; expected one of {sorted(types)}"
                )
                raise TopicError(msg)
            wanted.setdefault(topic, role)
        return wanted

    def _read(self, reader: Reader, conns: list[Connection], wanted: dict[str, str]) -> None:
        extractors: dict[str, Callable[[Any, str], Any]] = {
            "pose": _pose_row,
            "goal": _pose_row,
            "person": _pose_row,
            "scan": lambda m, _t: (
                m.ranges, m.angle_min, m.angle_increment, m.range_min, m.range_max
            ),
            "cmd_vel": lambda m, t: (
                (m.twist if t == TWIST_STAMPED else m).linear.x,
                (m.twist if t == TWIST_STAMPED else m).linear.y,
                (m.twist if t == TWIST_STAMPED else m).angular.z,
            ),
            "facts": lambda m, _t: m.data,
            "outcome": lambda m, _t: m.data,
            "tf_static": _tf_rows,
        }
        # Per connection, resolved once: decoder, extractor and the lists to append to.
        plan = {}
        for conn in conns:
            role, msgdef = wanted[conn.topic], conn.msgdef
            typestore = _typestore_for(conn.msgtype, msgdef.format, msgdef.data)
            sample = self.topics[role]
            plan[conn.id] = (
                typestore.deserialize_cdr, conn.msgtype, extractors[role],
                sample.stamp.append, sample.recv.append, sample.rows.append,
            )
        for conn, recv_ns, raw in reader.messages(connections=conns):
            decode, msgtype, extract, add_stamp, add_recv, add_row = plan[conn.id]
            msg = decode(raw, msgtype)
            header = getattr(msg, "header", None)
            add_stamp(_stamp_ns(header) if header is not None else 0)
            add_recv(recv_ns)
            add_row(extract(msg, msgtype))
        for role, conn in ((wanted[c.topic], c) for c in conns):
            if conn.msgtype in (LASER_SCAN, ODOMETRY, POSE_STAMPED, POSE_COV, TWIST_STAMPED):
                self.topics[role].has_header = True
        if self.topics["tf_static"].rows and self.topics["scan"].rows:
            self._frames(reader, conns, wanted)

    def _frames(self, reader: Reader, conns: list[Connection], wanted: dict[str, str]) -> None:
        """The scan's frame and the robot's base frame (Odometry's child frame), from the
        first message of each, for placing the LiDAR with ``/tf_static``."""
        for conn in conns:
            role = wanted[conn.topic]
            if role not in ("scan", "pose") or conn.msgtype not in (LASER_SCAN, ODOMETRY):
                continue
            for _, _, raw in reader.messages(connections=[conn]):
                msg = _typestore_for(conn.msgtype, conn.msgdef.format, conn.msgdef.data)\
                    .deserialize_cdr(raw, conn.msgtype)
                frame = msg.header.frame_id if role == "scan" else msg.child_frame_id
                self.topics[role].frame = frame.lstrip("/")
                break


def _pose_series(raw: _Topic, name: str, warnings: list[str]) -> tuple[PoseSeries, int | None]:
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


def _sorted(raw: _Topic, offset: int, name: str, warnings: list[str]) -> tuple[np.ndarray, list[Any]]:
    """Stamps on the pose time base and the payload rows, sorted and de-duplicated."""
    _zero_stamps(raw, name, warnings)
    t_ns = _timeline(raw, offset)
    keep = _order(t_ns, name, warnings)
    return t_ns[keep], [raw.rows[i] for i in keep]


def _scan_series(raw: _Topic, offset: int, warnings: list[str]) -> ScanSeries | None:
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


def _cmd_series(raw: _Topic, offset: int, warnings: list[str]) -> CmdSeries | None:
    if not raw.rows:
        return None
    t_ns, rows = _sorted(raw, offset, "cmd_vel", warnings)
    v = np.asarray(rows, dtype=float)
    return CmdSeries(t_ns, v[:, 0], v[:, 1], v[:, 2])


def _point_series(raw: _Topic, offset: int, warnings: list[str]) -> PointSeries | None:
    if not raw.rows:
        return None
    t_ns, rows = _sorted(raw, offset, "person", warnings)
    p = np.asarray(rows, dtype=float)
    return PointSeries(t_ns, p[:, 0], p[:, 1])


def _facts(
    bag: _BagContents, offset: int, cli: EpisodeFacts, cli_given: frozenset[str],
    warnings: list[str],
) -> EpisodeFacts:
    """Merge facts: facts topic < custom_data < goal/outcome topics (if still unknown) < CLI.

    A fact that cannot be read is left out and warned about (``warnings``); a tolerance that
    none gives takes the metrics' default (``EpisodeFacts.with_defaults``)."""
    facts = EpisodeFacts()
    for payload in bag.topics["facts"].rows[:1]:
        try:
            data = json.loads(payload)
            if not isinstance(data, dict):
                raise TypeError(type(data).__name__)
        except (json.JSONDecodeError, TypeError):
            warnings.append(f"facts topic holds no JSON object: {payload[:80]!r}; ignored")
            continue
        topic_facts, given = parse_facts(data, source="facts topic", problems=warnings)
        facts = facts.merged(topic_facts, given=given)
    custom, given = parse_facts(bag.custom, source="custom_data", problems=warnings)
    facts = facts.merged(custom, given=given)
    goals = bag.topics["goal"].rows
    if facts.goal is None and goals:
        facts = facts.merged(EpisodeFacts(goal=goals[-1][:2]), given=frozenset({"goal"}))
    outcome = bag.topics["outcome"]
    if outcome.rows:
        try:
            word, stamp = parse_outcome_event(outcome.rows[-1])
        except ConfigError as err:
            warnings.append(f"{err}; outcome ignored")
        else:
            if stamp is None:
                stamp = int(outcome.recv[-1]) + offset
            if facts.outcome is None:
                facts = facts.merged(EpisodeFacts(outcome=word), given=frozenset({"outcome"}))
            facts = facts.merged(
                EpisodeFacts(outcome_stamp_ns=stamp), given=frozenset({"outcome_stamp_ns"})
            )
    if facts.scan_mount is None and bag.topics["tf_static"].rows:
        mount = _mount_from_tf(bag, warnings)
        if mount is not None:
            facts = facts.merged(EpisodeFacts(scan_mount=mount), given=frozenset({"scan_mount"}))
    return facts.merged(cli, given=cli_given).with_defaults()


#: Frames tried as the robot's base when the pose topic names none (PoseStamped).
BASE_FRAMES = ("base_link", "base_footprint")


def _mount_from_tf(bag: _BagContents, warnings: list[str]) -> Mount | None:
    """The scan frame's pose in the base frame, chained through ``/tf_static`` (the last
    transform of each child wins, projected onto the plane); None with a warning when the
    tree does not join them."""
    parent: dict[str, tuple[str, float, float, float]] = {}
    for rows in bag.topics["tf_static"].rows:
        for up, child, x, y, yaw in rows:
            parent[child] = (up, x, y, yaw)
    scan_frame = bag.topics["scan"].frame
    bases = [bag.topics["pose"].frame] if bag.topics["pose"].frame else list(BASE_FRAMES)
    x = y = yaw = 0.0
    frame, seen = scan_frame, set()
    while frame not in bases:
        if frame not in parent or frame in seen:
            warnings.append(
                f"{TF_STATIC_TOPIC}: no chain of transforms from {' or '.join(bases)!s} to the "
                f"scan frame {scan_frame!r}; the LiDAR is taken at the base's origin"
            )
            return None
        seen.add(frame)
        up, tx, ty, tyaw = parent[frame]
        c, s = math.cos(tyaw), math.sin(tyaw)
        x, y, yaw = tx + c * x - s * y, ty + s * x + c * y, tyaw + yaw
        frame = up
    return Mount(x, y, math.atan2(math.sin(yaw), math.cos(yaw)))


def read_episode(
    path: Path | str,
    topic_map: TopicMap | None = None,
    facts: EpisodeFacts | None = None,
    given: frozenset[str] = frozenset(),
) -> Episode:
    """Read the bag at ``path`` (directory, ``.db3`` or ``.mcap``) into an ``Episode``.

    ``facts``/``given``: values from the command line or a topic map, overriding the bag's.
    Raises ``BagError``, ``TopicError`` or ``EpisodeError`` naming the bag and the problem.
    """
    path = Path(path)
    topic_map = topic_map or TopicMap()
    bag = _BagContents(path, topic_map)
    warnings: list[str] = list(bag.notes)
    raw_pose = bag.topics["pose"]
    if len(raw_pose.rows) < 2:
        msg = (
            f"{str(path)!r}: pose topic {bag.pose_topic!r} has {len(raw_pose.rows)} message(s); "
            "at least 2 poses are needed"
        )
        raise EpisodeError(msg)
    pose, offset = _pose_series(raw_pose, bag.pose_topic, warnings)
    if len(pose) < 2:
        msg = (
            f"{str(path)!r}: pose topic {bag.pose_topic!r} has {len(pose)} usable pose(s) "
            "after dropping NaN and repeated stamps; at least 2 are needed"
        )
        raise EpisodeError(msg)
    merged = _facts(bag, offset, facts or EpisodeFacts(), given, warnings)
    return Episode(
        bag=path,
        facts=merged,
        pose=pose,
        pose_topic=bag.pose_topic,
        scan=_scan_series(bag.topics["scan"], offset, warnings),
        cmd=_cmd_series(bag.topics["cmd_vel"], offset, warnings),
        person=_point_series(bag.topics["person"], offset, warnings),
        warnings=tuple(warnings),
    )
