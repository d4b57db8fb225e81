"""Every topic and service of the sim node, in one table: pure data (no rclpy), so the node,
the bridge's transports and recorder, and the docs test all read the same names.

Names are relative (a namespace moves them all). Types are ROS type names; the node maps them
to rclpy classes and the QoS kinds to profiles in ``pic4rl_sim.node.ros_interfaces``. The
table's order is the docs' order, and for the ``STEP`` topics the order in which a step
publishes them: the scan (or, without a LiDAR, the depth image) is a step's last message.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import Enum

from pic4rl_base.plugins import load_group

from .engine.sensor_kinds import sonar, stereo, uwb


class Direction(str, Enum):
    """The node's side: it publishes, subscribes or serves."""

    PUB = "pub"
    SUB = "sub"
    SRV = "srv"


@dataclass(frozen=True)
class QosSettings:
    """Reliable or best effort, transient local (latched) or volatile, history depth (0: not
    known). The one description of a QoS: the node's kinds, the bridge's subscriptions, what
    a bag's metadata records (``pic4rl_bridge.transports.transport.OfferedQos``); rclpy's profiles
    are made from it (``pic4rl_sim.node.ros_interfaces.profile``)."""

    reliable: bool = True
    transient_local: bool = False
    depth: int = 10

    def __str__(self) -> str:
        return (f"{'reliable' if self.reliable else 'best effort'}, "
                f"{'transient local' if self.transient_local else 'volatile'}, {self.depth}")


class QosKind(Enum):
    """The QoS the node offers (or subscribes with)."""

    #: rclpy's ``qos_profile_sensor_data``: a reliable subscriber does not match it.
    SENSOR_DATA = QosSettings(reliable=False, transient_local=False, depth=5)
    RELIABLE = QosSettings(reliable=True, transient_local=False, depth=10)
    #: The current episode's message reaches a (transient-local) subscriber that joins later.
    LATCHED = QosSettings(reliable=True, transient_local=True, depth=1)


#: How many messages the bridge keeps per subscription (and its ``cmd_vel`` publisher): the
#: recorder must see every message.
BRIDGE_HISTORY = 100


def bridge_qos(kind: QosKind) -> QosSettings:
    """The QoS the bridge matches a ``kind`` topic with: the same policies, a longer history
    (``BRIDGE_HISTORY``) unless latched (only the current episode's message counts)."""
    settings = kind.value
    if settings.transient_local:
        return settings
    return QosSettings(settings.reliable, settings.transient_local, BRIDGE_HISTORY)


class Cadence(str, Enum):
    """When the node publishes a topic."""

    #: Each step, in the table's order (``pic4rl_sim.node.messages.StateMessages``).
    STEP = "every step"
    #: Each step, before the step's sensor messages (the physics status).
    STATUS = "every step, before the step's sensor messages"
    #: At each reset, before the episode's first step messages.
    EPISODE = "once per episode"


@dataclass(frozen=True)
class Interface:
    """One topic or service of the sim node."""

    name: str
    #: ROS type name, e.g. ``sensor_msgs/msg/LaserScan``.
    type: str
    direction: Direction
    #: ``None`` for a service (rclpy's services default).
    qos: QosKind | None
    #: What fills the message (a topic) or what a call does (a service).
    content: str
    #: When it is published (``None``: not published by the node).
    cadence: Cadence | None = None
    #: When the topic exists at all, e.g. "with a LiDAR"; empty: always.
    condition: str = ""
    #: Place in the episode bags' default topic list (``RECORDED``); ``None``: not recorded.
    record_order: int | None = None

    @property
    def published(self) -> str:
        """When it is published, as docs/sim.md's table says it."""
        if self.cadence is None:
            return "—"
        return f"{self.cadence.value}, {self.condition}" if self.condition else self.cadence.value


CMD_VEL = Interface(
    "cmd_vel", "geometry_msgs/msg/Twist", Direction.SUB, QosKind.RELIABLE,
    "the command: steps once in lockstep, the latest in realtime; holonomic robots use "
    "`linear.y`", record_order=4)
CLOCK = Interface(
    "clock", "rosgraph_msgs/msg/Clock", Direction.PUB, QosKind.RELIABLE,
    "sim time: the step's stamp", Cadence.STEP, record_order=0)
