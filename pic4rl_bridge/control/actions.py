"""The normalised action of the differential-drive tasks and the planar command it stands for.

An action in [-1, 1]² spans the robot's [min_linear, max_linear] (m/s) forward and
[-max_angular, max_angular] (rad/s) yaw rate: ``planar_command`` reads it (the goToPose and
vineyard tasks), ``normalized_action`` writes it (every baseline and expert that drives those
tasks), ``planar_action_space`` is its space.
"""

from __future__ import annotations

import gymnasium as gym
import numpy as np
from pic4rl_sim.engine.geometry import Twist2D

from ..perception.observations import clipped_action
from ..robot_info import RobotInfo


def planar_command(action: np.ndarray, robot: RobotInfo) -> Twist2D:
    """A 2-D normalized action as (forward, yaw rate): -1..1 spans the robot's
    [min_linear, max_linear] (m/s) and [-max_angular, max_angular] (rad/s)."""
    a = clipped_action(action, 2).astype(np.float64)
    span = robot.max_linear_m_s - robot.min_linear_m_s
    v = robot.min_linear_m_s + 0.5 * (a[0] + 1.0) * span
    return Twist2D(vx=float(v), vy=0.0, wz=float(a[1] * robot.max_angular_rad_s))


def normalized_action(robot: RobotInfo, v: float, w: float) -> np.ndarray:
    """The 2-D normalized action of (v, ω) (m/s, rad/s): ``planar_command``'s inverse, clipped
    to [-1, 1]."""
    span = robot.max_linear_m_s - robot.min_linear_m_s
    a_v = 2.0 * (v - robot.min_linear_m_s) / span - 1.0 if span > 0 else 0.0
    a_w = w / robot.max_angular_rad_s if robot.max_angular_rad_s > 0 else 0.0
    return np.clip(np.array([a_v, a_w], dtype=np.float32), -1.0, 1.0)


def planar_action_space() -> gym.spaces.Box:
    """The 2-D normalized action space of the differential-drive tasks."""
    return gym.spaces.Box(-1.0, 1.0, (2,), np.float32)
