"""What the ROS transport subscribes to, and with which type and QoS: the pose and goal, the
frame's sensors a task needs (``pic4rl_bridge.readings.sensor_table``), and the topics only
recorded.

Types and QoS come from the sim's interface table (``pic4rl_sim.interfaces``): a topic is
matched as the sim node offers it, keeping ``BRIDGE_HISTORY`` messages so the recorder sees
each; and the messages the transport reads stamps from and publishes (commands). Also what
the transport says of its topics: one gone silent in rate mode (``stale``), and those a wait
heard nothing from, with their publishers' QoS (``silent``).
"""

from __future__ import annotations

import math
import struct
import time
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass, field
from typing import Any

from builtin_interfaces.msg import Time
from geometry_msgs.msg import Twist, TwistStamped
from pic4rl_sim.engine.geometry import Twist2D
from pic4rl_sim.interfaces import (
    GOAL_POSE,
    INTERFACE_TABLE,
    ODOM,
    STEP_TOPICS,
    Cadence,
    Interface,
    QosKind,
    QosSettings,
    bridge_qos,
)
from pic4rl_sim.node.ros_interfaces import ros_type, settings_of, starts_with_stamp
from rclpy.serialization import deserialize_message
from rosgraph_msgs.msg import Clock

from ..config import EnvConfig, SensorQos
from ..errors import ConfigError
from ..readings import decode
from ..readings.sensor_table import READING_TABLE

#: The sim node's state and episode topics by relative name, recordable by name alone.
KNOWN_TOPICS = {i.name: i for i in INTERFACE_TABLE if i.cadence in (Cadence.STEP, Cadence.EPISODE)}
#: A step's topics in the sim's publishing order.
_STEP_ORDER = {t.name: i for i, t in enumerate(STEP_TOPICS)}
def cdr_stamp(data: bytes) -> int:
    """The stamp (ns) of a message that starts with one, read from its CDR bytes: 4 bytes of
    encapsulation (byte 1: 1 = little endian), then ``int32 sec``, ``uint32 nanosec``."""
    sec, nanosec = struct.unpack_from("<iI" if data[1] == 1 else ">iI", data, 4)
    return sec * 1_000_000_000 + nanosec


def stamp_of(msg: Any) -> int | None:
    """A decoded message's stamp (ns): its header's, a clock's, or a ``TFMessage``'s first
    transform's; ``None`` if it has none."""
    if isinstance(msg, Clock):
        return decode.stamp_ns(msg.clock)
    transforms = getattr(msg, "transforms", None)
    header = getattr(transforms[0] if transforms else msg, "header", None)
    return decode.stamp_ns(header) if header is not None else None