GROUND_TRUTH = Interface(
    "ground_truth", "nav_msgs/msg/Odometry", Direction.PUB, QosKind.RELIABLE,
    "the robot's exact pose and velocity", Cadence.STEP, record_order=1)
ODOM = Interface(
    "odom", "nav_msgs/msg/Odometry", Direction.PUB, QosKind.RELIABLE,
    "wheel odometry, with the robot's odometry errors", Cadence.STEP, record_order=2)
TF = Interface(
    "tf", "tf2_msgs/msg/TFMessage", Direction.PUB, QosKind.RELIABLE,
    "the odometry's pose as a transform (REP 105): one per `odom` message, stamped alike",
    Cadence.STEP, record_order=10)
IMU = Interface(
    "imu/data", "sensor_msgs/msg/Imu", Direction.PUB, QosKind.SENSOR_DATA,
    "the IMU: orientation, angular velocity, linear acceleration", Cadence.STEP)
PERSON_POSE = Interface(
    "person/pose", "geometry_msgs/msg/PoseStamped", Direction.PUB, QosKind.RELIABLE,
    "the person's pose", Cadence.STEP, "`person` worlds only", record_order=8)
PEOPLE = Interface(
    "people", "geometry_msgs/msg/PoseArray", Direction.PUB, QosKind.RELIABLE,
    "the crowd's people: one pose each, yaw along its velocity, the array's order their "
    "identity", Cadence.STEP, "with a crowd (`crowd.count` > 0)", record_order=12)
CAMERA_INFO = Interface(
    "camera/depth/camera_info", "sensor_msgs/msg/CameraInfo", Direction.PUB,
    QosKind.SENSOR_DATA, "the depth camera's intrinsics", Cadence.STEP, "with a depth camera",
    record_order=7)
DEPTH_IMAGE = Interface(
    "camera/depth/image_raw", "sensor_msgs/msg/Image", Direction.PUB, QosKind.SENSOR_DATA,
    "the depth image, 32FC1 (m)", Cadence.STEP, "with a depth camera", record_order=6)
SCAN = Interface(
    "scan", "sensor_msgs/msg/LaserScan", Direction.PUB, QosKind.SENSOR_DATA,
    "the LiDAR's ranges", Cadence.STEP, "with a LiDAR", record_order=3)
GOAL_POSE = Interface(
    "goal_pose", "geometry_msgs/msg/PoseStamped", Direction.PUB, QosKind.LATCHED,
    "the episode's goal", Cadence.EPISODE, record_order=5)
PLAN = Interface(
    "plan", "nav_msgs/msg/Path", Direction.PUB, QosKind.LATCHED,
    "the episode's global plan from start to goal (the shortest path with a clearance margin, "
    "`pic4rl_sim.engine.paths.plan_path`)", Cadence.EPISODE, record_order=9)
TF_STATIC = Interface(
    "tf_static", "tf2_msgs/msg/TFMessage", Direction.PUB, QosKind.LATCHED,
    "each sensor's frame on the base, from the robot's mounts", Cadence.EPISODE,
    record_order=11)
WORLD_MARKERS = Interface(
    "world/markers", "visualization_msgs/msg/MarkerArray", Direction.PUB, QosKind.LATCHED,
    "the world's boxes and cylinders, and the goal", Cadence.EPISODE)
DIAGNOSTICS = Interface(
    "diagnostics", "diagnostic_msgs/msg/DiagnosticArray", Direction.PUB, QosKind.RELIABLE,
    "status `sim: physics`: OK, or ERROR with the reason when the physics diverged; status "
    "`sim: contact`: WARN (`touching`) when the robot touched anything during the step, sensed "
    "or not, else OK (`clear`)", Cadence.STATUS)
RESET_WORLD = Interface(
    "reset_world", "std_srvs/srv/Empty", Direction.SRV, None, "starts the next episode")
PAUSE_PHYSICS = Interface(
    "pause_physics", "std_srvs/srv/Empty", Direction.SRV, None, "stops stepping")
#: A sonar ring's cones (``engine.sensor_kinds.sonar``): a ring of ``sonar.count`` publishes the
#: first ``count``.
SONAR = tuple(Interface(sonar.topic_name(i), "sensor_msgs/msg/Range", Direction.PUB,
                        QosKind.SENSOR_DATA, f"sonar cone {i}'s range (m, REP 117)", Cadence.STEP,
                        f"with `sonar.count` > {i}") for i in range(sonar.MAX_CONES))
