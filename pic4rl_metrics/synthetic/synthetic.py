"""Synthetic episode bags for tests and benchmarks, whose metrics are known by hand.

Test support, not a recorder: tests need bags with analytic answers (the tracks and worlds of
``synthetic_tracks``; a bag with odd facts as real robots write them) and the benchmark needs
bags of a chosen size. The bags are written through the metrics' one bag writer
(``bagwriter``), the one ``pic4rl_bridge``'s recorder writes through, so the reader meets no
special case. It ships in the package, not under ``tests/``: the benchmark scripts
(``benchmarks/``) import it, as may the tests of a user's metric plugin, and it needs nothing
beyond the metrics' own dependencies.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from .. import contract
from ..bags.bagwriter import BagWriter
from ..contract import OUTCOMES, STORAGES, EpisodeFacts, typestore
from .synthetic_crowd import people_records
from .synthetic_tracks import (
    Obstacles,
    Track,
    cast_scan,
    circle,
    from_waypoints,
    speed_ramp,
    straight_line,
)
from ..bags.topics import normalize_topic

__all__ = ["DEFAULT_T0_NS", "POSE_TYPES", "Obstacles", "Track", "cast_scan", "circle",
           "from_waypoints", "speed_ramp", "straight_line", "write_episode_bag", "write_long_bag"]

#: Header stamp of ``t_s = 0`` (ns): 2023-11-14, far from zero so that no code can confuse
#: stamps with durations.
DEFAULT_T0_NS = 1_700_000_000_000_000_000

POSE_TYPES = {
    "odometry": "nav_msgs/msg/Odometry",
    "pose_stamped": "geometry_msgs/msg/PoseStamped",
    "pose_cov": "geometry_msgs/msg/PoseWithCovarianceStamped",
}


class _Messages:
    """Builds the ROS 2 messages of one track from the typestore's classes."""

    def __init__(self, track: Track, stamp_ns: np.ndarray) -> None:
        self.t = typestore().types
        self.track, self.stamp_ns = track, stamp_ns

    def header(self, ns: int, frame: str) -> Any:
        sec, nanosec = divmod(int(ns), 1_000_000_000)
        return self.t["std_msgs/msg/Header"](
            self.t["builtin_interfaces/msg/Time"](sec, nanosec), frame
        )

    def pose(self, x: float, y: float, yaw: float) -> Any:
        q = self.t["geometry_msgs/msg/Quaternion"](0.0, 0.0, math.sin(yaw / 2), math.cos(yaw / 2))
        return self.t["geometry_msgs/msg/Pose"](self.t["geometry_msgs/msg/Point"](x, y, 0.0), q)

    def pose_stamped(self, ns: int, x: float, y: float, yaw: float) -> Any:
        return self.t["geometry_msgs/msg/PoseStamped"](self.header(ns, "map"), self.pose(x, y, yaw))

    def twist(self, i: int) -> Any:
        vec, tr = self.t["geometry_msgs/msg/Vector3"], self.track
        return self.t["geometry_msgs/msg/Twist"](vec(tr.vx[i], tr.vy[i], 0.0), vec(0, 0, tr.wz[i]))

    def robot(self, i: int, kind: str) -> Any:
        """Pose sample ``i`` as ``kind`` (a key of ``POSE_TYPES``)."""
        tr, ns = self.track, int(self.stamp_ns[i])
        if kind == "pose_stamped":
            return self.pose_stamped(ns, tr.x[i], tr.y[i], tr.yaw[i])
        pose = self.t["geometry_msgs/msg/PoseWithCovariance"](
            self.pose(tr.x[i], tr.y[i], tr.yaw[i]), np.zeros(36)
        )
        if kind == "pose_cov":
            return self.t[POSE_TYPES[kind]](self.header(ns, "map"), pose)
        twist = self.t["geometry_msgs/msg/TwistWithCovariance"](self.twist(i), np.zeros(36))
        return self.t[POSE_TYPES[kind]](self.header(ns, "odom"), "base_link", pose, twist)

    def scan(self, ns: int, ranges: np.ndarray) -> Any:
        inc = 2 * math.pi / len(ranges)
        return self.t["sensor_msgs/msg/LaserScan"](
            self.header(ns, "base_scan"), -math.pi, math.pi - inc, inc, 0.0, 0.0, 0.05, 10.0,
            ranges, np.zeros(0, dtype=np.float32),
        )  # fmt: skip

    def string(self, data: str) -> Any:
        return self.t["std_msgs/msg/String"](data)


#: A bag's messages: (header time ns, order among equal times, topic, message).
_Record = tuple[int, int, str, Any]