def command_message(command: Twist2D, stamped: bool, stamp_ns: int) -> Twist | TwistStamped:
    """``command`` as a ``Twist``, or a ``TwistStamped`` stamped ``stamp_ns``."""
    twist = Twist()
    twist.linear.x, twist.linear.y, twist.angular.z = command.vx, command.vy, command.wz
    if not stamped:
        return twist
    msg = TwistStamped(twist=twist)
    msg.header.stamp = Time(sec=stamp_ns // 1_000_000_000, nanosec=stamp_ns % 1_000_000_000)
    return msg


class Topic:
    """One raw subscription: the latest message's CDR bytes (``data``), its stamp and arrival
    time; ``msg`` deserializes them when read (once per message)."""

    def __init__(self, name: str, type_name: str) -> None:
        self.name, self.type_name = name, type_name
        self.data: bytes | None = None
        self._msg: Any = None
        self._msg_data: bytes | None = None  # the bytes ``_msg`` was deserialized from
        self.stamp_ns = -1
        self.received_s = -math.inf  # time.monotonic() of the latest message
        self.qos = QosSettings()  # the subscription's
        self.count = 0
        self.recorded = False
        self.episodic = False  # published once per episode (goal, plan), not every step

    @property
    def msg(self) -> Any:
        """The latest message deserialized; ``None`` before the first. A step reads its
        odometry and sensors from ``data`` (``cdr``): only what has no CDR reader, or what
        is published once an episode, comes through here."""
        if self.data is not None and self._msg_data is not self.data:
            self._msg = deserialize_message(self.data, ros_type(self.type_name))
            self._msg_data = self.data
        return self._msg


def receiver(entry: Topic,
             deliver: Callable[[Topic, bytes, int], None]) -> Callable[[bytes], None]:
    """A raw subscription's callback: keeps ``entry``'s latest bytes, stamp (read from the
    CDR bytes; deserialized only for a type that does not start with one) and arrival time,
    and hands a recorded one's bytes and stamp to ``deliver``."""
    stamped = starts_with_stamp(ros_type(entry.type_name))

    def on_message(data: bytes) -> None:
        entry.data = data
        stamp = cdr_stamp(data) if stamped else stamp_of(entry.msg)
        stamp = time.time_ns() if stamp is None else stamp
        entry.stamp_ns, entry.received_s = stamp, time.monotonic()
        entry.count += 1
        if entry.recorded:
            deliver(entry, data, stamp)

    return on_message


def offered(node: Any, topic: str) -> QosSettings | None:
    """The QoS the topic's first publisher offers, as the ROS graph reports it (depth 0:
    DDS does not tell a remote publisher's history depth); ``None`` without one."""
    infos = node.get_publishers_info_by_topic(topic)
    return settings_of(infos[0].qos_profile) if infos else None


@dataclass
class Wiring:
    """The subscriptions to make: topic (as configured) → (type name, QoS); ``roles`` maps
    ``pose``, ``goal`` and each needed sensor to its topic; ``episodic`` the topics published
    once an episode; ``recorded`` the resolved names recorded; ``record_cmd`` whether the
    commands are recorded; ``once`` the needed sensors published once an episode (the plan),
    which a reset waits for; ``sync`` the topic a lockstep step waits for: of the needed
    sensors, the one the sim publishes last in a step (the scan, else the depth image), else
    the pose."""

    wanted: dict[str, tuple[str, QosSettings]] = field(default_factory=dict)
    roles: dict[str, str] = field(default_factory=dict)
    episodic: set[str] = field(default_factory=set)
    recorded: set[str] = field(default_factory=set)
    record_cmd: bool = False
    once: list[str] = field(default_factory=list)
    sync: str = ""


def _like(sim_topic: Interface, sensor_qos: SensorQos) -> tuple[str, QosSettings]:
    """A sim topic's type, and its QoS (sensor data as ``ros.sensor_qos`` says)."""
    sensor = sim_topic.qos is QosKind.SENSOR_DATA and sensor_qos is SensorQos.BEST_EFFORT
    return sim_topic.type, bridge_qos(QosKind.SENSOR_DATA if sensor else QosKind.RELIABLE)


def wiring(config: EnvConfig, sensors: frozenset[str],
           resolve: Callable[[str], str]) -> Wiring:
    """The subscriptions for ``sensors`` and ``config.recorded_topics`` (``resolve``: the
    node's topic name resolution)."""
    t, out = config.topics, Wiring()
    sensor_qos = SensorQos(config.ros.sensor_qos)
    # The sim latches its goal; an operator's tool (rviz2's "2D Goal Pose") publishes
    # volatile, which a transient-local subscription would not match.
    goal_qos = bridge_qos(QosKind.LATCHED if config.ros.sim_node else QosKind.RELIABLE)
    out.wanted = {t.pose: (ODOM.type, bridge_qos(QosKind.RELIABLE)),
                  t.goal: (GOAL_POSE.type, goal_qos)}
    out.roles = {"pose": t.pose, "goal": t.goal}
    out.episodic = {t.goal, *(getattr(t, s.name) for s in READING_TABLE if s.episodic)}
    # Episodic sensors first, like the goal (the plan; nav2's /plan: on each replan).
    for sensor in sorted(READING_TABLE, key=lambda s: not s.episodic):
        if sensor.name in sensors:
            topic = getattr(t, sensor.name)
            out.wanted[topic] = ((sensor.interface.type, goal_qos) if sensor.episodic
                                 else _like(sensor.interface, sensor_qos))
            out.roles[sensor.name] = topic
    out.once = [s.name for s in READING_TABLE if s.name in out.roles and s.episodic]
    stepped = [s for s in READING_TABLE if s.name in out.roles and not s.episodic]
    last = max(stepped, key=lambda s: _STEP_ORDER[s.interface.name], default=None)
    out.sync = out.roles[last.name] if last is not None else t.pose
    if config.record.enabled:
        _add_recorded(config, out, sensor_qos, resolve)
    out.episodic |= {topic for topic, (_, qos) in out.wanted.items() if qos.transient_local}
    return out


def _add_recorded(config: EnvConfig, out: Wiring, sensor_qos: SensorQos,
                  resolve: Callable[[str], str]) -> None:
    """Subscriptions for the recorded topics no frame needs, by their sim interface."""
    cmd_vel = resolve(config.topics.cmd_vel)
    taken = {resolve(name) for name in out.wanted}
    for topic in config.recorded_topics:
        if resolve(topic) == cmd_vel or topic == "cmd_vel":
            out.record_cmd = True
            continue
        if resolve(topic) in taken:
            continue
        taken.add(resolve(topic))
        sim_topic = KNOWN_TOPICS.get(topic) or KNOWN_TOPICS.get(topic.strip("/"))
        if sim_topic is None:
            raise ConfigError(f"record.topics: {topic!r} has no known message type; "
                              f"expected one of {', '.join(KNOWN_TOPICS)}")
        out.wanted[topic] = ((sim_topic.type, bridge_qos(QosKind.LATCHED))
                             if sim_topic.qos is QosKind.LATCHED
                             else _like(sim_topic, sensor_qos))
    out.recorded = {resolve(name) for name in config.recorded_topics}


def stale(topics: Iterable[Topic], max_age_s: float, now_s: float) -> str | None:
    """Why a rate-mode frame cannot be trusted: the first of ``topics`` whose latest message
    arrived more than ``max_age_s`` before ``now_s`` (``time.monotonic()``), or ``None``."""
    for topic in topics:
        age = now_s - topic.received_s
        if age > max_age_s:
            return (f"topic {topic.name}: no message for {age:.2f} s "
                    f"(ros.max_sensor_age_s {max_age_s:g} s)")
    return None


def silent(node: Any, topics: Iterable[Topic], keys: Mapping[str, str]) -> str:
    """``topics`` (those that sent nothing a wait needed) named, each with its ``topics.*``
    key (``keys``: topic → key) and what the ROS graph says of its publishers: none, or the
    QoS they offer, and whether it matches this env's subscription."""
    parts = []
    for topic in topics:
        key = f"topics.{keys[topic.name]}; " if topic.name in keys else ""
        infos = node.get_publishers_info_by_topic(topic.name)
        if not infos:
            parts.append(f"{topic.name} ({key}no publisher)")
            continue
        offered = [settings_of(info.qos_profile) for info in infos]
        words = sorted({_qos_words(q) for q in offered})
        clash = ""
        if topic.qos.reliable and not any(q.reliable for q in offered):
            clash = (": none matches this env's reliable subscription (ros.sensor_qos: "
                     "best_effort for a sensor)")
        elif topic.qos.transient_local and not any(q.transient_local for q in offered):
            clash = ": none matches this env's transient-local subscription"
        parts.append(f"{topic.name} ({key}{len(infos)} publisher(s) offering "
                     f"{' / '.join(words)}{clash})")
    return f"topic{'s' if len(parts) > 1 else ''} {', '.join(parts)}"


def _qos_words(qos: QosSettings) -> str:
    return (f"{'reliable' if qos.reliable else 'best effort'}, "
            f"{'transient local' if qos.transient_local else 'volatile'}")
