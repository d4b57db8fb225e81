"""The engine's state as ROS 2 messages, built once per engine and refilled in place each step.

The per-step path is the sim's hot loop (a lockstep client waits for it every control
period), so messages are allocated once; every header shares one ``Time`` object, and the
LiDAR ranges and depth pixels are written into the messages' own buffers through numpy views.

Frames: ``world`` is the fixed frame of the world's geometry, goal, person and ground truth;
``odom`` is wheel odometry's frame, equal to ``world`` when an episode starts (the estimate
starts at the true start pose, then drifts with the odometry's errors); sensors carry the
frame ids of ``pic4rl_sim.engine.sensors``, which ``tf_static`` places on ``base_link``, and ``tf``
carries the odometry's ``odom → base_link`` (``pic4rl_sim.node.transforms``).
"""

from __future__ import annotations

import array
import sys
from collections.abc import Callable, Container
from typing import Any

import numpy as np
from builtin_interfaces.msg import Time
from geometry_msgs.msg import Point, Pose, PoseArray, PoseStamped, Quaternion, Vector3
from nav_msgs.msg import Odometry, Path
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import CameraInfo, Image, Imu, LaserScan
from std_msgs.msg import ColorRGBA, Header
from visualization_msgs.msg import Marker, MarkerArray

from pic4rl_base.geometry import Pose2D, yaw_to_quaternion
from pic4rl_base.goal import Goal

from ..engine.core import Engine
from ..engine.sensor_kinds import sonar, stereo, uwb
from ..engine.sensors import EXACT_VARIANCE, SENSOR_TABLE
from ..engine.worlds.spec import WorldSpec
from ..interfaces import (CAMERA_INFO, CLOCK, DEPTH_IMAGE, EPISODE_TOPICS, GOAL_POSE, GROUND_TRUTH,
                          IMU, ODOM, PEOPLE, PERSON_POSE, PLAN, SCAN, SONAR, STEP_TOPICS,
                          STEREO_DEPTH, STEREO_DISPARITY, TF, TF_STATIC, UWB, UWB_ANCHORS,
                          WORLD_MARKERS, Interface)
from .transforms import OdomTransform, static_transforms

WORLD_FRAME = "world"
BASE_FRAME = "base_link"
#: Name of the sim node's per-step status on ``diagnostics``: ERROR when the physics diverged.
PHYSICS_STATUS = "sim: physics"
#: Name of its per-step contact status: WARN (message ``touching``) when the robot touched
#: anything during the step, sensed or not (``StepResult.collided``), else OK (``clear``).
CONTACT_STATUS = "sim: contact"
_RGBA = {
    "wall": (0.75, 0.75, 0.72, 1.0), "furniture": (0.55, 0.38, 0.22, 1.0),
    "obstacle": (0.35, 0.45, 0.6, 1.0), "trunk": (0.4, 0.26, 0.13, 1.0),
    "canopy": (0.2, 0.55, 0.2, 0.6), "person": (0.9, 0.55, 0.2, 1.0),
    "post": (0.6, 0.6, 0.58, 1.0),
    "goal": (0.1, 0.8, 0.1, 0.8),
}
_GOAL_MARKER_HEIGHT_M = 0.05
_POSE_VARIANCE = tuple(EXACT_VARIANCE if i % 7 == 0 else 0.0 for i in range(36))  # diagonal


def set_stamp(stamp: Time, stamp_ns: int) -> None:
    """Write ``stamp_ns`` (ns) into ``stamp`` in place."""
    stamp.sec, stamp.nanosec = divmod(stamp_ns, 1_000_000_000)


def _set_pose(pose: Pose, p: Pose2D) -> None:
    """Fill a ``geometry_msgs/Pose`` from a planar pose."""
    pose.position.x, pose.position.y = p.x, p.y
    q = pose.orientation
    q.x, q.y, q.z, q.w = yaw_to_quaternion(p.yaw)


def _odometry(stamp: Time, frame_id: str, exact: bool) -> Odometry:
    msg = Odometry(header=Header(stamp=stamp, frame_id=frame_id), child_frame_id=BASE_FRAME)
    if exact:
        msg.pose.covariance = _POSE_VARIANCE
        msg.twist.covariance = _POSE_VARIANCE
    return msg


