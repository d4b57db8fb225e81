"""A classical reference for goToPose: a proportional go-to-goal controller.

It turns toward the goal and drives when facing it, with no obstacle avoidance: the simplest
baseline a learned policy should beat among obstacles, and a check that the env, transport and
recorder work end to end (it reaches any goal in open space).
"""

from __future__ import annotations

import math

import numpy as np

from .frame import SensorFrame
from .robot import RobotInfo


class GoToGoalController:
    """Normalized goToPose actions ([-1, 1]²) from the robot's pose and the goal:
    ω = ``turn_gain`` × bearing, v = ``speed_gain`` × distance × cos⁴(bearing), clipped to the
    robot's ranges (m/s, rad/s)."""

    def __init__(self, robot: RobotInfo, *, turn_gain: float = 2.0,
                 speed_gain: float = 1.0) -> None:
        self.robot = robot
        self.turn_gain = turn_gain
        self.speed_gain = speed_gain

    def action(self, frame: SensorFrame) -> np.ndarray:
        if frame.goal is None:
            raise ValueError("GoToGoalController: the frame has no goal")
        r = self.robot
        dx, dy = frame.goal[0] - frame.pose.x, frame.goal[1] - frame.pose.y
        bearing = math.atan2(math.sin(math.atan2(dy, dx) - frame.pose.yaw),
                             math.cos(math.atan2(dy, dx) - frame.pose.yaw))
        w = float(np.clip(self.turn_gain * bearing, -r.max_angular_rad_s, r.max_angular_rad_s))
        v = self.speed_gain * math.hypot(dx, dy) * max(0.0, math.cos(bearing)) ** 4
        v = float(np.clip(v, r.min_linear_m_s, r.max_linear_m_s))
        span = r.max_linear_m_s - r.min_linear_m_s
        a_v = 2.0 * (v - r.min_linear_m_s) / span - 1.0 if span > 0 else 0.0
        a_w = w / r.max_angular_rad_s if r.max_angular_rad_s > 0 else 0.0
        return np.array([a_v, a_w], dtype=np.float32)
