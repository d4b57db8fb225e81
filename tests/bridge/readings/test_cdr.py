"""The CDR readers (``pic4rl_bridge.readings.cdr``) give bit for bit what rclpy's
deserialization and ``decode`` give, for every alignment the strings before the fields make;
bytes that are not plain little-endian CDR are left to rclpy."""

from __future__ import annotations

import math

import numpy as np
import pytest
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
from nav_msgs.msg import Odometry
from rclpy.serialization import deserialize_message, serialize_message
from sensor_msgs.msg import Image, LaserScan

from pic4rl_bridge.readings import cdr, decode
from pic4rl_bridge.readings.frame import ScanData
from pic4rl_base.geometry import Pose2D

FRAME_IDS = ["", "o", "od", "odo", "odom", "base_link_x"]  # every string length mod 8
MOUNT = Pose2D(0.12, -0.03, 0.1)


def _big_endian(data: bytes) -> bytes:
    return b"\x00\x00" + data[2:]  # only the header's flag: the reader must not trust it


@pytest.mark.parametrize("frame_id", FRAME_IDS)
@pytest.mark.parametrize("child", FRAME_IDS)
def test_odometry_equals_the_deserialized_message(frame_id: str, child: str) -> None:
    msg = Odometry(child_frame_id=child)
    msg.header.frame_id, msg.header.stamp.sec, msg.header.stamp.nanosec = frame_id, 7, 9
    p, q, t = msg.pose.pose.position, msg.pose.pose.orientation, msg.twist.twist
    p.x, p.y, p.z = 1.0 / 3.0, -2.5e-9, 4.0
    q.x, q.y, q.z, q.w = 0.0, 0.0, math.sin(1.1), math.cos(1.1)
    t.linear.x, t.linear.y, t.linear.z = 0.3, -0.1, 9.0
    t.angular.x, t.angular.y, t.angular.z = 5.0, 6.0, -0.7
    msg.pose.covariance[0] = msg.twist.covariance[35] = 123.0  # must not be read as a field
    data = serialize_message(msg)
    expected = decode.odometry(deserialize_message(data, Odometry))
    assert cdr.odometry(data) == expected
    assert cdr.odometry(data)[0] == Pose2D(1.0 / 3.0, -2.5e-9, expected[0].yaw)
    assert cdr.odometry(_big_endian(data)) is None


@pytest.mark.parametrize("frame_id", FRAME_IDS)
def test_scan_equals_the_deserialized_message(frame_id: str) -> None:
    msg = LaserScan(angle_min=-math.pi, angle_max=math.pi, angle_increment=2 * math.pi / 5,
                    time_increment=0.5, scan_time=0.1, range_min=0.05, range_max=10.0)
    msg.header.frame_id = frame_id
    msg.ranges = [1.5, math.inf, -math.inf, 0.1 + 1e-9, 9.99]
    msg.intensities = [1.0, 2.0]
    data = serialize_message(msg)
    expected = decode.scan(deserialize_message(data, LaserScan), MOUNT)
    got = cdr.scan(data, MOUNT)
    assert isinstance(got, ScanData)
    assert got.ranges.dtype == np.float32 and got.ranges.flags.writeable
    np.testing.assert_array_equal(got.ranges, expected.ranges)
    assert (got.angle_min_rad, got.angle_increment_rad, got.range_min_m, got.range_max_m,
            got.mount) == (expected.angle_min_rad, expected.angle_increment_rad,
                           expected.range_min_m, expected.range_max_m, MOUNT)
    assert got.angle_increment_rad == float(np.float32(2 * math.pi / 5))
    assert cdr.scan(serialize_message(LaserScan()), MOUNT).ranges.shape == (0,)
    assert cdr.scan(_big_endian(data), MOUNT) is None


@pytest.mark.parametrize("encoding", ["32FC1", "16UC1", "mono8"])
@pytest.mark.parametrize("frame_id", FRAME_IDS[:4])
def test_image_fields_equal_the_deserialized_message(encoding: str, frame_id: str) -> None:
    pixels = np.arange(6, dtype=np.float32).reshape(2, 3) + 0.25
    msg = Image(height=2, width=3, encoding=encoding, is_bigendian=0, step=12)
    msg.header.frame_id = frame_id
    msg.data = pixels.tobytes()
    data = serialize_message(msg)
    got = cdr.image(data)
    assert got == (2, 3, encoding, 0, pixels.tobytes())
    if encoding == "32FC1":
        np.testing.assert_array_equal(decode.depth_image(got), pixels)
    assert cdr.image(_big_endian(data)) is None


def test_statuses_read_every_status_after_any_values() -> None:
    msg = DiagnosticArray(status=[
        DiagnosticStatus(level=DiagnosticStatus.WARN, name="motors", message="hot",
                         hardware_id="x", values=[KeyValue(key="t", value="80"),
                                                  KeyValue(key="unit", value="C")]),
        DiagnosticStatus(level=DiagnosticStatus.ERROR, name="sim: physics",
                         message="diverged: qacc 1e10", hardware_id="jackal")])
    msg.header.stamp.sec, msg.header.stamp.nanosec, msg.header.frame_id = 3, 200, "abc"
    data = serialize_message(msg)
    assert cdr.statuses(data) == (3_000_000_200, [(1, "motors", "hot"),
                                                  (2, "sim: physics", "diverged: qacc 1e10")])
    assert cdr.statuses(serialize_message(DiagnosticArray())) == (0, [])
    assert cdr.statuses(_big_endian(data)) is None