def write_episode_bag(
    path: Path,
    track: Track,
    *,
    obstacles: Obstacles | None = None,
    scan_every: int = 1,
    scans: Sequence[np.ndarray] | None = None,
    n_beams: int = 360,
    pose_topic: str = contract.GROUND_TRUTH_TOPIC,
    pose_type: str = "odometry",
    also_odom: bool = True,
    cmd: bool = True,
    cmd_stamped: bool = False,
    goal: tuple[float, float] | None = None,
    person: Track | None = None,
    people: Sequence[Track] = (),
    facts: EpisodeFacts | Mapping[str, object] | None = None,
    outcome: str | None = None,
    t0_ns: int = DEFAULT_T0_NS,
    receive_offset_ns: int = 0,
    storage: str = "sqlite3",
    write_metadata: bool = True,
) -> Path:
    """Write ``track`` as one episode bag at ``path`` (a new directory) and return it.

    Header stamps are ``t0_ns + t_s`` (ns); bag log times add ``receive_offset_ns``, as a
    recorder's wall clock differs from sim time. Headerless ``Twist`` commands carry only the
    log time. ``people``: the people topic's PoseArrays (``synthetic_crowd``). ``facts`` are
    typed, or plain values by key (a test's odd or broken facts, as real robots' bags carry
    them). ``write_metadata=False`` leaves the bag as a killed recorder
    does: no ``metadata.yaml``, only the storage file.
    """
    path, pose_topic = Path(path), normalize_topic(pose_topic)
    if path.exists():
        msg = f"{str(path)!r} exists already; synthetic bags never overwrite"
        raise FileExistsError(msg)
    _check(track, pose_topic, pose_type, also_odom, storage, outcome, scan_every, scans,
           obstacles)
    values = facts.values() if isinstance(facts, EpisodeFacts) else dict(facts or {})
    stamp_ns = t0_ns + np.round(track.t_s * 1e9).astype(np.int64)
    make = _Messages(track, stamp_ns)
    first, last = int(stamp_ns[0]), int(stamp_ns[-1])
    records: list[_Record] = []
    if facts is not None:
        records.append((first, 0, contract.FACTS_TOPIC,
                        make.string(contract.encode_facts_json(values))))
    if goal is not None:
        records.append((first, 1, contract.GOAL_TOPIC, make.pose_stamped(first, *goal, 0.0)))
    records += _track_records(make, pose_topic, pose_type, also_odom, obstacles, scan_every,
                              scans, n_beams, cmd, cmd_stamped)
    if person is not None:
        records += _person_records(make, person, t0_ns)
    records += people_records(people, t0_ns)
    if outcome is not None:
        event = contract.outcome_event(outcome, last)
        records.append((last, 9, contract.OUTCOME_TOPIC, make.string(event)))
        values["outcome"] = outcome
    _write(path, records, storage, receive_offset_ns, values)
    if not write_metadata:
        (path / "metadata.yaml").unlink()
    return path


def _check(track: Track, pose_topic: str, pose_type: str, also_odom: bool, storage: str,
           outcome: str | None, scan_every: int, scans: Sequence[np.ndarray] | None,
           obstacles: Obstacles | None) -> None:
    """``ValueError`` naming the first of ``write_episode_bag``'s arguments that is wrong."""
    clash = also_odom and pose_topic == contract.ODOM_TOPIC and pose_type != "odometry"
    bad_scans = scans is not None and (obstacles is not None or len(scans) != len(track))
    for failed, msg in (
        (
            pose_type not in POSE_TYPES,
            f"pose_type={pose_type!r}; expected one of {list(POSE_TYPES)}",
        ),
        (storage not in STORAGES, f"storage={storage!r}; expected one of {list(STORAGES)}"),
        (outcome not in (None, *OUTCOMES), f"outcome={outcome!r}; expected one of {OUTCOMES}"),
        (scan_every < 1, f"scan_every={scan_every!r}; expected >= 1"),
        (bad_scans, f"scans: expected one per pose ({len(track)}) and no obstacles"),
        (clash, f"pose_type={pose_type!r} on {pose_topic!r} clashes with also_odom=True"),
    ):
        if failed:
            raise ValueError(msg)


def _track_records(make: _Messages, pose_topic: str, pose_type: str, also_odom: bool,
                   obstacles: Obstacles | None, scan_every: int,
                   scans: Sequence[np.ndarray] | None, n_beams: int, cmd: bool,
                   cmd_stamped: bool) -> list[_Record]:
    """Per pose of the track: the pose, its odometry copy, the scan and the command."""
    track, records = make.track, []
    odom_copy = also_odom and pose_topic != contract.ODOM_TOPIC
    for i, ns in enumerate(make.stamp_ns.tolist()):
        records.append((ns, 2, pose_topic, make.robot(i, pose_type)))
        if odom_copy:
            records.append((ns, 3, contract.ODOM_TOPIC, make.robot(i, "odometry")))
        if obstacles is not None and i % scan_every == 0:
            ranges = cast_scan(track.x[i], track.y[i], track.yaw[i], obstacles, n_beams=n_beams)
            records.append((ns, 4, contract.SCAN_TOPIC, make.scan(ns, ranges)))
        elif scans is not None:
            ranges = np.asarray(scans[i], dtype=np.float32)
            records.append((ns, 4, contract.SCAN_TOPIC, make.scan(ns, ranges)))
        if cmd:
            twist = make.twist(i)
            if cmd_stamped:
                twist = make.t["geometry_msgs/msg/TwistStamped"](
                    make.header(ns, "base_link"), twist
                )
            records.append((ns, 5, contract.CMD_VEL_TOPIC, twist))
    return records


