"""Read one bag into an ``Episode``: only the topics the metrics need, only once.

The bag is any ``bagfile`` opens (rosbag2 of any storage, version or compression; ROS 1);
``topics.choose_topics`` picks its topics; ``timebase`` puts their samples on one time base.
The pose comes from a pose topic, or from a chain of ``/tf`` and ``/tf_static`` transforms
(``tf``). A fact or an outcome that cannot be read is left out with a warning: the metrics that
do not need it stay. The LiDAR's mount is read from ``/tf_static`` when the facts do not give it.
"""

from __future__ import annotations

import contextlib
import json
import math
from collections import defaultdict
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
from rosbags.interfaces import Connection
from tqdm import tqdm

from pic4rl_base.errors import ConfigError
from pic4rl_base.geometry import Pose2D

from ..contract import TF_STATIC_TOPIC, EpisodeFacts, parse_facts, parse_outcome_event
from ..core.plausibility import check_one_track
from ..core.roles import LASER_SCAN, ODOMETRY, ROLE_TABLE, SERIES_ROLES, TF_MESSAGE, has_header, pose_row
from ..core.scan_summary import ScanStream
from ..core.series import Episode, PoseSeries
from ..core.tasks.seen import reader_stream
from ..core.timebase import ONE_SOURCE_ROLES, Samples, one_source, pose_series
from ..errors import CorruptBagError, EpisodeError
from . import tf
from .bagfile import OpenBag, bag_errors
from .topics import TopicMap, choose_topics


def _stamp_ns(header: Any) -> int:
    return int(header.stamp.sec) * 1_000_000_000 + int(header.stamp.nanosec)


def _tf_extract(msg: Any, _msgtype: str) -> list[tf.Row]:
    return tf.tf_rows(msg)


#: Bags of at least this many messages show a progress bar when asked (about 20 min of a robot
#: with 40 Hz scans and 50 Hz odometry).
LONG_BAG_MESSAGES = 100_000

#: Per role, the payload kept of each message (a TFMessage's transforms whatever the role).
_EXTRACTORS: dict[str, Callable[[Any, str], Any]] = {
    "pose": pose_row, **{role.name: role.extract for role in ROLE_TABLE}}


