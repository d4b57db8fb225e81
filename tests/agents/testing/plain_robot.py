"""A robot without a simulator, for the tester's real-robot test: one rclpy process that
integrates ``cmd_vel`` into ``odom``, publishes a 360-beam ``scan`` of free space (every range
5 m) at 20 Hz, and, as the operator, a new goal on ``goal_pose`` 2 m ahead of the robot every
second. No world, no parameter services, no reset service: what ``pic4rl-test`` meets on a
real robot. Stamps are the system clock's, as a real robot's and rviz2's are.

Usage: ``python plain_robot.py`` (in the ROS domain of ``ROS_DOMAIN_ID``); SIGINT ends it.
"""

from __future__ import annotations

import math

import rclpy
from geometry_msgs.msg import PoseStamped, Twist
from nav_msgs.msg import Odometry
from rclpy.executors import ExternalShutdownException
from sensor_msgs.msg import LaserScan

PERIOD_S = 0.05
BEAMS = 360


def main() -> None:
    rclpy.init()
    node = rclpy.create_node("plain_robot")
    odom = node.create_publisher(Odometry, "odom", 10)
    scan = node.create_publisher(LaserScan, "scan", 10)
    goal = node.create_publisher(PoseStamped, "goal_pose", 10)
    state = {"x": 0.0, "y": 0.0, "yaw": 0.0, "v": 0.0, "w": 0.0, "ticks": 0}

    def command(msg: Twist) -> None:
        state["v"], state["w"] = msg.linear.x, msg.angular.z

    def tick() -> None:
        s = state
        s["yaw"] += s["w"] * PERIOD_S
        s["x"] += s["v"] * math.cos(s["yaw"]) * PERIOD_S
        s["y"] += s["v"] * math.sin(s["yaw"]) * PERIOD_S
        stamp = node.get_clock().now().to_msg()
        o = Odometry()
        o.header.stamp, o.header.frame_id, o.child_frame_id = stamp, "odom", "base_link"
        o.pose.pose.position.x, o.pose.pose.position.y = s["x"], s["y"]
        o.pose.pose.orientation.z = math.sin(s["yaw"] / 2)
        o.pose.pose.orientation.w = math.cos(s["yaw"] / 2)
        o.twist.twist.linear.x, o.twist.twist.angular.z = s["v"], s["w"]
        odom.publish(o)
        ls = LaserScan()
        ls.header.stamp, ls.header.frame_id = stamp, "laser"
        ls.angle_min, ls.angle_increment = -math.pi, 2 * math.pi / BEAMS
        ls.angle_max = ls.angle_min + ls.angle_increment * (BEAMS - 1)
        ls.range_min, ls.range_max = 0.1, 10.0
        ls.ranges = [5.0] * BEAMS
        scan.publish(ls)
        s["ticks"] += 1
        if s["ticks"] % 20 == 0:  # the operator: a new goal every second
            g = PoseStamped()
            g.header.stamp, g.header.frame_id = stamp, "odom"
            g.pose.position.x = s["x"] + 2.0 * math.cos(s["yaw"])
            g.pose.position.y = s["y"] + 2.0 * math.sin(s["yaw"])
            g.pose.orientation.w = 1.0
            goal.publish(g)

    node.create_subscription(Twist, "cmd_vel", command, 10)
    node.create_timer(PERIOD_S, tick)
    try:
        rclpy.spin(node)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    finally:
        node.destroy_node()
        rclpy.try_shutdown()


if __name__ == "__main__":
    main()
