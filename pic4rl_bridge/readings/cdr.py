"""The per-step messages read straight from their CDR bytes: odometry, scan, depth image and
the sim's physics status, without building rclpy message objects.

A lockstep step receives the pose and the task's sensor every step; rclpy's
``deserialize_message`` builds every nested message of them in Python (an ``Odometry`` is a
dozen objects and two 36-element covariances), which cost more than the task itself. These
readers take only the fields the frame needs, with the same values: ``float64`` fields as
the doubles they are, ``float32`` ones as the float a deserialized message holds. They read
plain little-endian CDR (encapsulation ``00 01``, what every ROS 2 middleware on x86 and ARM
sends) and return ``None`` for anything else, which the caller then deserializes as before.

Layout (XCDR1): a 4-byte encapsulation header, then each primitive aligned to its size from
the end of that header; a string is a ``uint32`` length counting its NUL, then its bytes; a
sequence a ``uint32`` count, then its elements.
"""

from __future__ import annotations

import struct
from typing import NamedTuple

import numpy as np
from pic4rl_base.geometry import Pose2D
from pic4rl_sim.engine.geometry import Twist2D

from .frame import ScanData, yaw_from_quaternion

_LE = b"\x00\x01"  # plain CDR, little endian
_HEAD = 4  # encapsulation bytes before the payload
_U32 = struct.Struct("<I")
_POSE = struct.Struct("<7d")  # position xyz, orientation xyzw
_TWIST = struct.Struct("<6d")  # linear xyz, angular xyz
_COVARIANCE_BYTES = 36 * 8
_SCAN_FIELDS = struct.Struct("<7f")  # angle_min ... range_max
_IMAGE_FIELDS = struct.Struct("<II")  # height, width


def _align(offset: int, size: int) -> int:
    """``offset`` (from the data's start) moved up to a multiple of ``size`` in the payload."""
    return offset + (-(offset - _HEAD) % size)


def _skip_string(data: bytes, offset: int) -> int:
    offset = _align(offset, 4)
    return offset + 4 + _U32.unpack_from(data, offset)[0]


def _string(data: bytes, offset: int) -> tuple[bytes, int]:
    """The string at ``offset`` (without its NUL) and the offset after it."""
    offset = _align(offset, 4)
    length = _U32.unpack_from(data, offset)[0]
    start = offset + 4
    return data[start:start + max(length - 1, 0)], start + length


def _after_header(data: bytes) -> int | None:
    """The offset after a ``std_msgs/Header`` that starts the payload, or ``None`` if the
    bytes are not plain little-endian CDR."""
    if data[:2] != _LE:
        return None
    return _skip_string(data, _HEAD + 8)  # stamp: int32 sec, uint32 nanosec; then frame_id


def odometry(data: bytes) -> tuple[Pose2D, Twist2D] | None:
    """A ``nav_msgs/Odometry``'s planar pose and body twist (``decode.odometry``'s values)."""
    offset = _after_header(data)
    if offset is None:
        return None
    offset = _align(_skip_string(data, offset), 8)  # child_frame_id
    x, y, _, qx, qy, qz, qw = _POSE.unpack_from(data, offset)
    offset += _POSE.size + _COVARIANCE_BYTES
    vx, vy, _, _, _, wz = _TWIST.unpack_from(data, offset)
    return Pose2D(x, y, yaw_from_quaternion(qx, qy, qz, qw)), Twist2D(vx, vy, wz)


def scan(data: bytes, mount: Pose2D) -> ScanData | None:
    """A ``sensor_msgs/LaserScan`` as ``decode.scan`` gives it (float32 ranges, a copy)."""
    offset = _after_header(data)
    if offset is None:
        return None
    offset = _align(offset, 4)
    angle_min, _, increment, _, _, range_min, range_max = _SCAN_FIELDS.unpack_from(data, offset)
    offset += _SCAN_FIELDS.size
    count = _U32.unpack_from(data, offset)[0]
    ranges = np.frombuffer(data, dtype="<f4", count=count, offset=offset + 4)
    return ScanData(ranges.astype(np.float32), angle_min, increment, range_min, range_max,
                    mount)


class Image(NamedTuple):
    """The fields of a ``sensor_msgs/Image`` that ``decode.depth_image`` reads."""

    height: int
    width: int
    encoding: str
    is_bigendian: int
    data: bytes


def image(data: bytes) -> Image | None:
    """A ``sensor_msgs/Image``'s size, encoding, byte order and pixel bytes."""
    offset = _after_header(data)
    if offset is None:
        return None
    offset = _align(offset, 4)
    height, width = _IMAGE_FIELDS.unpack_from(data, offset)
    encoding, offset = _string(data, offset + _IMAGE_FIELDS.size)
    bigendian = data[offset]
    offset = _align(offset + 1, 4) + 4  # step
    count = _U32.unpack_from(data, offset)[0]
    start = offset + 4
    return Image(height, width, encoding.decode(), bigendian, data[start:start + count])


def statuses(data: bytes) -> tuple[int, list[tuple[int, str, str]]] | None:
    """A ``diagnostic_msgs/DiagnosticArray``'s stamp (ns) and each status's (level, name,
    message)."""
    if data[:2] != _LE:
        return None
    sec, nanosec = struct.unpack_from("<iI", data, _HEAD)
    offset = _skip_string(data, _HEAD + 8)
    count = _U32.unpack_from(data, _align(offset, 4))[0]
    offset = _align(offset, 4) + 4
    found = []
    for _ in range(count):
        level = data[offset]
        name, offset = _string(data, offset + 1)
        message, offset = _string(data, offset)
        offset = _skip_string(data, offset)  # hardware_id
        offset = _align(offset, 4)
        values = _U32.unpack_from(data, offset)[0]
        offset += 4
        for _ in range(2 * values):  # each KeyValue: key, value
            offset = _skip_string(data, offset)
        found.append((level, name.decode(), message.decode()))
    return sec * 1_000_000_000 + nanosec, found
