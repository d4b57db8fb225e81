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
``rate`` publishes, waits one control period of wall time, and takes the latest messages.
With our sim node, a step also waits for the sim's status of that step on ``diagnostics``: an
ERROR (the physics diverged; the robot is back at its start) becomes the transport's ``fault``.
"""

from __future__ import annotations

import logging
import struct
import time
from collections.abc import Callable
from typing import Any

import numpy as np
import rclpy
from builtin_interfaces.msg import Time
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from geometry_msgs.msg import PoseStamped, Twist, TwistStamped
from nav_msgs.msg import Odometry, Path
from rcl_interfaces.msg import Parameter as ParameterMsg
from rcl_interfaces.msg import ParameterType, ParameterValue
from rcl_interfaces.srv import SetParametersAtomically
from rclpy.context import Context
from rclpy.experimental import EventsExecutor
from rclpy.node import Node
from rclpy.qos import (
    DurabilityPolicy,
    HistoryPolicy,
    QoSProfile,
    ReliabilityPolicy,
)
from rclpy.serialization import deserialize_message, serialize_message
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import CameraInfo, Image, Imu, LaserScan
from std_srvs.srv import Empty

from pic4rl_sim.engine.geometry import Pose2D, Twist2D
from pic4rl_sim.interfaces import (
    DEPTH_IMAGE,
    DIAGNOSTICS,
    GOAL_POSE,
    INTERFACES,
    ODOM,
    PERSON_POSE,
    PLAN,
    SCAN,
    Cadence,
    Interface,
    QosKind,
)
from pic4rl_sim.node.ros_interfaces import ros_type

from . import decode
from .config import EnvConfig, StepMode
from .errors import ConfigError, EpisodeRejected, SimConflict, TransportError
from .frame import SensorFrame
from .scenario import Scenario
from .transport import EpisodeRequest, OfferedQos, RawMessage, Transport

log = logging.getLogger(__name__)

_DEPTH = 100  # history kept per subscription: the recorder must see every message
_RELIABLE = QoSProfile(depth=_DEPTH, reliability=ReliabilityPolicy.RELIABLE)
_BEST_EFFORT = QoSProfile(depth=_DEPTH, reliability=ReliabilityPolicy.BEST_EFFORT)
_LATCHED = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE,
                      durability=DurabilityPolicy.TRANSIENT_LOCAL,
                      history=HistoryPolicy.KEEP_LAST)
#: How the ROS graph names a node whose name record has not arrived yet.
_UNNAMED = "_NODE_NAME_UNKNOWN_"
#: The sim node's state and episode topics by relative name, recordable by name alone.
_KNOWN_TOPICS = {i.name: i for i in INTERFACES if i.cadence in (Cadence.STEP, Cadence.EPISODE)}


#: Types whose CDR starts with a ``builtin_interfaces/Time`` (a header's stamp, or the clock).
_STAMP_FIRST = (Clock, Odometry, LaserScan, Imu, Image, CameraInfo, PoseStamped, Path)


def _cdr_stamp(data: bytes) -> int:
    """The stamp (ns) of a message that starts with one, read from its CDR bytes: 4 bytes of
    encapsulation (byte 1: 1 = little endian), then ``int32 sec``, ``uint32 nanosec``."""
    sec, nanosec = struct.unpack_from("<iI" if data[1] == 1 else ">iI", data, 4)
    return sec * 1_000_000_000 + nanosec


def _like(sim_topic: Interface, sensor_qos: QoSProfile) -> tuple[type, QoSProfile]:
    """A sim topic's type, and ``sensor_qos`` (``ros.sensor_qos``) if it is sensor data."""
    return ros_type(sim_topic.type), (sensor_qos if sim_topic.qos is QosKind.SENSOR_DATA
                                      else _RELIABLE)


def _type_name(kind: type) -> str:
    return f"{kind.__module__.split('.')[0]}/msg/{kind.__name__}"


def _stamp_of(msg: Any) -> int | None:
    if isinstance(msg, Clock):
        return decode.stamp_ns(msg.clock)
    header = getattr(msg, "header", None)
    return decode.stamp_ns(header) if header is not None else None


class _Topic:
    """One raw subscription: the latest decoded message and its stamp."""

    def __init__(self, name: str, kind: type) -> None:
        self.name, self.kind = name, kind
        self.msg: Any = None
        self.stamp_ns = -1
        self.count = 0
        self.recorded = False
        self.episodic = False  # published once per episode (goal, plan), not every step


