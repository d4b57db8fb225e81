"""``pic4rl_bridge.readings.decode`` on real ROS 2 message objects (rclpy's message packages, no
ROS graph): poses and yaw from quaternions, odometry twists, scans, depth images in both encodings
and byte orders, and ``frame.as_published`` agreeing with a decoded message."""

from __future__ import annotations

import math

import numpy as np
import pytest
from builtin_interfaces.msg import Time
from geometry_msgs.msg import PoseStamped
from nav_msgs.msg import Odometry
from rclpy.serialization import deserialize_message, serialize_message
from sensor_msgs.msg import Image, LaserScan

from pic4rl_base.geometry import Pose2D, yaw_to_quaternion
from pic4rl_bridge.errors import TransportError
from pic4rl_bridge.readings import decode
from pic4rl_bridge.readings.frame import ScanData, as_published, yaw_from_quaternion
from pic4rl_sim.engine.geometry import Twist2D

YAWS = [0.0, 0.3, -0.3, 1.0, math.pi / 2, -math.pi / 2, 2.5, -2.5, 3.1, -3.1,
        math.pi, -math.pi, math.nextafter(math.pi, 0.0)]


def angle_gap(a: float, b: float) -> float:
    """|a - b| on the circle (rad)."""
    return abs(math.remainder(a - b, 2.0 * math.pi))


