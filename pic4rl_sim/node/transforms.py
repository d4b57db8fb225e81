"""The sim's TF (REP 105): ``tf`` carries ``odom → base_link`` from the odometry it publishes,
``tf_static`` carries ``base_link →`` each sensor's frame, from the robot's mounts.

So a message's ``frame_id`` resolves through TF as on a real robot: a scan's ``laser`` through
``tf_static``, the odometry's ``odom → base_link`` through ``tf``. ``tf2_msgs`` is not on PyPI:
``make setup`` builds it (``ros/build.sh``); its type hash is real Jazzy's.

Sensor frames: ``laser`` at the LiDAR's mount (x, y, z) turned by its yaw; the depth image's
``camera_depth_optical_frame`` at the camera's mount, pitched down by its pitch, in the optical
convention (REP 103: z forward, x right, y down); ``imu_link`` at the base's origin (the IMU
reads the base's motion); a sonar ring's ``sonar_<i>`` at its mount, +x along cone i's axis;
a UWB tag's ``uwb_tag`` at its mount; a stereo camera's ``stereo_left_optical_frame`` at its mount
(the left camera's, optical).
"""

from __future__ import annotations

import math

from geometry_msgs.msg import TransformStamped
from nav_msgs.msg import Odometry
from std_msgs.msg import Header
from tf2_msgs.msg import TFMessage

from pic4rl_base.geometry import yaw_to_quaternion

from ..engine.core import Engine
from ..engine.sensor_kinds import NAMES as KIND_NAMES
from ..engine.sensor_kinds import OPTICAL_XYZW

Quaternion = tuple[float, float, float, float]
#: A sensor's frame in the base frame: (frame id, (x, y, z) m, quaternion (x, y, z, w)).
MountedFrame = tuple[str, tuple[float, float, float], Quaternion]

_IDENTITY: Quaternion = (0.0, 0.0, 0.0, 1.0)


def _multiply(a: Quaternion, b: Quaternion) -> Quaternion:
    """Hamilton product ``a ⊗ b`` (x, y, z, w): rotate by ``b``, then by ``a``."""
    ax, ay, az, aw = a
    bx, by, bz, bw = b
    return (aw * bx + ax * bw + ay * bz - az * by, aw * by - ax * bz + ay * bw + az * bx,
            aw * bz + ax * by - ay * bx + az * bw, aw * bw - ax * bx - ay * by - az * bz)


def sensor_frames(engine: Engine) -> tuple[MountedFrame, ...]:
    """Each sensor's frame in ``base_link``, for the sensors ``engine``'s robot carries."""
    frames: list[MountedFrame] = [(engine.imu.frame_id, (0.0, 0.0, 0.0), _IDENTITY)]
    if engine.lidar is not None:
        spec = engine.lidar.spec
        frames.append((engine.lidar.frame_id, spec.mount_xyz_m,
                       yaw_to_quaternion(spec.mount_yaw_rad)))
    if engine.depth is not None:
        cam = engine.depth.spec
        half = 0.5 * cam.mount_pitch_rad  # a positive pitch looks down: about +y
        pitch = (0.0, math.sin(half), 0.0, math.cos(half))
        frames.append((engine.depth.frame_id, cam.mount_xyz_m, _multiply(pitch, OPTICAL_XYZW)))
    for name in KIND_NAMES:  # the sonar ring's cones, the UWB tag
        if name in engine.sensors:
            frames.extend(engine.sensors[name].frames())
    return tuple(frames)


def static_transforms(engine: Engine, stamp_ns: int) -> TFMessage:
    """``tf_static``: ``base_link →`` each sensor frame of ``engine``, stamped ``stamp_ns``."""
    sec, nanosec = divmod(stamp_ns, 1_000_000_000)
    base = engine.odometry.child_frame_id
    transforms = []
    for frame, (x, y, z), (qx, qy, qz, qw) in sensor_frames(engine):
        tf = TransformStamped(header=Header(frame_id=base), child_frame_id=frame)
        tf.header.stamp.sec, tf.header.stamp.nanosec = sec, nanosec
        t, q = tf.transform.translation, tf.transform.rotation
        t.x, t.y, t.z = float(x), float(y), float(z)
        q.x, q.y, q.z, q.w = qx, qy, qz, qw
        transforms.append(tf)
    return TFMessage(transforms=transforms)


class OdomTransform:
    """``tf``: the odometry message's pose as ``odom → base_link``, sharing its header (stamp
    and frame) and refilled from it in place (``fill``, after the odometry's)."""

    def __init__(self, odom: Odometry) -> None:
        self._odom = odom
        self._tf = TransformStamped(header=odom.header, child_frame_id=odom.child_frame_id)
        self.msg = TFMessage(transforms=[self._tf])

    def fill(self) -> None:
        p, t = self._odom.pose.pose, self._tf.transform
        t.translation.x, t.translation.y, t.translation.z = p.position.x, p.position.y, p.position.z
        q, r = p.orientation, t.rotation
        r.x, r.y, r.z, r.w = q.x, q.y, q.z, q.w
