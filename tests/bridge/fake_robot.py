"""A robot that is not pic4rl-sim, for the ROS integration tests: an rclpy node publishing
odometry, LaserScans of a known world in the geometries it is told, and a goal, as a real
robot's drivers and its operator would.

Usage: ``python fake_robot.py [--scan TOPIC:ANGLE_MIN:INCREMENT:BEAMS]... [--silence-after N]
[--scan-qos best_effort|reliable] [--no-odom]``. The robot starts at the origin heading +x,
drives with the last ``cmd_vel`` (a unicycle; ``--no-odom``: its odometry is advertised but
never published), and sees a round room of radius 5 m with three
thin posts (``POSTS``) from its LiDAR at ``MOUNT`` (the Jackal's). Every scan topic stops for
good once ``N`` commands have come (a LiDAR that dies mid-episode). The goal ``GOAL`` goes out
on ``goal_pose`` twice a second with one stamp (one operator goal). Prints ``READY``.
"""

from __future__ import annotations

import argparse
import math
import sys

import numpy as np
import rclpy
from geometry_msgs.msg import PoseStamped, Twist
from nav_msgs.msg import Odometry
from rclpy.executors import ExternalShutdownException
from rclpy.qos import QoSProfile, ReliabilityPolicy
from sensor_msgs.msg import LaserScan

RATE_HZ = 20.0
ROOM_RADIUS_M = 5.0
#: (distance from the origin (m), bearing (deg), radius (m)) of each post.
POSTS = ((1.0, 35.0, 0.02), (2.0, -65.0, 0.02), (1.5, 175.0, 0.02))
MOUNT = (0.12, 0.0)  # the Jackal's LiDAR, in its base frame (yaw 0)
GOAL = (3.0, 0.0)


def cast(x: float, y: float, theta: np.ndarray) -> np.ndarray:
    """Ranges (m) from (x, y) inside the room along the world directions ``theta``."""
    ux, uy = np.cos(theta), np.sin(theta)
    b = ux * x + uy * y
    out = -b + np.sqrt(b * b - (x * x + y * y - ROOM_RADIUS_M ** 2))
    for distance, bearing, radius in POSTS:
        cx = distance * math.cos(math.radians(bearing)) - x
        cy = distance * math.sin(math.radians(bearing)) - y
        along = ux * cx + uy * cy
        miss2 = cx * cx + cy * cy - along * along
        hit = (along > 0) & (miss2 <= radius * radius)
        near = along - np.sqrt(np.maximum(radius * radius - miss2, 0.0))
        out = np.where(hit, np.minimum(out, near), out)
    return out


def main(argv: list[str]) -> int:
    parser = argparse.ArgumentParser()
    parser.add_argument("--scan", action="append", default=[])
    parser.add_argument("--silence-after", type=int, default=0)
    parser.add_argument("--scan-qos", default="best_effort")
    parser.add_argument("--no-odom", action="store_true")
    args = parser.parse_args(argv)
    rclpy.init()
    node = rclpy.create_node("fake_robot")
    pose, command, heard = [0.0, 0.0, 0.0], Twist(), [0]

    def on_command(msg: Twist) -> None:
        command.linear.x, command.angular.z = msg.linear.x, msg.angular.z
        heard[0] += 1

    node.create_subscription(Twist, "cmd_vel", on_command, 10)
    odom_pub = node.create_publisher(Odometry, "odom", 10)
    goal_pub = node.create_publisher(PoseStamped, "goal_pose", 10)
    reliability = (ReliabilityPolicy.RELIABLE if args.scan_qos == "reliable"
                   else ReliabilityPolicy.BEST_EFFORT)
    scans = []
    for spec in args.scan:
        topic, angle_min, increment, beams = spec.split(":")
        scans.append((node.create_publisher(LaserScan, topic,
                                            QoSProfile(depth=5, reliability=reliability)),
                      float(angle_min), float(increment), int(beams)))
    goal = PoseStamped()
    goal.header.frame_id = "odom"
    goal.header.stamp = node.get_clock().now().to_msg()
    goal.pose.position.x, goal.pose.position.y = GOAL
    dt = 1.0 / RATE_HZ

    def tick() -> None:
        x, y, yaw = pose
        pose[0] = x + command.linear.x * math.cos(yaw) * dt
        pose[1] = y + command.linear.x * math.sin(yaw) * dt
        pose[2] = yaw + command.angular.z * dt
        stamp = node.get_clock().now().to_msg()
        if not args.no_odom:
            odom = Odometry()
            odom.header.stamp, odom.header.frame_id, odom.child_frame_id = stamp, "odom", "base"
            odom.pose.pose.position.x, odom.pose.pose.position.y = pose[0], pose[1]
            odom.pose.pose.orientation.z = math.sin(pose[2] / 2)
            odom.pose.pose.orientation.w = math.cos(pose[2] / 2)
            odom.twist.twist.linear.x, odom.twist.twist.angular.z = (command.linear.x,
                                                                     command.angular.z)
            odom_pub.publish(odom)
        if args.silence_after and heard[0] >= args.silence_after:
            return
        c, s = math.cos(pose[2]), math.sin(pose[2])
        mx, my = pose[0] + c * MOUNT[0] - s * MOUNT[1], pose[1] + s * MOUNT[0] + c * MOUNT[1]
        for publisher, angle_min, increment, beams in scans:
            angles = (float(np.float32(angle_min))
                      + float(np.float32(increment)) * np.arange(beams))
            msg = LaserScan()
            msg.header.stamp, msg.header.frame_id = stamp, "laser"
            msg.angle_min, msg.angle_increment = angle_min, increment
            msg.angle_max = angle_min + (beams - 1) * increment
            msg.range_min, msg.range_max = 0.1, 10.0
            msg.ranges = cast(mx, my, angles + pose[2]).astype(np.float32).tolist()
            publisher.publish(msg)

    node.create_timer(dt, tick)
    node.create_timer(0.5, lambda: goal_pub.publish(goal))
    print("READY", flush=True)
    try:
        rclpy.spin(node)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    finally:
        node.destroy_node()
        rclpy.try_shutdown()
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