def pose_stamped(pose: Pose2D, stamp_ns: int = 0) -> PoseStamped:
    msg = PoseStamped()
    msg.header.stamp = Time(sec=stamp_ns // 1_000_000_000, nanosec=stamp_ns % 1_000_000_000)
    msg.header.frame_id = "world"
    msg.pose.position.x, msg.pose.position.y = pose.x, pose.y
    q = msg.pose.orientation
    q.x, q.y, q.z, q.w = yaw_to_quaternion(pose.yaw)
    return msg


def depth_msg(pixels: np.ndarray, encoding: str, dtype: str, *, big: bool = False) -> Image:
    h, w = pixels.shape
    msg = Image(height=h, width=w, encoding=encoding, is_bigendian=int(big))
    msg.step = w * np.dtype(dtype).itemsize
    msg.data = np.ascontiguousarray(pixels, dtype=dtype).tobytes()
    return msg


# --- poses ------------------------------------------------------------------------------------


@pytest.mark.parametrize("yaw", YAWS)
def test_yaw_from_quaternion_inverts_yaw_to_quaternion(yaw: float) -> None:
    """The decoded yaw is the encoded one (to rounding) and stays in [-pi, pi]."""
    decoded = yaw_from_quaternion(*yaw_to_quaternion(yaw))
    assert -math.pi <= decoded <= math.pi
    assert angle_gap(decoded, yaw) < 1e-12


def test_yaw_at_plus_and_minus_pi_keeps_its_sign() -> None:
    """+pi and -pi are both half a turn; each decodes to the one it was."""
    assert yaw_from_quaternion(*yaw_to_quaternion(math.pi)) == pytest.approx(math.pi, abs=1e-12)
    assert yaw_from_quaternion(*yaw_to_quaternion(-math.pi)) == pytest.approx(-math.pi,
                                                                              abs=1e-12)


def test_yaw_ignores_the_quaternion_sign() -> None:
    """q and -q are the same rotation."""
    x, y, z, w = yaw_to_quaternion(1.2)
    assert yaw_from_quaternion(-x, -y, -z, -w) == pytest.approx(1.2, abs=1e-12)


def test_planar_pose_of_a_pose_stamped() -> None:
    msg = pose_stamped(Pose2D(1.5, -2.25, 0.7), stamp_ns=3_000_000_123)
    pose = decode.planar_pose(msg.pose)
    assert (pose.x, pose.y) == (1.5, -2.25)
    assert pose.yaw == pytest.approx(0.7, abs=1e-12)
    assert decode.stamp_ns(msg.header) == 3_000_000_123
    assert decode.stamp_ns(msg.header.stamp) == 3_000_000_123


@pytest.mark.parametrize("yaw", YAWS)
def test_as_published_equals_the_decoded_message(yaw: float) -> None:
    """``as_published`` is exactly what a subscriber decodes from a message filled from the
    same pose, serialized to CDR and back."""
    pose = Pose2D(-3.25, 4.125, yaw)
    data = serialize_message(pose_stamped(pose))
    received = deserialize_message(data, PoseStamped)
    assert as_published(pose) == decode.planar_pose(received.pose)


def test_odometry_gives_pose_and_body_twist() -> None:
    msg = Odometry()
    msg.header.stamp = Time(sec=12, nanosec=500_000_000)
    msg.pose.pose = pose_stamped(Pose2D(0.5, 0.25, -2.0)).pose
    msg.twist.twist.linear.x, msg.twist.twist.linear.y = 0.4, -0.1
    msg.twist.twist.angular.z = 0.75
    msg.twist.twist.angular.x = 9.0  # not planar: ignored
    pose, twist = decode.odometry(msg)
    assert (pose.x, pose.y) == (0.5, 0.25)
    assert pose.yaw == pytest.approx(-2.0, abs=1e-12)
    assert twist == Twist2D(0.4, -0.1, 0.75)
    assert decode.stamp_ns(msg.header) == 12_500_000_000


# --- scans ------------------------------------------------------------------------------------


def test_scan_keeps_float32_ranges_and_angles() -> None:
    """Ranges stay float32 bit for bit, REP 117 infinities and NaN included; the angles and
    limits are the message's float32 fields."""
    ranges = np.array([1.0, 0.1 + 1e-7, math.inf, -math.inf, math.nan, 9.75], np.float32)
    msg = LaserScan(angle_min=-math.pi, angle_max=math.pi, angle_increment=2 * math.pi / 6,
                    range_min=0.1, range_max=10.0)
    msg.ranges = ranges.tolist()
    msg = deserialize_message(serialize_message(msg), LaserScan)  # as a subscriber gets it
    mount = Pose2D(0.12, 0.0, 0.1)
    scan = decode.scan(msg, mount)
    assert isinstance(scan, ScanData)
    assert scan.ranges.dtype == np.float32
    np.testing.assert_array_equal(scan.ranges, ranges)
    assert scan.mount == mount
    assert scan.angle_min_rad == float(np.float32(-math.pi))
    assert scan.range_min_m == float(np.float32(0.1)) and scan.range_max_m == 10.0
    np.testing.assert_allclose(scan.angles()[[0, 3]], [-math.pi, 0.0], atol=1e-6)


def test_an_unserialized_scan_decodes_as_the_wire_would_carry_it() -> None:
    """The in-process transport decodes messages it built and never serialized, whose float32
    fields still hold float64: its frames must equal the ROS transport's all the same."""
    msg = LaserScan(angle_min=-math.pi, angle_max=math.pi, angle_increment=2 * math.pi / 360,
                    range_min=0.1, range_max=10.0)
    msg.ranges = [1.0] * 360
    wire = deserialize_message(serialize_message(msg), LaserScan)
    local, remote = decode.scan(msg, Pose2D(0.0, 0.0)), decode.scan(wire, Pose2D(0.0, 0.0))
    assert (local.angle_min_rad, local.angle_increment_rad, local.range_min_m) == (
        remote.angle_min_rad, remote.angle_increment_rad, remote.range_min_m)
    np.testing.assert_array_equal(local.angles(), remote.angles())


# --- depth images -----------------------------------------------------------------------------

PIXELS_M = np.array([[0.5, 1.25, math.inf], [3.0, 0.0, 7.125]], np.float32)


@pytest.mark.parametrize("big", [False, True], ids=["little", "big"])
def test_depth_32fc1_in_either_byte_order(big: bool) -> None:
    """32FC1 (m) is decoded from either byte order to native float32 metres."""
    msg = depth_msg(PIXELS_M, "32FC1", ">f4" if big else "<f4", big=big)
    image = decode.depth_image(msg)
    assert image.shape == (2, 3) and image.dtype == np.float32
    assert image.dtype.isnative
    np.testing.assert_array_equal(image, PIXELS_M)


def test_depth_byte_order_matters() -> None:
    """The same bytes read with the other byte order are other depths (the flag is used)."""
    msg = depth_msg(PIXELS_M, "32FC1", ">f4", big=False)  # big-endian bytes, flagged little
    assert not np.array_equal(decode.depth_image(msg), PIXELS_M)


@pytest.mark.parametrize("big", [False, True], ids=["little", "big"])
def test_depth_16uc1_millimetres_and_zero_is_no_return(big: bool) -> None:
    """16UC1 in mm becomes metres; 0 (no return) becomes +inf."""
    raw = np.array([[0, 1, 500], [1250, 65535, 0]], np.uint16)
    msg = depth_msg(raw, "16UC1", ">u2" if big else "<u2", big=big)
    image = decode.depth_image(msg)
    assert image.dtype == np.float32 and image.dtype.isnative
    expected = np.array([[math.inf, 0.001, 0.5], [1.25, 65.535, math.inf]], np.float32)
    np.testing.assert_allclose(image, expected, rtol=1e-6)
    assert np.isposinf(image[[0, 1], [0, 2]]).all()


def test_depth_ignores_padding_beyond_the_pixels() -> None:
    """Only height × width pixels are read."""
    msg = depth_msg(PIXELS_M, "32FC1", "<f4")
    msg.data = bytes(msg.data) + b"\x00" * 8
    np.testing.assert_array_equal(decode.depth_image(msg), PIXELS_M)


@pytest.mark.parametrize("encoding", ["rgb8", "mono16", "32FC3", ""])
def test_unsupported_depth_encoding_names_the_topic(encoding: str) -> None:
    msg = depth_msg(np.zeros((2, 2), np.uint8), encoding, "u1")
    with pytest.raises(TransportError, match=rf"^/robot1/camera/depth/image_raw: depth "
                                             rf"encoding '{encoding}' is not supported"):
        decode.depth_image(msg, topic="/robot1/camera/depth/image_raw")


def test_a_goal_pose_keeps_its_heading_and_the_identity_means_none() -> None:
    """The sim's ``goal_pose`` of a goal with and without heading, through CDR, back to the
    same ``Goal``."""
    from pic4rl_base.goal import Goal
    from pic4rl_sim.node.messages import goal_pose

    for goal in (Goal(1.5, -2.0), Goal(1.5, -2.0, 0.75), Goal(0.0, 0.0, -3.0)):
        msg = deserialize_message(serialize_message(goal_pose(goal, 5)), PoseStamped)
        back = decode.goal(msg)
        assert tuple(back) == tuple(goal)
        assert (back.yaw is None) == (goal.yaw is None)
        if goal.yaw is not None:
            assert back.yaw == pytest.approx(goal.yaw, abs=1e-12)
