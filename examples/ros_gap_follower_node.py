"""A ROS 2 navigation node as a user would write it: plain rclpy, nothing imported from pic4rl.

Subscribes ``scan`` (sensor_msgs/LaserScan), ``odom`` (nav_msgs/Odometry) and ``goal_pose``
(geometry_msgs/PoseStamped, as RViz's goal tool sends it), publishes ``cmd_vel``
(geometry_msgs/Twist) once per scan: go to the goal through the free gap nearest its bearing.
It answers every scan, so it runs against ``pic4rl-sim``'s lockstep clock as it is
(docs/your-agent.md, "A ROS 2 navigation stack"):

    python examples/ros_gap_follower_node.py                    # beside a running pic4rl-sim

The goal is in the ``world`` frame; the sim's odometry starts each episode at the robot's start
pose in that frame, so this node uses odometry as its pose (a real stack would use TF).
"""

from __future__ import annotations

import math

import rclpy
from geometry_msgs.msg import PoseStamped, Twist
from nav_msgs.msg import Odometry
from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy, qos_profile_sensor_data
from sensor_msgs.msg import LaserScan

MAX_SPEED = 0.5  # m/s
MAX_TURN = 1.5  # rad/s
CLEARANCE = 0.45  # m: a beam is free when its range exceeds this (robot radius + margin)
GOAL_TOLERANCE = 0.3  # m


class GapFollower(Node):
    def __init__(self) -> None:
        super().__init__("gap_follower")
        latched = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE,
                             durability=DurabilityPolicy.TRANSIENT_LOCAL)
        self.goal: tuple[float, float] | None = None
        self.pose: tuple[float, float, float] | None = None
        self.create_subscription(PoseStamped, "goal_pose", self.on_goal, latched)
        self.create_subscription(Odometry, "odom", self.on_odom, 10)
        self.create_subscription(LaserScan, "scan", self.on_scan, qos_profile_sensor_data)
        self.cmd = self.create_publisher(Twist, "cmd_vel", 10)

    def on_goal(self, msg: PoseStamped) -> None:
        self.goal = (msg.pose.position.x, msg.pose.position.y)

    def on_odom(self, msg: Odometry) -> None:
        q = msg.pose.pose.orientation
        yaw = math.atan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z))
        self.pose = (msg.pose.pose.position.x, msg.pose.pose.position.y, yaw)

    def on_scan(self, scan: LaserScan) -> None:
        twist = Twist()
        if self.goal is not None and self.pose is not None:
            x, y, yaw = self.pose
            dx, dy = self.goal[0] - x, self.goal[1] - y
            distance = math.hypot(dx, dy)
            bearing = math.atan2(math.sin(math.atan2(dy, dx) - yaw),
                                 math.cos(math.atan2(dy, dx) - yaw))
            if distance > GOAL_TOLERANCE:
                heading, ahead = self.steer(scan, bearing, distance)
                twist.angular.z = max(-MAX_TURN, min(MAX_TURN, 2.0 * heading))
                speed = min(MAX_SPEED, 0.5 * ahead, distance)
                twist.linear.x = max(0.0, speed * math.cos(heading))
        self.cmd.publish(twist)

    @staticmethod
    def steer(scan: LaserScan, bearing: float, distance: float) -> tuple[float, float]:
        """The free beam angle nearest the goal's bearing, and the free range straight ahead."""
        best, best_cost, ahead = bearing, math.inf, math.inf
        for i, r in enumerate(scan.ranges):
            angle = scan.angle_min + i * scan.angle_increment
            r = r if math.isfinite(r) else scan.range_max
            if abs(angle) < 0.35:
                ahead = min(ahead, r)
            if r > min(distance, CLEARANCE * 2.5) and abs(angle - bearing) < best_cost:
                best, best_cost = angle, abs(angle - bearing)
        return best, (ahead if math.isfinite(ahead) else scan.range_max) - CLEARANCE + 0.2


def main() -> None:
    rclpy.init()
    node = GapFollower()
    try:
        rclpy.spin(node)
    except (KeyboardInterrupt, rclpy.executors.ExternalShutdownException):
        pass
    finally:
        node.destroy_node()
        rclpy.try_shutdown()


if __name__ == "__main__":
    main()