#: A UWB tag's ranges (``engine.sensor_kinds.uwb``), one per anchor a robot's tag may range to,
#: then the goal's tag; the anchors' positions, latched.
UWB = tuple(Interface(uwb.topic_name(target), "sensor_msgs/msg/Range", Direction.PUB,
                      QosKind.SENSOR_DATA, f"the UWB range to {what} (m, REP 117)", Cadence.STEP,
                      when)
            for target, what, when in (
                *((f"a{i}", f"anchor a{i}", f"with `uwb.anchors_xy_m` of {i + 1}+ anchors")
                  for i in range(uwb.MAX_ANCHORS)),
                (uwb.GOAL_TAG, "the goal's tag", "with `uwb.goal_tag`")))
STEREO_DEPTH = Interface(
    stereo.DEPTH_TOPIC, "sensor_msgs/msg/Image", Direction.PUB, QosKind.SENSOR_DATA,
    "the stereo camera's depth, 32FC1 (m; NaN: no match)", Cadence.STEP, "with a stereo camera")
STEREO_DISPARITY = Interface(
    stereo.DISPARITY_TOPIC, "stereo_msgs/msg/DisparityImage", Direction.PUB,
    QosKind.SENSOR_DATA, "the stereo camera's disparity (px; -1: invalid), `f`, `T`",
    Cadence.STEP, "with a stereo camera")
UWB_ANCHORS = Interface(
    uwb.ANCHORS_TOPIC, "geometry_msgs/msg/PoseArray", Direction.PUB, QosKind.LATCHED,
    "the UWB anchors' positions, in name order", Cadence.EPISODE, "with UWB anchors")
UNPAUSE_PHYSICS = Interface(
    "unpause_physics", "std_srvs/srv/Empty", Direction.SRV, None, "resumes stepping")

#: The sim node's interfaces, in the docs' order (``STEP`` topics: in publishing order).
INTERFACE_TABLE = (CMD_VEL, CLOCK, GROUND_TRUTH, ODOM, TF, IMU, *SONAR, *UWB, STEREO_DEPTH,
                   STEREO_DISPARITY, PERSON_POSE,
                   PEOPLE, CAMERA_INFO,
              DEPTH_IMAGE, SCAN, GOAL_POSE, PLAN, TF_STATIC, UWB_ANCHORS, WORLD_MARKERS, DIAGNOSTICS,
              RESET_WORLD, PAUSE_PHYSICS, UNPAUSE_PHYSICS)
#: A user's sensors' topics: each an ``Interface`` that its package names in this entry-point
#: group under the topic's name, published after the IMU's (so that the scan stays last).
INTERFACE_GROUP = "pic4rl.interfaces"
_AFTER_IMU = INTERFACE_TABLE.index(IMU) + 1
INTERFACE_TABLE = (*INTERFACE_TABLE[:_AFTER_IMU],
                   *load_group(INTERFACE_GROUP, Interface,
                               taken={i.name for i in INTERFACE_TABLE}).values(),
                   *INTERFACE_TABLE[_AFTER_IMU:])
_BY_NAME = {i.name: i for i in INTERFACE_TABLE}
#: A step's state topics, in publishing order.
STEP_TOPICS = tuple(i for i in INTERFACE_TABLE if i.cadence is Cadence.STEP)
#: An episode's topics, in publishing order (at each reset, before the step topics).
EPISODE_TOPICS = tuple(i for i in INTERFACE_TABLE if i.cadence is Cadence.EPISODE)
#: The topics recorded to each episode's bag by default (the bag contract), in ``record_order``.
RECORDED = tuple(name for _, name in sorted((i.record_order, i.name) for i in INTERFACE_TABLE
                                             if i.record_order is not None))


def interface(name: str) -> Interface:
    """The interface of relative ``name``; ``KeyError`` if the sim has none."""
    return _BY_NAME[name]


def find(name: str) -> Interface | None:
    """The interface a topic name ends with, relative or resolved (``/robot1/scan``: scan);
    ``None`` if none."""
    parts = name.strip("/").split("/")
    for start in range(len(parts)):
        found = _BY_NAME.get("/".join(parts[start:]))
        if found is not None:
            return found
    return None