class _BagContents:
    """Raw samples of the mapped topics of one open bag: every topic but the scan in one pass
    (on opening), then the scan, summarized as it is read with the episode's facts
    (``read_scans``)."""

    def __init__(self, path: Path, bag: OpenBag, topic_map: TopicMap, progress: bool) -> None:
        self.path = path
        self.topics: dict[str, Samples] = defaultdict(Samples)
        available = {c.topic: c.msgtype for c in bag.connections}
        chosen = choose_topics(topic_map, available, repr(str(path)))
        self.custom = bag.custom
        self.pose_topic, self.notes = chosen.pose, list(chosen.notes)
        self.wanted = chosen.wanted
        conns = [c for c in bag.connections if c.topic in chosen.wanted]
        self._scans = [c for c in conns if chosen.wanted[c.topic] == "scan"]
        self.has_scan = False  # a scan message seen (by ``_frames``, when /tf_static is there)
        total = sum(c.msgcount for c in conns)
        self._bar = tqdm(total=total, desc=path.name, unit="msg", leave=False,
                         disable=not progress or total < LONG_BAG_MESSAGES)
        for conn in conns:
            if chosen.wanted[conn.topic] in ONE_SOURCE_ROLES and conn.msgtype != TF_MESSAGE:
                one_source(conn.topic, bag.publishers(conn))
        self._read(bag, [c for c in conns if c not in self._scans])
        if self.topics["tf_static"].rows and self._scans:
            self._frames(bag, conns)

    def read_scans(self, bag: OpenBag, facts: EpisodeFacts, full: bool, sample: int,
                   pose: PoseSeries, offset: int | None) -> None:
        """Read the scan topic, reduced to what the metrics use (``ScanStream``; whole scans
        too when ``full``, at most ``sample`` of them when that is given; an exploration's
        area seen integrated on the way, placed by ``pose``)."""
        if self._scans:
            raw = self.topics["scan"]
            seen = None if full else reader_stream(facts, pose, raw, offset)
            raw.rows = ScanStream(facts, full=full, sample=sample, seen=seen)
            self._read(bag, self._scans)
        self._bar.close()

    def _read(self, bag: OpenBag, conns: list[Connection]) -> None:
        wanted, update = self.wanted, self._bar.update
        for own, messages in bag.streams(conns):  # one storage file at a time
            # Per connection, resolved once: decoder, extractor and the lists to append to.
            plan = {}
            for conn in own:
                role = wanted[conn.topic]
                extract = _tf_extract if conn.msgtype == TF_MESSAGE else _EXTRACTORS[role]
                sample = self.topics[role]
                sample.topic = conn.topic
                plan[conn.id] = (
                    bag.decoder(conn), conn.msgtype, extract,
                    sample.stamp.append, sample.recv.append, sample.rows.append,
                )
            n = 0
            for n, (conn, recv_ns, raw) in enumerate(messages, 1):
                decode, msgtype, extract, add_stamp, add_recv, add_row = plan[conn.id]
                msg = decode(raw, msgtype)
                header = getattr(msg, "header", None)
                add_stamp(_stamp_ns(header) if header is not None else 0)
                add_recv(recv_ns)
                add_row(extract(msg, msgtype))
                if not n % 4096:
                    update(4096)
            update(n % 4096)
        for role, conn in ((wanted[c.topic], c) for c in conns):
            if has_header(conn.msgtype):
                self.topics[role].has_header = True

    def _frames(self, bag: OpenBag, conns: list[Connection]) -> None:
        """The scan's frame and the robot's base frame (Odometry's child frame), from the
        first message of each, for placing the LiDAR with ``/tf_static``."""
        for conn in conns:
            role = self.wanted[conn.topic]
            if role not in ("scan", "pose") or conn.msgtype not in (LASER_SCAN, ODOMETRY):
                continue
            for _, messages in bag.streams([conn]):
                first = next(iter(messages), None)
                if first is None:
                    continue
                msg = bag.decoder(conn)(first[2], conn.msgtype)
                frame = msg.header.frame_id if role == "scan" else msg.child_frame_id
                self.topics[role].frame = frame.lstrip("/")
                self.has_scan |= role == "scan"
                break


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
    if facts.scan_mount is None and bag.topics["tf_static"].rows and bag.has_scan:
        mount = _mount_from_tf(bag, warnings)
        if mount is not None:
            facts = facts.merged(EpisodeFacts(scan_mount=mount), given=frozenset({"scan_mount"}))
    return facts.merged(cli, given=cli_given).with_defaults()


#: Frames tried as the robot's base when the pose topic names none (PoseStamped).
BASE_FRAMES = ("base_link", "base_footprint")


def _mount_from_tf(bag: _BagContents, warnings: list[str]) -> Pose2D | None:
    """The scan frame's pose in the base frame, chained through ``/tf_static`` (the last
    transform of each child wins, projected onto the plane); None with a warning when the
    tree does not join them."""
    static = tf.edges([], bag.topics["tf_static"].rows)
    scan_frame = bag.topics["scan"].frame
    bases = [bag.topics["pose"].frame] if bag.topics["pose"].frame else list(BASE_FRAMES)
    for base in bases:
        try:
            return Pose2D(*tf.static_pose(static, base, scan_frame))
        except tf.ChainError:
            continue
    warnings.append(
        f"{TF_STATIC_TOPIC}: no chain of transforms from {' or '.join(bases)!s} to the "
        f"scan frame {scan_frame!r}; the LiDAR is taken at the base's origin"
    )
    return None


