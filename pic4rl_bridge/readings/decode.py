"""ROS 2 messages → the plain values of a ``SensorFrame``.

Duck-typed on the message fields, so it needs no rclpy import: the ROS transport decodes what
it receives, and the in-process transport, when it records, decodes the messages it writes.
"""

from __future__ import annotations

import sys
from typing import Any

import numpy as np

from pic4rl_base.goal import Goal
from pic4rl_base.geometry import Pose2D
from pic4rl_sim.engine.geometry import Twist2D

from ..errors import TransportError
from .frame import ScanData, yaw_from_quaternion

_MM = 1e-3


def stamp_ns(header: Any) -> int:
    """A ``builtin_interfaces/Time`` (or a header holding one) as int nanoseconds."""
    stamp = getattr(header, "stamp", header)
    return int(stamp.sec) * 1_000_000_000 + int(stamp.nanosec)


def planar_pose(pose: Any) -> Pose2D:
    """A ``geometry_msgs/Pose`` as (x, y, yaw)."""
    q = pose.orientation
    return Pose2D(float(pose.position.x), float(pose.position.y),
                  yaw_from_quaternion(q.x, q.y, q.z, q.w))


def goal(msg: Any) -> Goal:
    """A ``geometry_msgs/PoseStamped`` goal: its position and, unless its orientation is the
    identity (a goal without heading), its heading."""
    p, q = msg.pose.position, msg.pose.orientation
    identity = (q.x, q.y, q.z, q.w) == (0.0, 0.0, 0.0, 1.0)
    return Goal(p.x, p.y, None if identity else yaw_from_quaternion(q.x, q.y, q.z, q.w))


def path(msg: Any) -> np.ndarray:
    """A ``nav_msgs/Path`` as its positions (k × 2, m, float64), in its header's frame."""
    return np.array([(float(p.pose.position.x), float(p.pose.position.y)) for p in msg.poses],
                    dtype=np.float64).reshape(-1, 2)


def people(msg: Any) -> np.ndarray:
    """A ``geometry_msgs/PoseArray`` of people as one (x, y, yaw) row each (n × 3, m and rad,
    float64), in the array's order (their identity) and its header's frame."""
    return np.array([tuple(planar_pose(p)) for p in msg.poses], dtype=np.float64).reshape(-1, 3)


def odometry(msg: Any) -> tuple[Pose2D, Twist2D]:
    """Pose and body twist of a ``nav_msgs/Odometry``."""
    lin, ang = msg.twist.twist.linear, msg.twist.twist.angular
    return planar_pose(msg.pose.pose), Twist2D(float(lin.x), float(lin.y), float(ang.z))


def scan(msg: Any, mount: Pose2D) -> ScanData:
    """A ``sensor_msgs/LaserScan`` (float32 ranges kept as they are). Its float32 fields are
    read as the wire holds them: a message built in this process and never serialized (the
    in-process transport's) still holds the float64 it was given."""
    return ScanData(np.array(msg.ranges, dtype=np.float32), _f32(msg.angle_min),
                    _f32(msg.angle_increment), _f32(msg.range_min), _f32(msg.range_max),
                    mount)


def _f32(value: float) -> float:
    return float(np.float32(value))


def depth_image(msg: Any, *, topic: str = "depth") -> np.ndarray:
    """A depth ``sensor_msgs/Image`` as metres (float32, height × width): ``32FC1`` in m, or
    ``16UC1`` in mm as real cameras publish (0 = no return → +inf, REP 118)."""
    h, w = int(msg.height), int(msg.width)
    order = ">" if msg.is_bigendian else "<"
    data = bytes(msg.data)
    if msg.encoding == "32FC1":
        pixels = np.frombuffer(data, dtype=f"{order}f4", count=h * w)
        image = pixels.reshape(h, w).astype(np.float32, copy=True)
    elif msg.encoding == "16UC1":
        raw = np.frombuffer(data, dtype=f"{order}u2", count=h * w).reshape(h, w)
        image = np.where(raw == 0, np.inf, raw * _MM).astype(np.float32)
    else:
        raise TransportError(f"{topic}: depth encoding {msg.encoding!r} is not supported; "
                             "expected 32FC1 (m) or 16UC1 (mm)")
    if image.dtype.byteorder not in ("=", "|") and sys.byteorder != "little":
        image = image.astype(np.float32)
    return image
