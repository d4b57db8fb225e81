"""The sim's TF (REP 105): ``tf`` carries ``odom → base_link`` from the odometry it publishes,
``tf_static`` carries ``base_link →`` each sensor's frame, from the robot's mounts.

So a message's ``frame_id`` resolves through TF as on a real robot: a scan's ``laser`` through
``tf_static``, the odometry's ``odom → base_link`` through ``tf``. ``tf2_msgs`` is not on PyPI:
``make setup`` builds it (``ros/build.sh``); its type hash is real Jazzy's.

Sensor frames, each the sensor's own (its ``frames()``, beside its reading, so a sensor
added to ``SENSOR_TABLE`` brings its frame with no change here): ``laser`` at the LiDAR's
mount (x, y, z) turned by its yaw; the depth image's ``camera_depth_optical_frame`` at the
camera's mount, pitched down by its pitch, in the optical convention (REP 103: z forward, x
right, y down); ``imu_link`` at the base's origin (the IMU reads the base's motion); a sonar
ring's ``sonar_<i>`` at its mount, +x along cone i's axis; a UWB tag's ``uwb_tag`` at its
mount; a stereo camera's ``stereo_left_optical_frame`` at its mount (the left camera's,
optical).
"""

from __future__ import annotations

from geometry_msgs.msg import TransformStamped
from nav_msgs.msg import Odometry
from std_msgs.msg import Header
from tf2_msgs.msg import TFMessage

from ..engine.core import Engine

Quaternion = tuple[float, float, float, float]
#: A sensor's frame in the base frame: (frame id, (x, y, z) m, quaternion (x, y, z, w)).
MountedFrame = tuple[str, tuple[float, float, float], Quaternion]


def sensor_frames(engine: Engine) -> tuple[MountedFrame, ...]:
    """Each sensor's frame in ``base_link``, for the sensors ``engine``'s robot carries: what
    each one's ``frames()`` gives (a sensor without ``frames``, the wheel odometry, has none),
    the IMU's first, then ``SENSOR_TABLE``'s order: the order recorded bags hold them in."""
    ordered = sorted(engine.sensors.values(), key=lambda sensor: sensor is not engine.imu)
    return tuple(frame for sensor in ordered if hasattr(sensor, "frames")
                 for frame in sensor.frames())


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
