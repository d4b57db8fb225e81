"""Synthetic episode bags for tests and benchmarks, whose metrics are known by hand.

Test support, not a recorder: tests need bags with analytic answers (a circle has curvature
``1/r``, a wall at 2 m gives a 2 m clearance, a bag with odd facts as real robots write them)
and the benchmark needs bags of a chosen size. The bags are written through the bag contract
(``contract``: topics, ``EpisodeFacts``, ``custom_data``, storages, typestore) exactly as
``pic4rl_bridge``'s recorder writes them, so the reader meets no special case.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from rosbags.rosbag2 import Writer

from . import contract
from .contract import OUTCOMES, STORAGES, EpisodeFacts, typestore
from .topics import normalize_topic

#: Header stamp of ``t_s = 0`` (ns): 2023-11-14, far from zero so that no code can confuse
#: stamps with durations.
DEFAULT_T0_NS = 1_700_000_000_000_000_000

POSE_TYPES = {
    "odometry": "nav_msgs/msg/Odometry",
    "pose_stamped": "geometry_msgs/msg/PoseStamped",
    "pose_cov": "geometry_msgs/msg/PoseWithCovarianceStamped",
}


@dataclass(frozen=True)
class Track:
    """Robot motion sampled at ``t_s`` (s from episode start): pose (m, rad) and body twist
    (``vx``, ``vy`` in m/s, ``wz`` in rad/s)."""

    t_s: np.ndarray
    x: np.ndarray
    y: np.ndarray
    yaw: np.ndarray
    vx: np.ndarray
    vy: np.ndarray
    wz: np.ndarray

    def __post_init__(self) -> None:
        for name in ("t_s", "x", "y", "yaw", "vx", "vy", "wz"):
            object.__setattr__(self, name, np.asarray(getattr(self, name), dtype=np.float64))
        n = len(self.t_s)
        lengths = {name: len(getattr(self, name)) for name in ("x", "y", "yaw", "vx", "vy", "wz")}
        if n == 0 or any(length != n for length in lengths.values()):
            msg = f"track: every array needs len(t_s)={n} > 0 samples, got {lengths!r}"
            raise ValueError(msg)
        if np.any(np.diff(self.t_s) <= 0):
            msg = "track: t_s must be strictly increasing"
            raise ValueError(msg)

    def __len__(self) -> int:
        return len(self.t_s)

    def truncated(self, n: int) -> Track:
        """The first ``n`` samples (an episode that ended early)."""
        return Track(*(getattr(self, k)[:n] for k in ("t_s", "x", "y", "yaw", "vx", "vy", "wz")))


def _times(duration_s: float, dt_s: float) -> np.ndarray:
    """Sample times ``0, dt, 2 dt, ...`` up to ``duration_s`` inclusive (within rounding)."""
    if not (dt_s > 0 and duration_s >= 0):
        msg = f"need dt_s > 0 and duration_s >= 0, got dt_s={dt_s!r}, duration_s={duration_s!r}"
        raise ValueError(msg)
    return np.arange(math.floor(duration_s / dt_s + 1e-9) + 1) * dt_s


def _wrap(angle: np.ndarray) -> np.ndarray:
    """Angle wrapped to [-pi, pi] (rad)."""
    return np.arctan2(np.sin(angle), np.cos(angle))


def straight_line(
    speed_mps: float,
    duration_s: float,
    dt_s: float = 0.1,
    *,
    start: tuple[float, float, float] = (0.0, 0.0, 0.0),
) -> Track:
    """Constant speed along the start heading: path length ``speed * duration``, no turning."""
    t = _times(duration_s, dt_s)
    x0, y0, yaw0 = start
    ones = np.ones_like(t)
    return Track(
        t, x0 + speed_mps * t * math.cos(yaw0), y0 + speed_mps * t * math.sin(yaw0),
        yaw0 * ones, speed_mps * ones, 0 * ones, 0 * ones,
    )  # fmt: skip


def circle(
    radius_m: float,
    speed_mps: float,
    duration_s: float,
    dt_s: float = 0.1,
    *,
    center: tuple[float, float] = (0.0, 0.0),
) -> Track:
    """Counter-clockwise circle starting at its lowest point heading +x (yaw 0).

    Positions lie exactly on the circle, yaw is the tangent, ``wz = speed / radius``.
    """
    if radius_m <= 0:
        msg = f"circle: radius_m={radius_m!r} must be positive"
        raise ValueError(msg)
    t = _times(duration_s, dt_s)
    heading = speed_mps / radius_m * t
    ones = np.ones_like(t)
    return Track(
        t, center[0] + radius_m * np.sin(heading), center[1] - radius_m * np.cos(heading),
        _wrap(heading), speed_mps * ones, 0 * ones, speed_mps / radius_m * ones,
    )  # fmt: skip


def speed_ramp(jerk_mps3: float, duration_s: float, dt_s: float = 0.1) -> Track:
    """Straight along +x from rest with constant jerk: ``a = j t``, ``v = j t²/2``,
    ``x = j t³/6``."""
    t = _times(duration_s, dt_s)
    zeros = np.zeros_like(t)
    return Track(t, jerk_mps3 * t**3 / 6, zeros, zeros, 0.5 * jerk_mps3 * t**2, zeros, zeros)


def from_waypoints(
    points: Sequence[tuple[float, float]],
    speed_mps: float,
    dt_s: float = 0.1,
    *,
    yaw_rate_radps: float | None = None,
) -> Track:
    """Piecewise-linear path through ``points`` at constant speed, yaw along each segment.

    With ``yaw_rate_radps`` the robot stops at each corner and turns in place at that rate
    (as a differential drive does); without it the heading jumps at corners and ``wz`` is 0.
    The last sample is the last point, even when the duration is not a multiple of ``dt_s``.
    """
    pts = np.asarray(points, dtype=np.float64)
    if pts.ndim != 2 or pts.shape[1] != 2 or len(pts) < 2 or speed_mps <= 0:
        msg = f"from_waypoints: need >= 2 points (x, y) and speed_mps > 0, got {points!r}"
        raise ValueError(msg)
    seg = np.diff(pts, axis=0)
    keep = np.hypot(seg[:, 0], seg[:, 1]) > 0
    starts, seg = pts[:-1][keep], seg[keep]
    if not len(seg):
        msg = f"from_waypoints: the points {points!r} never move"
        raise ValueError(msg)
    headings = np.arctan2(seg[:, 1], seg[:, 0])
    # Phases: (start time, duration, x0, y0, yaw0, vx, wz), each a move or a turn in place.
    phases: list[tuple[float, ...]] = []
    clock = 0.0
    for i, (p, d, heading) in enumerate(zip(starts, seg, headings)):
        if i > 0 and yaw_rate_radps:
            turn = float(_wrap(heading - headings[i - 1]))
            rate = math.copysign(abs(yaw_rate_radps), turn)
            phases.append((clock, abs(turn) / abs(yaw_rate_radps), *p, headings[i - 1], 0, rate))
            clock += phases[-1][1]
        phases.append((clock, float(np.hypot(*d)) / speed_mps, *p, heading, speed_mps, 0.0))
        clock += phases[-1][1]
    t = _times(clock, dt_s)
    if clock - t[-1] > 1e-9:
        t = np.append(t, clock)
    table = np.asarray(phases)
    idx = np.clip(np.searchsorted(table[:, 0], t, side="right") - 1, 0, len(table) - 1)
    t0, _, x0, y0, yaw0, vx, wz = table[idx].T
    tau = t - t0
    yaw = yaw0 + wz * tau
    return Track(
        t, x0 + vx * tau * np.cos(yaw0), y0 + vx * tau * np.sin(yaw0), _wrap(yaw),
        vx, np.zeros_like(t), wz,
    )  # fmt: skip


@dataclass(frozen=True)
class Obstacles:
    """A 2D world for ray casting: cylinders ``(cx, cy, r)`` and walls ``(x0, y0, x1, y1)`` (m)."""

    circles: tuple[tuple[float, float, float], ...] = ()
    segments: tuple[tuple[float, float, float, float], ...] = ()


def cast_scan(
    x: float,
    y: float,
    yaw: float,
    obstacles: Obstacles,
    *,
    n_beams: int = 360,
    angle_min: float = -math.pi,
    angle_max: float | None = None,
    range_min: float = 0.05,
    range_max: float = 10.0,
) -> np.ndarray:
    """Exact ranges (m, float32) of a 2D LiDAR at ``(x, y, yaw)``: ``n_beams`` bearings evenly
    from ``angle_min`` to ``angle_max`` inclusive, by default the full circle in steps of
    ``2 pi / n_beams`` (as ``write_episode_bag`` records them).

    As real drivers do (REP 117): ``+inf`` where nothing lies within ``range_max``, ``-inf``
    where the nearest hit is closer than ``range_min``.
    """
    if angle_max is None:
        angle_max = math.pi - 2 * math.pi / n_beams
    bearing = yaw + np.linspace(angle_min, angle_max, n_beams)
    dx, dy = np.cos(bearing)[:, None], np.sin(bearing)[:, None]
    best = np.full(n_beams, np.inf)
    if obstacles.circles:
        c = np.asarray(obstacles.circles, dtype=np.float64)
        ox, oy = c[:, 0] - x, c[:, 1] - y
        b = dx * ox + dy * oy  # distance along the ray to the point nearest the centre
        disc = b**2 - (ox**2 + oy**2 - c[:, 2] ** 2)
        root = np.sqrt(np.where(disc >= 0, disc, np.nan))
        near, far = b - root, b + root
        hit = np.where(near >= 0, near, np.where(far >= 0, far, np.inf))  # NaN: a miss
        best = np.minimum(best, hit.min(axis=1))
    if obstacles.segments:
        s = np.asarray(obstacles.segments, dtype=np.float64)
        ax, ay = s[:, 0] - x, s[:, 1] - y
        ex, ey = s[:, 2] - s[:, 0], s[:, 3] - s[:, 1]
        denom = dx * ey - dy * ex
        with np.errstate(divide="ignore", invalid="ignore"):
            t = (ax * ey - ay * ex) / denom  # along the ray
            u = (ax * dy - ay * dx) / denom  # along the segment, 0..1
        ok = (denom != 0) & (t >= 0) & (u >= 0) & (u <= 1)
        best = np.minimum(best, np.where(ok, t, np.inf).min(axis=1))
    ranges = np.where(best > range_max, np.inf, best)
    return np.where(ranges < range_min, -np.inf, ranges).astype(np.float32)


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
    log time. ``facts`` are typed, or plain values by key (a test's odd or broken facts, as
    real robots' bags carry them). ``write_metadata=False`` leaves the bag as a killed recorder
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
    if outcome is not None:
        event = contract.outcome_event(outcome, last)
        records.append((last, 9, contract.OUTCOME_TOPIC, make.string(event)))
        values["outcome"] = outcome
    _write(path, records, storage, receive_offset_ns, contract.encode_custom_data(values))
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
           custom: Mapping[str, str]) -> None:
    """Write ``records`` in time order (log time: header time + ``receive_offset_ns``) and
    ``custom`` as the ``custom_data``."""
    records.sort(key=lambda r: (r[0], r[1]))
    ts = typestore()
    with Writer(path, version=9, storage_plugin=STORAGES[storage]) as writer:
        connections: dict[str, Any] = {}
        for ns, _, topic, message in records:
            msgtype = message.__msgtype__
            if topic not in connections:
                connections[topic] = writer.add_connection(topic, msgtype, typestore=ts)
            data = ts.serialize_cdr(message, msgtype)
            writer.write(connections[topic], ns + receive_offset_ns, data)
        for key, value in custom.items():
            writer.set_custom_data(key, value)