class _Imu:
    """``imu/data``: the IMU's sample (every robot has one)."""

    def __init__(self, engine: Engine, stamp: Time) -> None:
        imu = engine.imu
        self.msg = Imu(header=Header(stamp=stamp, frame_id=imu.frame_id),
                       orientation_covariance=imu.orientation_covariance,
                       angular_velocity_covariance=imu.angular_velocity_covariance,
                       linear_acceleration_covariance=imu.linear_acceleration_covariance)
        self.held = {IMU: self.msg}

    def fill(self, engine: Engine) -> None:
        reading = engine.imu_reading()
        q, w, a = self.msg.orientation, self.msg.angular_velocity, self.msg.linear_acceleration
        q.x, q.y, q.z, q.w = reading.orientation_xyzw
        w.x, w.y, w.z = reading.angular_velocity_xyz
        a.x, a.y, a.z = reading.linear_acceleration_xyz


class _Person:
    """``person/pose``: the walking person's pose (worlds with a person)."""

    def __init__(self, engine: Engine, stamp: Time) -> None:
        self.msg = PoseStamped(header=Header(stamp=stamp, frame_id=WORLD_FRAME))
        self.held = {PERSON_POSE: self.msg}

    def fill(self, engine: Engine) -> None:
        person = engine.person_pose()
        if person is not None:
            _set_pose(self.msg.pose, person[0])


class _People:
    """``people``: the crowd's poses, one ``Pose`` per person in the crowd's order (allocated
    once; a person's velocity is the difference of its consecutive poses over the period)."""

    def __init__(self, engine: Engine, stamp: Time) -> None:
        count = engine.config.crowd.count
        self.msg = PoseArray(header=Header(stamp=stamp, frame_id=WORLD_FRAME),
                             poses=[Pose() for _ in range(count)])
        self.held = {PEOPLE: self.msg}

    def fill(self, engine: Engine) -> None:
        people = engine.people()
        assert people is not None
        for pose, (x, y), yaw in zip(self.msg.poses, *people):
            _set_pose(pose, Pose2D(float(x), float(y), float(yaw)))


class _Depth:
    """``camera/depth/image_raw`` (pixels written in place) and its ``camera_info``."""

    def __init__(self, engine: Engine, stamp: Time) -> None:
        cam = engine.depth
        assert cam is not None
        header = Header(stamp=stamp, frame_id=cam.frame_id)
        image = Image(header=header, height=cam.height, width=cam.width, encoding="32FC1",
                      is_bigendian=int(sys.byteorder == "big"), step=4 * cam.width)
        image.data = array.array("B", bytes(4 * cam.width * cam.height))
        self._pixels = np.frombuffer(image.data, dtype=np.float32).reshape(cam.height,
                                                                            cam.width)
        info = CameraInfo(
            header=header, height=cam.height, width=cam.width, distortion_model="plumb_bob",
            d=[0.0] * 5, k=cam.k_matrix, r=(1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0),
            p=cam.p_matrix)
        self.held = {DEPTH_IMAGE: image, CAMERA_INFO: info}

    def fill(self, engine: Engine) -> None:
        self._pixels[...] = engine.depth_image()


class _Scan:
    """``scan``: the LiDAR's ranges, written in place."""

    def __init__(self, engine: Engine, stamp: Time) -> None:
        lidar = engine.lidar
        assert lidar is not None
        msg = LaserScan(
            header=Header(stamp=stamp, frame_id=lidar.frame_id),
            angle_min=lidar.angle_min_rad, angle_max=lidar.angle_max_rad,
            angle_increment=lidar.angle_increment_rad, time_increment=0.0,
            scan_time=engine.config.control_dt_s, range_min=lidar.range_min_m,
            range_max=lidar.range_max_m)
        msg.ranges = array.array("f", bytes(4 * lidar.spec.beams))
        self._ranges = np.frombuffer(msg.ranges, dtype=np.float32)
        self.held = {SCAN: msg}

    def fill(self, engine: Engine) -> None:
        self._ranges[...] = engine.scan()


