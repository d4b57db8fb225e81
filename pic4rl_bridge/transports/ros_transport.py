"""The ROS 2 transport: drives ``pic4rl_sim``'s node, any ROS 2 simulator or a real robot that
speaks standard topics.

Subscriptions are raw: each message arrives as the CDR bytes on the wire, goes to the tap
(the recorder) as it is, and is decoded for the frame. Episodes:

- with a simulator node (``ros.sim_node``): ``seed``, ``start_pose`` and ``goal`` are set
  atomically through its parameter service (a refused value rejects the episode, with the
  node's reason),
  then ``ros.reset_service`` is called; the new episode's first stamp is its new ``goal_pose``
  stamp, and the frame is the first full sensor set at or after it (the sim node's contract);
- without a reset service (a real robot): a reset stops the robot and waits for the operator's
  next goal on ``topics.goal`` (``ros.operator_timeout_s``, 0 = forever).

Steps: ``lockstep`` publishes the command and waits for the sensor set it causes (the sync
topic, scan or depth image, with a newer stamp, and every other needed topic at that stamp);
``rate`` publishes, waits one control period of wall time, and takes the latest messages; a
needed topic silent longer than ``ros.max_sensor_age_s`` stops the robot (zero ``cmd_vel``)
and raises ``StaleSensor``, which the env turns into an aborted episode.
With our sim node, a step also waits for the sim's status of that step on ``diagnostics``: an
ERROR (the physics diverged; the robot is back at its start) becomes the transport's ``fault``,
a contact the frame's ``contact`` (``None`` without our sim: a real robot's).
"""

from __future__ import annotations

import logging
import time
from dataclasses import replace
from collections.abc import Callable
from typing import Any

import rclpy
from geometry_msgs.msg import Twist, TwistStamped
from rcl_interfaces.srv import SetParametersAtomically
from rclpy.context import Context
from rclpy.experimental import EventsExecutor
from rclpy.node import Node
from rclpy.serialization import serialize_message
from std_srvs.srv import Empty

from pic4rl_sim.engine.geometry import Twist2D
from pic4rl_sim.interfaces import QosKind, bridge_qos
from pic4rl_sim.node.ros_interfaces import (
    profile,
    ros_type,
    type_name,
)

from ..config import EnvConfig, StepMode
from ..errors import EpisodeRejected, StaleSensor, TransportError
from ..scenario import Scenario
from ..readings import cdr, decode
from ..readings.frame import SensorFrame
from .ros_sim import check_one_sim, episode_request, settle, subscribe_status
from .ros_topics import Topic, command_message, offered, receiver, silent, stale, wiring
from ..readings.sensor_table import FrameSensor, build_frame
from .transport import EpisodeRequest, OfferedQos, RawMessage, Transport

log = logging.getLogger(__name__)


