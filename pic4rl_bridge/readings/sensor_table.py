"""The frame's sensors in one table, and the one function that builds a ``SensorFrame``.

Each reading of ``SensorFrame`` is one ``FrameSensor``: the sim topic that carries it (its
type, QoS and default name, ``topics.<name>`` in the config, with its doc), how its message
decodes, and how the in-process transport reads the same value straight from the engine. Both
transports build frames through ``build_frame``; a task names the sensors it needs in its
``required`` and reads them from ``SensorFrame.readings`` with the same names.
"""

from __future__ import annotations

from collections.abc import Callable, Collection, Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from pic4rl_base.goal import Goal
from pic4rl_base.plugins import load_group
from pic4rl_base.geometry import Pose2D
from pic4rl_sim.engine.geometry import Twist2D
from pic4rl_sim.engine.sensor_kinds import sonar, stereo, uwb
from pic4rl_sim.interfaces import (DEPTH_IMAGE, PEOPLE, PERSON_POSE, PLAN, SCAN, SONAR, STEREO_DEPTH,
                                   UWB, Interface)

from . import cdr, decode
from .frame import ScanData, SensorFrame, as_published

_ORIGIN = Pose2D(0.0, 0.0, 0.0)


@dataclass(frozen=True)
class FrameSensor:
    """One reading of ``SensorFrame``: ``name`` is its key in ``readings``, the task's
    ``required`` entry and the ``topics`` key; ``interface`` the sim topic that carries it."""

    name: str
    interface: Interface
    #: (message, its sensor's mount, topic name) → the field's value.
    decode: Callable[[Any, Pose2D, str], Any]
    #: (engine, its sensor's mount) → the same value as the decoded message, or ``None`` when
    #: the engine has no such sensor (the in-process transport when it does not record).
    read: Callable[[Any, Pose2D], Any]
    #: The robot's sensor kind (a ``SENSOR_TABLE`` name, a ``RobotInfo.mounts`` key) that
    #: makes the reading and whose mount ``decode`` and ``read`` take; ``None``: no mount.
    kind: str | None = None
    #: Published once an episode (subscribed like the goal, decoded once per message).
    episodic: bool = False
    #: What ``topics.<name>``'s doc adds to the message type.
    topic_note: str = ""
    #: (CDR bytes, mount, topic name) → ``decode``'s value read straight from the bytes
    #: (``cdr``: no message objects built), or ``None`` where they cannot be read so and
    #: ``decode`` takes the deserialized message; ``None``: always ``decode``.
    read_cdr: Callable[[bytes, Pose2D, str], Any] | None = None

    def mount(self, mounts: Mapping[str, Pose2D]) -> Pose2D:
        """The mount of this reading's sensor in ``mounts`` (the origin without one)."""
        return mounts.get(self.kind, _ORIGIN) if self.kind else _ORIGIN

    def reading(self, entry: Any, mount: Pose2D, topic: str) -> Any:
        """The value of ``entry``'s latest message (an object with its CDR bytes ``data`` and
        the message they deserialize to, ``msg``): read from the bytes where ``read_cdr``
        can, else decoded from the message."""
        value = (self.read_cdr(entry.data, mount, topic)
                 if self.read_cdr is not None and entry.data is not None else None)
        return self.decode(entry.msg, mount, topic) if value is None else value

    @property
    def default_topic(self) -> str:
        """``topics.<name>``'s default: the sim's topic."""
        return self.interface.name

    @property
    def topic_doc(self) -> str:
        """``topics.<name>``'s doc: the message type and what it carries."""
        return f"{self.interface.type}{self.topic_note}"


def _f32(value: float) -> float:
    """``value`` as a float32 message field holds it."""
    return float(np.float32(value))


def _read_scan(engine: Any, mount: Pose2D) -> ScanData | None:
    lidar = engine.lidar
    if lidar is None:
        return None
    return ScanData(engine.scan().astype(np.float32), _f32(lidar.angle_min_rad),
                    _f32(lidar.angle_increment_rad), _f32(lidar.range_min_m),
                    _f32(lidar.range_max_m), mount)