#: Each sensor's step messages: (whether an engine has it, its message maker). A maker holds
#: ``held`` (interface → message, allocated once) and ``fill(engine)`` writes a reading.
SENSOR_MESSAGES: tuple[tuple[Callable[[Engine], bool], Callable[[Engine, Time], Any]], ...] = (
    (lambda engine: True, _Imu),
    (lambda engine: sonar.NAME in engine.sensors,
     lambda engine, stamp: sonar.RangeMessages(engine, stamp, SONAR)),
    (lambda engine: uwb.NAME in engine.sensors,
     lambda engine, stamp: uwb.RangeMessages(engine, stamp, dict(zip(uwb.TARGETS, UWB)))),
    (lambda engine: stereo.NAME in engine.sensors,
     lambda engine, stamp: stereo.StereoMessages(engine, stamp, STEREO_DEPTH, STEREO_DISPARITY)),
    (lambda engine: engine.world.person is not None, _Person),
    (lambda engine: engine.crowd is not None, _People),
    (lambda engine: engine.depth is not None, _Depth),
    (lambda engine: engine.lidar is not None, _Scan),
    *((lambda engine, name=kind.name: name in engine.sensors, kind.messages)
      for kind in SENSOR_TABLE if kind.messages is not None),  # a user's sensors'
)


class StateMessages:
    """One step's messages for ``engine``; ``fill`` refreshes them for a new stamp.

    ``stamp`` is shared by every header and the clock, so one write re-stamps them all.
    Sensors the robot lacks (and the person, in a world without one) have no messages.
    """

    def __init__(self, engine: Engine) -> None:
        self.stamp = Time()
        stamp = self.stamp
        self.clock = Clock(clock=stamp)
        self.ground_truth = _odometry(stamp, WORLD_FRAME, exact=True)
        self.odom = _odometry(stamp, engine.odometry.frame_id, exact=False)
        self._tf = OdomTransform(self.odom)
        self._sensors = [make(engine, stamp) for has, make in SENSOR_MESSAGES if has(engine)]
        held: dict[Interface, Any] = {CLOCK: self.clock, GROUND_TRUTH: self.ground_truth,
                                      ODOM: self.odom, TF: self._tf.msg}
        for sensor in self._sensors:
            held.update(sensor.held)
        #: (topic, message) of each step topic this engine has, in publishing order.
        self.published: tuple[tuple[Interface, Any], ...] = tuple(
            (topic, held[topic]) for topic in STEP_TOPICS if topic in held)

    def fill(self, engine: Engine, stamp_ns: int) -> None:
        """Stamp every message with ``stamp_ns`` (ns) and fill it from ``engine`` now."""
        set_stamp(self.stamp, stamp_ns)
        gt = self.ground_truth
        _set_pose(gt.pose.pose, engine.robot_pose())
        twist = engine.robot_twist()
        lin, ang = gt.twist.twist.linear, gt.twist.twist.angular
        lin.x, lin.y, ang.z = twist.vx, twist.vy, twist.wz
        pose, twist = engine.wheel_odometry()
        odom = self.odom
        _set_pose(odom.pose.pose, pose)
        lin, ang = odom.twist.twist.linear, odom.twist.twist.angular
        lin.x, lin.y, ang.z = twist.vx, twist.vy, twist.wz
        self._tf.fill()
        for sensor in self._sensors:
            sensor.fill(engine)


def goal_pose(goal: Goal, stamp_ns: int) -> PoseStamped:
    """The goal as a pose in the world frame: its heading, or the identity orientation for a
    goal without one."""
    msg = PoseStamped(header=Header(frame_id=WORLD_FRAME))
    set_stamp(msg.header.stamp, stamp_ns)
    msg.pose.position.x, msg.pose.position.y = goal
    if goal.yaw is not None:
        q = msg.pose.orientation
        q.x, q.y, q.z, q.w = yaw_to_quaternion(goal.yaw)
    return msg


