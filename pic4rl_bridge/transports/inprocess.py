"""The in-process transport: the same episodes as through ROS 2, over ``pic4rl_sim``'s engine
in this process (no DDS), for speed.

It mirrors the sim node step for step: a reset advances sim time one control period and reads
every sensor once; a step tracks the command for one control period, then reads every sensor
once. Values pass through the same float32 buffers and quaternions as the node's messages, so
the frames equal the ROS transport's bit for bit. When recording, it builds the node's own
messages (``pic4rl_sim.node.messages``), decodes the frame from them and hands them to the tap
serialized, so its bags equal the node's too. A step's frame carries the engine's contact
(``SensorFrame.contact``), as the node's ``diagnostics`` do. A request for another variant of
the world builds a new engine on it, as the node does when its ``world_variant`` changed.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from typing import Any

from pic4rl_base.geometry import Pose2D
from pic4rl_sim.engine.core import Engine
from pic4rl_sim.engine.geometry import Twist2D
from pic4rl_sim.errors import SimError
from pic4rl_sim.interfaces import (
    CMD_VEL,
    EPISODE_TOPICS,
    INTERFACE_TABLE,
    STEP_TOPICS,
    QosKind,
    bridge_qos,
    interface,
)

from ..config import EnvConfig
from ..errors import ConfigError, EpisodeRejected
from ..readings import decode
from ..readings.frame import SensorFrame, as_published
from ..readings.sensor_table import FrameSensor, build_frame
from ..scenario import Scenario
from .transport import EpisodeRequest, OfferedQos, RawMessage, Tap, Transport

_POSE_SOURCES = ("odom", "ground_truth")
#: The QoS the sim node offers its topics with, and the ROS transport its ``cmd_vel``; the
#: rest: ``OfferedQos()``.
_NODE_QOS = {i.name: i.qos.value for i in INTERFACE_TABLE if i.qos is not None}
_NODE_QOS[CMD_VEL.name] = bridge_qos(QosKind.RELIABLE)


class InProcessTransport(Transport):
    """An ``Engine`` built from the config's sim section; ``sensors`` lists the frame's
    optional fields to fill ("scan", "depth", "person")."""

    def __init__(self, config: EnvConfig, scenario: Scenario, sensors: frozenset[str]) -> None:
        if scenario.sim is None or scenario.world is None:
            raise ConfigError("transport: 'inprocess' needs the sim's parameters (a 'sim:' "
                              "section in the config file)")
        pose = config.topics.pose
        if pose not in _POSE_SOURCES:
            raise ConfigError(f"topics.pose: {pose!r} is invalid for the in-process transport; "
                              f"expected one of {', '.join(_POSE_SOURCES)}")
        sim = scenario.sim
        self.engine = Engine(sim.robot, scenario.world, sim.engine, seed=sim.episode.seed)
        self._exact_pose = pose == "ground_truth"
        self._sensors = sensors
        self._mounts = scenario.robot.mounts
        self._scenario, self._variant = scenario, scenario.variant
        self._namespace = "/" + config.ros.namespace.strip("/") if config.ros.namespace else ""
        self._record_topics = config.recorded_topics
        self._control_dt_ns = round(sim.engine.control_dt_s * 1e9)
        self._stamp_ns = 0
        self._writer: _MessageWriter | None = None

    @property
    def world_name(self) -> str:
        return self._scenario.world_name

    def reset(self, request: EpisodeRequest) -> SensorFrame:
        variant = request.world_variant
        if variant is not None and variant != self._variant:  # as the node rebuilds its own
            sim, world = self._scenario.sim, self._scenario.world_at(variant)
            assert sim is not None and world is not None  # checked in __init__
            self.engine = Engine(sim.robot, world, sim.engine, seed=request.seed)
            self._variant, self._writer = variant, None
        try:
            self.engine.reset(seed=request.seed, start=request.start, goal=request.goal)
        except (SimError, ConfigError) as err:
            raise EpisodeRejected(str(err)) from err
        self._stamp_ns += self._control_dt_ns
        self.fault = None
        if self.tap is not None:
            self._messages().episode(self.engine, self._stamp_ns, self.tap)
        return self._frame()

    def step(self, command: Twist2D) -> SensorFrame:
        if self.tap is not None:
            self._messages().command(command, self._stamp_ns, self.tap)
        result = self.engine.step(command)
        self.fault = result.reason if result.diverged else None
        self._stamp_ns += self._control_dt_ns
        return dataclasses.replace(self._frame(), contact=result.collided)

    def offered_qos(self, topic: str) -> OfferedQos | None:
        """As the sim node and the ROS transport offer it."""
        name = topic.removeprefix(self._namespace)
        return _NODE_QOS.get(name.lstrip("/"), OfferedQos())

    def close(self) -> None:
        self.tap = None

    def _messages(self) -> _MessageWriter:
        if self._writer is None:
            self._writer = _MessageWriter(self.engine, self._namespace, self._record_topics)
        return self._writer

    def _frame(self) -> SensorFrame:
        if self.tap is not None:
            return self._messages().state(self._stamp_ns, self._exact_pose, self._sensors,
                                          self._mounts, self.tap)
        engine, mounts = self.engine, self._mounts
        pose, twist = ((engine.robot_pose(), engine.robot_twist()) if self._exact_pose
                       else engine.wheel_odometry())
        return build_frame(self._stamp_ns, (as_published(pose), twist), engine.goal,
                           self._sensors, lambda sensor: sensor.read(engine, sensor.mount(mounts)))


class _MessageWriter:
    """The sim node's messages for one engine, serialized to a tap (needs rclpy's message
    packages, imported here only)."""

    def __init__(self, engine: Engine, namespace: str, topics: tuple[str, ...]) -> None:
        from geometry_msgs.msg import Twist
        from rclpy.serialization import serialize_message

        from pic4rl_sim.node.messages import StateMessages, episode_messages

        self._engine = engine
        self._serialize = serialize_message
        self._twist_type = Twist
        self._episode_messages = episode_messages
        self.state_messages = StateMessages(engine)
        self._names = {t.name: f"{namespace}/{t.name}"
                       for t in (*STEP_TOPICS, *EPISODE_TOPICS, CMD_VEL)}
        self._outputs = [(t.name, msg) for t, msg in self.state_messages.published
                         if t.name in topics]
        #: The step messages by topic, refilled in place each step: a sensor's frame value
        #: is decoded from its message when the engine publishes one.
        self._held = {t.name: msg for t, msg in self.state_messages.published}
        self._topics = topics

    def _emit(self, topic: str, msg: Any, stamp_ns: int, tap: Tap) -> None:
        if topic in self._topics:
            tap(RawMessage(self._names[topic], interface(topic).type, self._serialize(msg),
                           stamp_ns))

    def episode(self, engine: Engine, stamp_ns: int, tap: Tap) -> None:
        """The episode's recorded messages (goal, plan, sensor frames), as the node publishes
        them."""
        for topic, msg in self._episode_messages(engine, stamp_ns, self._topics):
            self._emit(topic.name, msg, stamp_ns, tap)

    def command(self, command: Twist2D, stamp_ns: int, tap: Tap) -> None:
        msg = self._twist_type()
        msg.linear.x, msg.linear.y, msg.angular.z = command.vx, command.vy, command.wz
        self._emit(CMD_VEL.name, msg, stamp_ns, tap)

    def state(self, stamp_ns: int, exact_pose: bool, sensors: frozenset[str],
              mounts: Mapping[str, Pose2D], tap: Tap) -> SensorFrame:
        """Fill the node's messages for ``stamp_ns``, hand them to ``tap`` in the node's
        publishing order and decode the frame from them."""
        engine, m = self._engine, self.state_messages
        m.fill(engine, stamp_ns)
        for topic, msg in self._outputs:
            self._emit(topic, msg, stamp_ns, tap)
        held = self._held

        def value(sensor: FrameSensor) -> Any:
            msg, mount = held.get(sensor.interface.name), sensor.mount(mounts)
            return (sensor.read(engine, mount) if msg is None
                    else sensor.decode(msg, mount, sensor.interface.name))

        return build_frame(stamp_ns, decode.odometry(m.ground_truth if exact_pose else m.odom),
                           engine.goal, sensors, value)