def _read_depth(engine: Any, mount: Pose2D) -> np.ndarray | None:
    return None if engine.depth is None else engine.depth_image().astype(np.float32)


def _read_person(engine: Any, mount: Pose2D) -> Pose2D | None:
    seen = engine.person_pose()
    return None if seen is None else as_published(seen[0])


def _read_people(engine: Any, mount: Pose2D) -> np.ndarray | None:
    people = engine.people()
    if people is None:
        return None
    return np.array([tuple(as_published(Pose2D(float(x), float(y), float(yaw))))
                     for (x, y), yaw in zip(*people)], dtype=np.float64).reshape(-1, 3)


def _depth_cdr(data: bytes, mount: Pose2D, topic: str) -> np.ndarray | None:
    image = cdr.image(data)
    return None if image is None else decode.depth_image(image, topic=topic)


READING_TABLE = (
    FrameSensor("scan", SCAN, lambda msg, mount, topic: decode.scan(msg, mount), _read_scan,
                kind="lidar", read_cdr=lambda data, mount, topic: cdr.scan(data, mount)),
    FrameSensor("depth", DEPTH_IMAGE,
                lambda msg, mount, topic: decode.depth_image(msg, topic=topic), _read_depth,
                topic_note=" (32FC1)", read_cdr=_depth_cdr),
    FrameSensor("person", PERSON_POSE, lambda msg, mount, topic: decode.planar_pose(msg.pose),
                _read_person, topic_note=" (personMonitoring)"),
    FrameSensor("people", PEOPLE, lambda msg, mount, topic: decode.people(msg), _read_people,
                topic_note=": the crowd, one (x, y, yaw) row a person in the world frame"),
    FrameSensor("plan", PLAN, lambda msg, mount, topic: decode.path(msg),
                lambda engine, mount: engine.plan(), episodic=True,
                topic_note=": the global plan of goal_input plan (the sim's, or any planner's, "
                "e.g. nav2's /plan)"),
    *(FrameSensor(sonar.reading_name(i), topic, sonar.decode, sonar.cone_reader(i),
                  kind=sonar.NAME) for i, topic in enumerate(SONAR)),
    *(FrameSensor(uwb.reading_name(target), topic, uwb.decode, uwb.target_reader(target),
                  kind=uwb.NAME) for target, topic in zip(uwb.TARGETS, UWB)),
    FrameSensor("stereo_depth", STEREO_DEPTH,
                lambda msg, mount, topic: decode.depth_image(msg, topic=topic), stereo.read_depth,
                kind=stereo.NAME, topic_note=" (32FC1; NaN: no match)", read_cdr=_depth_cdr),
)
#: A user's readings, after pic4rl's: each a ``FrameSensor`` that its package names in this
#: entry-point group under the reading's name (its sensor in ``pic4rl.sensors``).
READING_GROUP = "pic4rl.readings"
READING_TABLE += tuple(load_group(READING_GROUP, FrameSensor,
                                  taken={s.name for s in READING_TABLE}).values())
#: The frame's sensors by name, in the table's order.
BY_NAME = {s.name: s for s in READING_TABLE}


def build_frame(stamp_ns: int, odometry: tuple[Pose2D, Twist2D],
                goal: Goal | None, wanted: Collection[str],
                value: Callable[[FrameSensor], Any]) -> SensorFrame:
    """The frame at ``stamp_ns``: pose and twist from ``odometry``, and ``value(sensor)`` for
    each sensor ``wanted`` in the table's order (the rest, and a ``None`` value, absent)."""
    pose, twist = odometry
    readings = {}
    for sensor in READING_TABLE:
        if sensor.name in wanted and (reading := value(sensor)) is not None:
            readings[sensor.name] = reading
    return SensorFrame(stamp_ns, pose, twist, goal, readings)