def plan_message(points: np.ndarray, stamp_ns: int) -> Path:
    """A plan (k × 2, m) as a ``nav_msgs/Path`` in the world frame: each pose heads along its
    segment (the last one along the one before it); an empty plan has no poses."""
    msg = Path(header=Header(frame_id=WORLD_FRAME))
    set_stamp(msg.header.stamp, stamp_ns)
    pts = np.asarray(points, dtype=np.float64).reshape(-1, 2)
    if len(pts) > 1:
        d = np.diff(pts, axis=0)
        yaws = np.arctan2(d[:, 1], d[:, 0])
        yaws = np.append(yaws, yaws[-1])
    else:
        yaws = np.zeros(len(pts))
    for (x, y), yaw in zip(pts, yaws):
        pose = PoseStamped(header=msg.header)
        pose.pose.position.x, pose.pose.position.y = float(x), float(y)
        qx, qy, qz, qw = yaw_to_quaternion(float(yaw))
        pose.pose.orientation = Quaternion(x=qx, y=qy, z=qz, w=qw)
        msg.poses.append(pose)
    return msg


def _marker(ns: str, index: int, shape: int, header: Header, kind: str) -> Marker:
    r, g, b, a = _RGBA.get(kind, _RGBA["obstacle"])
    return Marker(header=header, ns=ns, id=index, type=shape, action=Marker.ADD,
                  color=ColorRGBA(r=r, g=g, b=b, a=a), frame_locked=False)


def world_markers(world: WorldSpec, goal: Goal, stamp_ns: int) -> MarkerArray:
    """One marker per box and cylinder of ``world`` and one for the goal, after a DELETEALL
    that clears what an earlier world left in a viewer."""
    header = Header(frame_id=WORLD_FRAME)
    set_stamp(header.stamp, stamp_ns)
    markers = [Marker(header=header, action=Marker.DELETEALL)]
    for i, box in enumerate(world.boxes):
        m = _marker("boxes", i, Marker.CUBE, header, box.kind)
        m.pose.position = Point(x=box.x, y=box.y, z=box.z_base_m + 0.5 * box.height_m)
        x, y, z, w = yaw_to_quaternion(box.yaw_rad)
        m.pose.orientation = Quaternion(x=x, y=y, z=z, w=w)
        m.scale = Vector3(x=box.size_x_m, y=box.size_y_m, z=box.height_m)
        markers.append(m)
    for i, cyl in enumerate(world.cylinders):
        m = _marker("cylinders", i, Marker.CYLINDER, header, cyl.kind)
        m.pose.position = Point(x=cyl.x, y=cyl.y, z=cyl.z_base_m + 0.5 * cyl.height_m)
        m.scale = Vector3(x=2 * cyl.radius_m, y=2 * cyl.radius_m, z=cyl.height_m)
        markers.append(m)
    m = _marker("goal", 0, Marker.CYLINDER, header, "goal")
    m.pose.position = Point(x=goal[0], y=goal[1], z=0.5 * _GOAL_MARKER_HEIGHT_M)
    m.scale = Vector3(x=0.3, y=0.3, z=_GOAL_MARKER_HEIGHT_M)
    markers.append(m)
    return MarkerArray(markers=markers)


def episode_messages(engine: Engine, stamp_ns: int,
                     topics: Container[str] | None = None) -> list[tuple[Interface, Any]]:
    """The episode's messages (goal, plan, sensor frames, UWB anchors, markers), stamped
    ``stamp_ns``, in publishing order; of ``topics`` (relative names) only, when given (the
    rest not made); a topic this engine has no message for (no UWB anchors) is left out."""
    anchors_header = Header(frame_id=WORLD_FRAME)
    set_stamp(anchors_header.stamp, stamp_ns)
    makers: dict[Interface, Callable[[], Any]] = {
        GOAL_POSE: lambda: goal_pose(engine.goal, stamp_ns),
        PLAN: lambda: plan_message(engine.plan(), stamp_ns),
        TF_STATIC: lambda: static_transforms(engine, stamp_ns),
        UWB_ANCHORS: lambda: uwb.anchors_message(engine, anchors_header),
        WORLD_MARKERS: lambda: world_markers(engine.world, engine.goal, stamp_ns),
    }
    made = [(topic, makers[topic]()) for topic in EPISODE_TOPICS
            if topics is None or topic.name in topics]
    return [(topic, msg) for topic, msg in made if msg is not None]