class RosTransport(Transport):
    """The env's ROS 2 side: one node (its own context unless ``node`` is given) spun by an
    events executor only while the env waits."""

    def __init__(self, config: EnvConfig, scenario: Scenario, sensors: frozenset[str], *,
                 node: Node | None = None) -> None:
        self._config, self._ros = config, config.ros
        self._mode, self._timeout_s = StepMode(config.ros.step_mode), config.ros.timeout_s
        self._dt_s = scenario.robot.control_dt_s
        self._max_age_s = config.ros.max_sensor_age_s or 5.0 * self._dt_s
        self._mounts = scenario.robot.mounts
        self._scenario = scenario  # its world_name: the current episode's world
        self._own_context: Context | None = None
        if node is None:
            self._own_context = Context()
            domain = config.ros.domain_id if config.ros.domain_id >= 0 else None
            rclpy.init(context=self._own_context, domain_id=domain)
            node = Node(config.ros.node_name, namespace=config.ros.namespace or None,
                        context=self._own_context)
        self.node = node
        self._executor = EventsExecutor(context=node.context)
        self._executor.add_node(node)
        self._topics: dict[str, Topic] = {}
        self._roles: dict[str, str] = {}  # frame field -> topic key
        self._pending: list[tuple[int, RawMessage]] = []  # (header stamp, message) held while
        # a reset waits for the new episode's first stamp (its goal's)
        self._t0_ns: int | None = None
        self._frame_stamp_ns = -1
        self._closed = False
        self._subscribe(config, sensors)
        self._faults: dict[int, str] = {}  # step stamp (ns) -> why the sim voided the episode
        self._contacts: set[int] = set()  # step stamps (ns) at which the sim's robot touched
        self._status_live = False  # the sim publishes a status every step: wait for it
        self._status = (subscribe_status(node, self._faults, self._contacts)
                        if config.ros.sim_node else None)
        self._cmd_stamped = config.ros.cmd_vel_type == "TwistStamped"
        kind = TwistStamped if self._cmd_stamped else Twist
        self._cmd_pub = node.create_publisher(kind, config.topics.cmd_vel,
                                              profile(bridge_qos(QosKind.RELIABLE)))
        self._cmd_name, self._cmd_type = self._cmd_pub.topic_name, type_name(kind)
        self._set_params = self._reset_client = None
        if config.ros.sim_node:
            self._set_params = node.create_client(
                SetParametersAtomically, f"{config.ros.sim_node}/set_parameters_atomically")
        if config.ros.reset_service:
            self._reset_client = node.create_client(Empty, config.ros.reset_service)
        self._used_goal_ns = -1  # the goal stamp of the last episode
        self._decoded: dict[str, tuple[Any, Any]] = {}  # goal, episodic sensor -> (data, value)

    # -- wiring ---------------------------------------------------------------------------

    def _subscribe(self, config: EnvConfig, sensors: frozenset[str]) -> None:
        wired = wiring(config, sensors, self.node.resolve_topic_name)
        self._roles, self._record_cmd = wired.roles, wired.record_cmd
        self._sync_topic, self._once = wired.sync, wired.once
        resolve = self.node.resolve_topic_name
        for topic, (kind, qos) in wired.wanted.items():
            entry = Topic(topic, kind)
            entry.qos = qos
            entry.recorded = resolve(topic) in wired.recorded
            entry.episodic = topic in wired.episodic
            sub = self.node.create_subscription(ros_type(kind), topic,
                                                receiver(entry, self._deliver),
                                                profile(qos), raw=True)
            entry.name = sub.topic_name
            self._topics[topic] = entry

    def _deliver(self, entry: Topic, data: bytes, stamp: int) -> None:
        """Hands a recorded message to the tap once it belongs to the episode (held while a
        reset waits for the episode's first stamp)."""
        if self.tap is None:
            return
        raw = RawMessage(entry.name, entry.type_name, data, self._bag_time(stamp))
        if self._t0_ns is None:
            self._pending.append((stamp, raw))
        elif stamp >= self._t0_ns:
            self.tap(raw)

    def _bag_time(self, stamp_ns: int) -> int:
        """Sim time in lockstep (what ``rosbag2 record --use-sim-time`` writes), else the
        receive time."""
        return stamp_ns if self._mode is StepMode.LOCKSTEP else time.time_ns()

    # -- waiting --------------------------------------------------------------------------

    def _spin_until(self, done: Callable[[], bool], timeout_s: float | None,
                    what: str | Callable[[], str]) -> None:
        """Spin until ``done()``; past ``timeout_s``, ``TransportError`` saying ``what`` (or
        what it returns then) heard nothing."""
        deadline = None if timeout_s is None else time.monotonic() + timeout_s
        while not done():
            if self._closed:
                raise TransportError(f"{what}: the transport was closed")
            remaining = 1.0 if deadline is None else deadline - time.monotonic()
            if remaining <= 0:
                self._check_one_sim()  # two sims out of step time out: say so, not "no sim"
                what = what if isinstance(what, str) else what()
                raise TransportError(f"{what}: nothing within {timeout_s:g} s")
            self._executor.spin_once(timeout_sec=min(remaining, 1.0))

    def _call(self, client: Any, request: Any, what: str) -> Any:
        if not client.service_is_ready():
            self._spin_until(client.service_is_ready, self._timeout_s,
                             f"service {client.srv_name} ({what}) not available")
        future = client.call_async(request)
        self._spin_until(future.done, self._timeout_s, f"service {client.srv_name} ({what})")
        return future.result()

    # -- episodes -------------------------------------------------------------------------

    @property
    def world_name(self) -> str:
        return self._scenario.world_name

    def reset(self, request: EpisodeRequest) -> SensorFrame:
        self._t0_ns, self._pending = None, []
        goal = self._topics[self._roles["goal"]]
        if self._set_params is not None or self._reset_client is not None:
            self._wait_for_graph(goal)
            self._check_one_sim()
            if self._set_params is not None:
                self._set_episode(request)
            before = goal.stamp_ns
            if self._reset_client is not None:
                self._call(self._reset_client, Empty.Request(), "reset")
            self._spin_until(lambda: goal.stamp_ns > before, self._timeout_s,
                             f"topic {goal.name}: the new episode's goal")
        else:  # a real robot: the next goal not used yet (a latched one counts)
            if request.start is not None or request.goal is not None:
                log.warning("no sim node: the requested start %s and goal %s are ignored; the "
                            "operator places the robot and sends the goal", request.start,
                            request.goal)
            self.step_command(Twist2D())
            used = self._used_goal_ns
            if goal.stamp_ns <= used:
                log.warning("waiting for the operator's next goal on %s", goal.name)
            self._spin_until(lambda: goal.stamp_ns > used,
                             self._ros.operator_timeout_s or None, f"topic {goal.name}: a goal")
        self._used_goal_ns = goal.stamp_ns
        for role in self._once:  # the sim's plan carries its goal's stamp
            entry = self._topics[self._roles[role]]
            first = goal.stamp_ns if self._set_params is not None else 0
            self._spin_until(lambda e=entry: e.stamp_ns >= first, self._timeout_s,
                             f"topic {entry.name}: the episode's {role}")
        self.fault = None
        self._faults.clear()
        if self._status is not None:
            self._status_live = self.node.count_publishers(self._status.name) > 0
        frame = self._next_frame(goal.stamp_ns, inclusive=True)
        self._t0_ns = goal.stamp_ns
        held, self._pending = self._pending, []
        if self.tap is not None:
            for header_ns, raw in held:
                if header_ns >= self._t0_ns:
                    self.tap(raw)
        return frame

    def _wait_for_graph(self, goal: Topic) -> None:
        """Before the first reset: the sim's latched goal seen and our cmd_vel matched."""
        if goal.stamp_ns < 0 and self._set_params is not None:
            self._spin_until(lambda: goal.stamp_ns >= 0, self._timeout_s,
                             f"topic {goal.name}: the simulator's latched goal")
        if self._cmd_pub.get_subscription_count() == 0:
            self._spin_until(lambda: self._cmd_pub.get_subscription_count() > 0,
                             self._timeout_s, f"topic {self._cmd_name}: a subscriber")

    def _check_one_sim(self) -> None:
        """``SimConflict`` when a second simulator answers on our names (``ros_sim``)."""
        if self._ros.sim_node:
            check_one_sim(self.node, self._ros.sim_node, self._topics[self._roles["goal"]].name,
                          self._topics[self._roles["pose"]].name)

    def _set_episode(self, request: EpisodeRequest) -> None:
        result = self._call(self._set_params, episode_request(request), "episode set-up").result
        if not result.successful:
            raise EpisodeRejected(f"{self._ros.sim_node}: {result.reason}")

    # -- stepping -------------------------------------------------------------------------

    def step_command(self, command: Twist2D) -> None:
        """Publish ``command`` (and hand it to the tap, stamped with the last frame's time)."""
        msg = command_message(command, self._cmd_stamped, max(self._frame_stamp_ns, 0))
        self._cmd_pub.publish(msg)
        if self.tap is not None and self._t0_ns is not None and self._record_cmd:
            self.tap(RawMessage(self._cmd_name, self._cmd_type, serialize_message(msg),
                                self._bag_time(max(self._frame_stamp_ns, 0))))

    def step(self, command: Twist2D) -> SensorFrame:
        self.step_command(command)
        if self._mode is StepMode.RATE:
            deadline = time.monotonic() + self._dt_s
            self._spin_until(lambda: time.monotonic() >= deadline, None, "control period")
        before = self._frame_stamp_ns
        frame = self._next_frame(before, inclusive=False)
        self.fault, touched = settle(self._faults, self._contacts, before, frame.stamp_ns)
        return replace(frame, contact=touched if self._status_live else None)

    def _needed(self) -> list[Topic]:
        """The topics every frame needs: the pose and the task's sensors sent every step."""
        return [self._topics[t] for role, t in self._roles.items()
                if role != "goal" and role not in self._once]

    def _check_fresh(self) -> None:
        """Rate mode: stop the robot and raise ``StaleSensor`` if a needed topic went silent."""
        reason = stale(self._needed(), self._max_age_s, time.monotonic())
        if reason is not None:
            self.step_command(Twist2D())
            raise StaleSensor(reason)

    def _next_frame(self, after_ns: int, *, inclusive: bool) -> SensorFrame:
        """In lockstep, the first full set of needed messages stamped after ``after_ns`` (at
        it when ``inclusive``); in rate mode, the latest messages, if none is stale. Silence
        names the topics that sent nothing, with their publishers' QoS."""
        needed, sync = self._needed(), self._topics[self._sync_topic]
        if self._mode is StepMode.LOCKSTEP:
            status = self._status if self._status_live and not inclusive else None  # a step's

            def late() -> list[Topic]:
                s = sync.stamp_ns
                if not (s >= after_ns if inclusive else s > after_ns):
                    return [sync]
                return [t for t in (*needed, *([status] if status else [])) if t.stamp_ns < s]
        else:
            def late() -> list[Topic]:
                return [t for t in needed if t.data is None]
        self._spin_until(lambda: not late(), self._timeout_s, lambda: silent(
            self.node, late(), {self._topics[t].name: r for r, t in self._roles.items()}))
        if self._mode is StepMode.RATE:
            self._check_fresh()
        return self._frame(sync.stamp_ns)

    def _frame(self, stamp_ns: int) -> SensorFrame:
        topics, roles = self._topics, self._roles
        goal = topics[roles["goal"]]
        goal_value = self._once_per_message("goal", goal, lambda: decode.goal(goal.msg))
        pose = topics[roles["pose"]]  # its odometry read from the CDR bytes where it can be
        frame = build_frame(stamp_ns, cdr.odometry(pose.data) or decode.odometry(pose.msg),
                            goal_value, roles, self._value)
        self._frame_stamp_ns = stamp_ns
        return frame

    def _value(self, sensor: FrameSensor) -> Any:
        """The sensor's latest message decoded (``FrameSensor.reading``); an episodic one's
        once per message (not at every step)."""
        topic = self._roles[sensor.name]
        entry, mount = self._topics[topic], sensor.mount(self._mounts)
        if not sensor.episodic:
            return sensor.reading(entry, mount, topic)
        return self._once_per_message(sensor.name, entry,
                                      lambda: sensor.reading(entry, mount, topic))

    def _once_per_message(self, key: str, entry: Topic, value: Callable[[], Any]) -> Any:
        """``value()`` for ``entry``'s latest message, once per message (``None`` before)."""
        last = self._decoded.get(key)
        if last is None or last[0] is not entry.data:
            last = self._decoded[key] = (entry.data, None if entry.data is None else value())
        return last[1]

    def offered_qos(self, topic: str) -> OfferedQos | None:
        return offered(self.node, topic)

    def flush(self) -> None:
        """Lockstep: wait (briefly) until every recorded topic has reached the last frame's
        stamp, so the bag holds the episode's last messages too."""
        if self.tap is None or self._mode is not StepMode.LOCKSTEP:
            return
        last = self._frame_stamp_ns
        waiting = [t for t in self._topics.values()
                   if not t.episodic and t.recorded and t.count > 0]
        try:
            self._spin_until(lambda: all(t.stamp_ns >= last for t in waiting), 1.0,
                             "recorded topics: the last step's messages")
        except TransportError as err:
            log.warning("%s; the bag may miss them", err)

    def close(self) -> None:
        if self._closed:
            return
        self.tap = None
        try:
            if self.node.context.ok():
                self._cmd_pub.publish(TwistStamped() if self._cmd_stamped else Twist())
        finally:
            self._closed = True
            self._executor.shutdown()
            if self._own_context is not None:
                self.node.destroy_node()
                rclpy.try_shutdown(context=self._own_context)
