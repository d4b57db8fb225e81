"""A gap follower as a pic4rl policy plugin: pure numpy, the public protocol only.

    pic4rl-test --agent examples/gap_follower.py:GapFollower --episodes 5 \\
        --ros-args --params-file config/env_goto_lidar.yaml

Each step it measures, along every beam's direction, how far a body as wide as the robot
(plus 0.05 m) is free; among the directions free for ``clear_m`` (or up to the goal) it turns
toward the one closest to the goal, and drives at ``speed_gain`` × the free distance ahead,
slower the more it must turn.
"""

from __future__ import annotations

import math

import numpy as np

from pic4rl_bridge.control.plugin import Policy, RobotInfo, SensorFrame, TaskInfo


class GapFollower(Policy):
    observes = "frame"  # act() gets the SensorFrame: scan with its angles, pose, goal
    acts = "velocity"  # act() returns (v m/s, ω rad/s)
    name = "gap_follower"  # its row in the tables

    def __init__(self, clear_m: float = 1.0, turn_gain: float = 2.0,
                 speed_gain: float = 1.0) -> None:
        self.clear_m, self.turn_gain, self.speed_gain = clear_m, turn_gain, speed_gain

    def reset(self, robot: RobotInfo, task: TaskInfo) -> None:
        self.robot = robot
        self.radius_m = robot.footprint.bounding_radius_m + 0.05

    def act(self, frame: SensorFrame) -> tuple[float, float]:
        r, pose, scan = self.robot, frame.pose, frame.scan
        gx, gy = frame.goal[0] - pose.x, frame.goal[1] - pose.y
        goal_bearing = math.atan2(math.sin(math.atan2(gy, gx) - pose.yaw),
                                  math.cos(math.atan2(gy, gx) - pose.yaw))
        ranges = np.nan_to_num(np.asarray(scan.ranges, dtype=float), nan=0.0,
                               posinf=scan.range_max_m, neginf=0.0)
        angles = np.angle(np.exp(1j * scan.base_angles()))  # wrapped to (-π, π]
        # Free distance along each beam's direction: how far a body of half-width radius_m
        # could go before a scan point comes within radius_m of its path.
        d = angles[None, :] - angles[:, None]
        along, lateral = ranges * np.cos(d), ranges * np.abs(np.sin(d))
        free = np.where((along > 0) & (lateral < self.radius_m), along, np.inf).min(axis=1)
        free = np.minimum(free, scan.range_max_m)
        reach = min(self.clear_m, math.hypot(gx, gy))
        open_ = free > reach
        if not open_.any():  # no gap reaches clear_m: head for the most open direction
            open_ = free >= free.max()
        heading = float(angles[open_][np.argmin(np.abs(angles[open_] - goal_bearing))])
        ahead = float(free[np.argmin(np.abs(angles - heading))])
        w = float(np.clip(self.turn_gain * heading, -r.max_angular_rad_s, r.max_angular_rad_s))
        v = self.speed_gain * (ahead - self.radius_m) * max(0.0, math.cos(heading)) ** 2
        v = float(np.clip(v, 0.0, r.max_linear_m_s))
        return v, w