class RosTransport(Transport):
    """The env's ROS 2 side: one node (its own context unless ``node`` is given) spun by an
    events executor only while the env waits."""

    def __init__(self, config: EnvConfig, scenario: Scenario, sensors: frozenset[str], *,
                 node: Node | None = None) -> None:
        self._config = config
        self._ros = config.ros
        self._mode = StepMode(config.ros.step_mode)
        self._timeout_s = config.ros.timeout_s
        self._dt_s = scenario.robot.control_dt_s
        self._lidar_mount = scenario.robot.lidar_mount or Pose2D(0.0, 0.0, 0.0)
        self._world_name = scenario.world_name
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
        self._topics: dict[str, _Topic] = {}
        self._roles: dict[str, str] = {}  # frame field -> topic key
        self._pending: list[tuple[int, RawMessage]] = []  # (header stamp, message) held while
        # a reset waits for the new episode's first stamp (its goal's)
        self._t0_ns: int | None = None
        self._frame_stamp_ns = -1
        self._closed = False
        self._subscribe(config, sensors)
        self._faults: dict[int, str] = {}  # step stamp (ns) -> why the sim voided the episode
        self._status: _Topic | None = None
        self._status_live = False  # the sim publishes a status every step: wait for it
        if config.ros.sim_node:
            self._subscribe_status()
        self._cmd_stamped = config.ros.cmd_vel_type == "TwistStamped"
        kind = TwistStamped if self._cmd_stamped else Twist
        self._cmd_pub = node.create_publisher(kind, config.topics.cmd_vel, _RELIABLE)
        self._cmd_name = self._cmd_pub.topic_name
        self._cmd_type = _type_name(kind)
        self._set_params = self._reset_client = None
        if config.ros.sim_node:
            self._set_params = node.create_client(
                SetParametersAtomically, f"{config.ros.sim_node}/set_parameters_atomically")
        if config.ros.reset_service:
            self._reset_client = node.create_client(Empty, config.ros.reset_service)
        self._used_goal_ns = -1  # the goal stamp of the last episode
        self._plan_msg: Any = None  # the plan message last decoded, and its points
        self._plan = np.zeros((0, 2))

    # -- wiring ---------------------------------------------------------------------------

    def _subscribe(self, config: EnvConfig, sensors: frozenset[str]) -> None:
        t = config.topics
        sensor_qos = _BEST_EFFORT if config.ros.sensor_qos == "best_effort" else _RELIABLE
        # The sim latches its goal; an operator's tool (rviz2's "2D Goal Pose") publishes
        # volatile, which a transient-local subscription would not match.
        goal_qos = _LATCHED if config.ros.sim_node else _RELIABLE
        wanted: dict[str, tuple[type, QoSProfile]] = {t.pose: (ros_type(ODOM.type), _RELIABLE),
                                                      t.goal: (ros_type(GOAL_POSE.type), goal_qos)}
        self._roles = {"pose": t.pose, "goal": t.goal}
        if "plan" in sensors:  # once per episode, like the goal (nav2's /plan: on each replan)
            wanted[t.plan] = (ros_type(PLAN.type), goal_qos)
            self._roles["plan"] = t.plan
        for role, topic, sim_topic in (("scan", t.scan, SCAN), ("depth", t.depth, DEPTH_IMAGE),
                                       ("person", t.person, PERSON_POSE)):
            if role in sensors:
                wanted[topic] = _like(sim_topic, sensor_qos)
                self._roles[role] = topic
        resolve = self.node.resolve_topic_name
        self._record_cmd = False
        if config.record.enabled:
            taken = {resolve(name) for name in wanted}
            for topic in config.record.topics:
                if resolve(topic) == resolve(t.cmd_vel) or topic == "cmd_vel":
                    self._record_cmd = True
                    continue
                if resolve(topic) in taken:
                    continue
                taken.add(resolve(topic))
                sim_topic = _KNOWN_TOPICS.get(topic) or _KNOWN_TOPICS.get(topic.strip("/"))
                if sim_topic is None:
                    raise ConfigError(f"record.topics: {topic!r} has no known message type; "
                                      f"expected one of {', '.join(_KNOWN_TOPICS)}")
                wanted[topic] = ((ros_type(sim_topic.type), _LATCHED)
                                 if sim_topic.qos is QosKind.LATCHED
                                 else _like(sim_topic, sensor_qos))
        listed = ({resolve(name) for name in config.record.topics} if config.record.enabled
                  else set())
        for topic, (kind, qos) in wanted.items():
            entry = _Topic(topic, kind)
            entry.recorded = resolve(topic) in listed
            entry.episodic = qos.durability == DurabilityPolicy.TRANSIENT_LOCAL or topic in (
                t.goal, t.plan)
            needed = topic in self._roles.values()
            sub = self.node.create_subscription(kind, topic, self._callback(entry, needed), qos,
                                                raw=True)
            entry.name = sub.topic_name
            self._topics[topic] = entry

    def _subscribe_status(self) -> None:
        """Our sim's per-step ``diagnostics`` status (``pic4rl_sim.node``): an ERROR says the
        physics diverged and the robot was put back at its start."""
        from pic4rl_sim.node.messages import PHYSICS_STATUS

        entry = _Topic(DIAGNOSTICS.name, DiagnosticArray)

        def on_status(msg: DiagnosticArray) -> None:
            for status in msg.status:
                if status.name == PHYSICS_STATUS:
                    entry.stamp_ns = decode.stamp_ns(msg.header)
                    if status.level == DiagnosticStatus.ERROR:
                        self._faults[entry.stamp_ns] = status.message

        sub = self.node.create_subscription(DiagnosticArray, DIAGNOSTICS.name, on_status,
                                            _RELIABLE)
        entry.name = sub.topic_name
        self._status = entry

    def _callback(self, entry: _Topic, needed: bool) -> Callable[[bytes], None]:
        """Stores the latest message of a topic frames need (decoded) or of one recorded only
        (just its stamp), and hands it to the tap once it belongs to the episode."""
        type_name = _type_name(entry.kind)
        decode_all = needed or entry.kind not in _STAMP_FIRST

        def on_message(data: bytes) -> None:
            if decode_all:
                entry.msg = deserialize_message(data, entry.kind)
                stamp = _stamp_of(entry.msg)
            else:  # recorded only: the stamp straight from the CDR bytes, nothing decoded
                stamp = _cdr_stamp(data)
            stamp = time.time_ns() if stamp is None else stamp
            entry.stamp_ns = stamp
            entry.count += 1
            if self.tap is None or not entry.recorded:
                return
            raw = RawMessage(entry.name, type_name, data, self._bag_time(stamp))
            if self._t0_ns is None:
                self._pending.append((stamp, raw))
            elif stamp >= self._t0_ns:
                self.tap(raw)

        return on_message

    def _bag_time(self, stamp_ns: int) -> int:
        """Sim time in lockstep (what ``rosbag2 record --use-sim-time`` writes), else the
        receive time."""
        return stamp_ns if self._mode is StepMode.LOCKSTEP else time.time_ns()

    # -- waiting --------------------------------------------------------------------------

    def _spin_until(self, done: Callable[[], bool], timeout_s: float | None, what: str) -> None:
        deadline = None if timeout_s is None else time.monotonic() + timeout_s
        while not done():
            if self._closed:
                raise TransportError(f"{what}: the transport was closed")
            remaining = 1.0 if deadline is None else deadline - time.monotonic()
            if remaining <= 0:
                self._check_one_sim()  # two sims out of step time out: say so, not "no sim"
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
        return self._world_name

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
        if "plan" in self._roles:  # the sim's plan carries its goal's stamp; any plan else
            plan = self._topics[self._roles["plan"]]
            first = goal.stamp_ns if self._set_params is not None else 0
            self._spin_until(lambda: plan.stamp_ns >= first, self._timeout_s,
                             f"topic {plan.name}: the episode's plan")
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

    def _wait_for_graph(self, goal: _Topic) -> None:
        """Before the first reset: the sim's latched goal seen and our cmd_vel matched."""
        if goal.stamp_ns < 0 and self._set_params is not None:
            self._spin_until(lambda: goal.stamp_ns >= 0, self._timeout_s,
                             f"topic {goal.name}: the simulator's latched goal")
        if self._cmd_pub.get_subscription_count() == 0:
            self._spin_until(lambda: self._cmd_pub.get_subscription_count() > 0,
                             self._timeout_s, f"topic {self._cmd_name}: a subscriber")

    def _check_one_sim(self) -> None:
        """``SimConflict`` when a second simulator answers on our names (a forgotten
        ``pic4rl-sim``), so that frames and bags would mix two worlds: more than one node
        named like ``ros.sim_node`` publishes the goal or the pose topic, or the pose topic
        (which only a simulator or a robot's driver publishes) has a second publisher whose
        node the graph cannot name yet (DDS may lose a node's name record while several
        participants start). A graph query: cheap, once an episode."""
        if not self._ros.sim_node:
            return
        sim = self.node.resolve_topic_name(self._ros.sim_node)
        for role in ("goal", "pose"):
            topic = self._topics[self._roles[role]].name
            nodes = [f"{info.node_namespace.rstrip('/')}/{info.node_name}"
                     for info in self.node.get_publishers_info_by_topic(topic)]
            twins = [name for name in nodes if name == sim or (
                role == "pose" and _UNNAMED in name)]
            if len(twins) > 1:
                shown = " and ".join(name if _UNNAMED not in name else "a node not yet named"
                                     for name in twins)
                raise SimConflict(
                    f"{len(twins)} simulator nodes publish {topic} in ROS domain "
                    f"{self.node.context.get_domain_id()}: {shown} (a pic4rl-sim left "
                    "running?); stop all but one, or give each its own namespace "
                    "(-r __ns:=/robot2) or ROS_DOMAIN_ID")

    def _set_episode(self, request: EpisodeRequest) -> None:
        start = [] if request.start is None else [float(v) for v in request.start]
        goal = [] if request.goal is None else [float(v) for v in request.goal]
        params = [
            ParameterMsg(name="seed", value=ParameterValue(
                type=ParameterType.PARAMETER_INTEGER, integer_value=int(request.seed))),
            ParameterMsg(name="start_pose", value=ParameterValue(
                type=ParameterType.PARAMETER_DOUBLE_ARRAY, double_array_value=start)),
            ParameterMsg(name="goal", value=ParameterValue(
                type=ParameterType.PARAMETER_DOUBLE_ARRAY, double_array_value=goal)),
        ]
        request_msg = SetParametersAtomically.Request(parameters=params)
        result = self._call(self._set_params, request_msg, "episode set-up").result
        if not result.successful:
            raise EpisodeRejected(f"{self._ros.sim_node}: {result.reason}")

    # -- stepping -------------------------------------------------------------------------

    def step_command(self, command: Twist2D) -> None:
        """Publish ``command`` (and hand it to the tap, stamped with the last frame's time)."""
        twist = Twist()
        twist.linear.x, twist.linear.y, twist.angular.z = command.vx, command.vy, command.wz
        msg: Any = twist
        if self._cmd_stamped:
            msg = TwistStamped(twist=twist)
            msg.header.stamp = Time(sec=max(self._frame_stamp_ns, 0) // 1_000_000_000,
                                    nanosec=max(self._frame_stamp_ns, 0) % 1_000_000_000)
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
        void = [stamp for stamp in self._faults if stamp <= frame.stamp_ns]
        reasons = [self._faults.pop(stamp) for stamp in sorted(void) if stamp > before]
        self.fault = reasons[0] if reasons else None
        return frame

    def _next_frame(self, after_ns: int, *, inclusive: bool) -> SensorFrame:
        """In lockstep, the first full set of needed messages stamped after ``after_ns`` (at
        it when ``inclusive``); in rate mode, the latest messages."""
        needed = [self._topics[t] for role, t in self._roles.items()
                  if role not in ("goal", "plan")]
        sync = self._topics[self._roles.get("scan") or self._roles.get("depth")
                            or self._roles["pose"]]
        if self._mode is StepMode.LOCKSTEP:
            status = self._status if self._status_live and not inclusive else None  # a step's

            def ready() -> bool:
                s = sync.stamp_ns
                fresh = s >= after_ns if inclusive else s > after_ns
                return fresh and all(t.stamp_ns >= s for t in needed) and (
                    status is None or status.stamp_ns >= s)
            what = f"topic {sync.name}: a message stamped after {after_ns} ns"
        else:
            def ready() -> bool:
                return all(t.msg is not None for t in needed)
            what = f"topics {', '.join(t.name for t in needed)}: a first message"
        self._spin_until(ready, self._timeout_s, what)
        return self._frame(sync.stamp_ns)

    def _frame(self, stamp_ns: int) -> SensorFrame:
        topics, roles = self._topics, self._roles
        pose, twist = decode.odometry(topics[roles["pose"]].msg)
        goal_msg = topics[roles["goal"]].msg
        goal = None if goal_msg is None else (float(goal_msg.pose.position.x),
                                              float(goal_msg.pose.position.y))
        scan = depth = person = None
        if "scan" in roles:
            scan = decode.scan(topics[roles["scan"]].msg, self._lidar_mount)
        if "depth" in roles:
            depth = decode.depth_image(topics[roles["depth"]].msg, topic=roles["depth"])
        if "person" in roles:
            person = decode.planar_pose(topics[roles["person"]].msg.pose)
        plan = self._decoded_plan(topics[roles["plan"]].msg) if "plan" in roles else None
        self._frame_stamp_ns = stamp_ns
        return SensorFrame(stamp_ns, pose, twist, goal, scan, depth, person, plan)

    def _decoded_plan(self, msg: Any) -> np.ndarray:
        """The plan message as points, decoded once per message (not at every step)."""
        if msg is not self._plan_msg:
            self._plan_msg, self._plan = msg, decode.path(msg)
        return self._plan

    def offered_qos(self, topic: str) -> OfferedQos | None:
        """The QoS the topic's first publisher offers, as the ROS graph reports it (depth 0:
        DDS does not tell a remote publisher's history depth)."""
        infos = self.node.get_publishers_info_by_topic(topic)
        if not infos:
            return None
        qos = infos[0].qos_profile
        return OfferedQos(reliable=qos.reliability == ReliabilityPolicy.RELIABLE,
                          transient_local=qos.durability == DurabilityPolicy.TRANSIENT_LOCAL,
                          depth=int(qos.depth))

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