def _tf_pose(bag: _BagContents, frames: tuple[str, str], warnings: list[str]) -> Samples:
    """The pose samples of ``frames``' child in their parent, from the TF topics read."""
    parent, child = frames
    raw = bag.topics["pose"]
    tree = tf.edges(list(zip(raw.recv, raw.rows, strict=True)), bag.topics["tf_static"].rows)
    try:
        t_ns, recv, xy_yaw = tf.chain_poses(tree, parent, child, warnings)
    except tf.ChainError as err:
        msg = f"{str(bag.path)!r}: {bag.pose_topic} and its _static: {err}"
        raise EpisodeError(msg) from err
    pose = Samples()
    pose.stamp, pose.recv = t_ns.tolist(), recv.tolist()
    pose.rows = np.column_stack([xy_yaw, np.full((len(t_ns), 3), math.nan)]).tolist()
    pose.frame, pose.has_header = child, True
    bag.pose_topic = f"{bag.pose_topic}:{parent}->{child}"
    return pose


def read_episode(
    path: Path | str,
    topic_map: TopicMap | None = None,
    facts: EpisodeFacts | None = None,
    given: frozenset[str] = frozenset(),
    *,
    full_scans: bool = False,
    progress: bool = False,
    scan_sample: int = 0,
) -> Episode:
    """Read the bag at ``path`` (see ``bagfile``) into an ``Episode``.

    ``facts``/``given``: values from the command line or a topic map, overriding the bag's.
    The scan is kept as what the metrics use of it (``ScanSummary``); ``full_scans`` keeps
    every beam (``ScanSeries``, for plots and videos); ``scan_sample`` keeps, beside the
    summary, at most that many whole scans evenly spread over the bag (``ScanSummary.sample``,
    for maps; memory bounded in the bag's length). ``progress``: a bar on stderr for a
    long bag. Raises ``BagError`` (``CorruptBagError`` for a bag mixing two sources),
    ``TopicError`` or ``EpisodeError`` naming the bag and the problem.
    """
    path = Path(path)
    topic_map = topic_map or TopicMap()
    try:
        with contextlib.ExitStack() as stack:
            with bag_errors(path):
                opened = stack.enter_context(OpenBag(path))
                bag = _BagContents(path, opened, topic_map, progress)
            warnings: list[str] = list(bag.notes)
            pose, offset = _pose(bag, topic_map, warnings)
            merged = _facts(bag, offset, facts or EpisodeFacts(), given, warnings)
            check_one_track(pose, merged.max_speed_mps, bag.pose_topic)
            with bag_errors(path):
                bag.read_scans(opened, merged, full_scans, scan_sample, pose, offset)
            inputs = {name: role.build(bag.topics[role.name], offset, warnings)  # type: ignore[misc]
                      for name, role in SERIES_ROLES.items()}
    except CorruptBagError as err:
        raise CorruptBagError(f"{str(path)!r}: {err}") from None
    return Episode(bag=path, facts=merged, pose=pose, pose_topic=bag.pose_topic, inputs=inputs,
                   warnings=tuple(warnings))


def _pose(bag: _BagContents, topic_map: TopicMap,
          warnings: list[str]) -> tuple[PoseSeries, int | None]:
    """The pose series and its header-minus-receive offset (ns); ``EpisodeError`` for fewer
    than two usable poses."""
    path = bag.path
    if topic_map.pose_frames is not None:
        bag.topics["pose"] = _tf_pose(bag, topic_map.pose_frames, warnings)
    raw_pose = bag.topics["pose"]
    if len(raw_pose.rows) < 2:
        msg = (
            f"{str(path)!r}: pose topic {bag.pose_topic!r} has {len(raw_pose.rows)} message(s); "
            "at least 2 poses are needed"
        )
        raise EpisodeError(msg)
    pose, offset = pose_series(raw_pose, bag.pose_topic, warnings)
    if len(pose) < 2:
        msg = (
            f"{str(path)!r}: pose topic {bag.pose_topic!r} has {len(pose)} usable pose(s) "
            "after dropping NaN and repeated stamps; at least 2 are needed"
        )
        raise EpisodeError(msg)
    return pose, offset