def _person_records(make: _Messages, person: Track, t0_ns: int) -> list[_Record]:
    """The walking person's poses, stamped on the episode's clock."""
    person_ns = t0_ns + np.round(person.t_s * 1e9).astype(np.int64)
    return [(ns, 6, contract.PERSON_TOPIC,
             make.pose_stamped(ns, person.x[i], person.y[i], person.yaw[i]))
            for i, ns in enumerate(person_ns.tolist())]


def _write(path: Path, records: list[_Record], storage: str, receive_offset_ns: int,
           values: Mapping[str, Any]) -> None:
    """Write ``records`` in time order (log time: header time + ``receive_offset_ns``) and
    the facts ``values`` as the ``custom_data``."""
    records.sort(key=lambda r: (r[0], r[1]))
    bag = BagWriter(path, storage=storage)
    for ns, _, topic, message in records:
        bag.write_message(topic, message, ns + receive_offset_ns)
    bag.close(values)


def write_long_bag(path: Path, minutes: float, *, speed_mps: float = 0.5, odom_hz: float = 50.0,
                   scan_hz: float = 40.0, n_beams: int = 720, wall_m: float = 2.0,
                   footprint_radius_m: float = 0.2) -> Path:
    """A long real-robot-shaped log, fast to write: odometry at ``odom_hz`` along +x at
    ``speed_mps`` and scans at ``scan_hz`` whose every beam reads ``wall_m + 0.5 sin(t)``
    (so the nearest obstacle is ``wall_m - 0.5`` and the footprint margin that less the
    radius); facts carry the circular footprint. For the memory benchmark and its test."""
    path = Path(path)
    if path.exists():
        msg = f"{str(path)!r} exists already; synthetic bags never overwrite"
        raise FileExistsError(msg)
    types, store = typestore().types, typestore()
    odom_cls, scan_cls = types["nav_msgs/msg/Odometry"], types["sensor_msgs/msg/LaserScan"]
    make = _Messages(straight_line(speed_mps, 1.0), np.zeros(1, dtype=np.int64))
    odom_ns = DEFAULT_T0_NS + np.round(np.arange(int(minutes * 60 * odom_hz) + 1)
                                       * 1e9 / odom_hz).astype(np.int64)
    scan_ns = DEFAULT_T0_NS + np.round(np.arange(int(minutes * 60 * scan_hz) + 1)
                                       * 1e9 / scan_hz).astype(np.int64)
    inc = 2 * math.pi / n_beams
    zeros, cov = np.zeros(0, dtype=np.float32), np.zeros(36)
    twist = types["geometry_msgs/msg/TwistWithCovariance"](
        types["geometry_msgs/msg/Twist"](types["geometry_msgs/msg/Vector3"](speed_mps, 0.0, 0.0),
                                         types["geometry_msgs/msg/Vector3"](0.0, 0.0, 0.0)), cov)
    bag = BagWriter(path)
    bag.write_facts({"footprint": {"radius_m": footprint_radius_m}}, int(odom_ns[0]))
    odom_t, scan_t = odom_ns.tolist(), scan_ns.tolist()
    i = j = 0
    while i < len(odom_t) or j < len(scan_t):
        if j >= len(scan_t) or (i < len(odom_t) and odom_t[i] <= scan_t[j]):
            ns, t_s = odom_t[i], (odom_t[i] - DEFAULT_T0_NS) * 1e-9
            pose = types["geometry_msgs/msg/PoseWithCovariance"](make.pose(speed_mps * t_s, 0.0,
                                                                           0.0), cov)
            msg = odom_cls(make.header(ns, "odom"), "base_link", pose, twist)
            bag.write("/odom", "nav_msgs/msg/Odometry",
                      bytes(store.serialize_cdr(msg, "nav_msgs/msg/Odometry")), ns)
            i += 1
        else:
            ns, t_s = scan_t[j], (scan_t[j] - DEFAULT_T0_NS) * 1e-9
            ranges = np.full(n_beams, wall_m + 0.5 * math.sin(t_s), dtype=np.float32)
            msg = scan_cls(make.header(ns, "base_scan"), -math.pi, math.pi - inc, inc, 0.0, 0.0,
                           0.05, 10.0, ranges, zeros)
            bag.write(contract.SCAN_TOPIC, "sensor_msgs/msg/LaserScan",
                      bytes(store.serialize_cdr(msg, "sensor_msgs/msg/LaserScan")), ns)
            j += 1
    bag.close({"footprint": {"radius_m": footprint_radius_m}})
    return path
