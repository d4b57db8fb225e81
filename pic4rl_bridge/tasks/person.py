"""personMonitoring: an omnidirectional robot keeps a walking person in view, at a distance.

An omni base can strafe while turning, so the action is 3-D (forward, left, yaw rate). The
reward pays facing the person (``cos`` of the bearing: 1 ahead, -1 behind) and penalizes the
error from the desired distance. There is no goal: an episode ends on a collision or on the
env's time limit.
"""

from __future__ import annotations

import math

import gymnasium as gym
import numpy as np

from pic4rl_metrics.contract import Outcome
from pic4rl_sim.engine.geometry import Twist2D

from ..config import EnvConfig
from ..frame import SensorFrame
from ..robot_info import RobotInfo
from .base import EpisodeContext, Judgement, Task
from .collision import assess
from .observations import MAX_TARGET_DISTANCE_M, clipped_action, lidar_sectors, target_polar


class PersonMonitoringTask(Task):
    """Observation: [LiDAR sectors (m), person distance (m), person bearing (rad, left
    positive), last action (3)]; action: forward, left, yaw rate, each in [-1, 1]."""

    name = "personMonitoring"
    required = frozenset({"scan", "person"})

    def __init__(self, config: EnvConfig, robot: RobotInfo) -> None:
        super().__init__(config, robot)
        self.action_space = gym.spaces.Box(-1.0, 1.0, (3,), np.float32)
        beams = config.lidar.beams
        low = np.concatenate((np.zeros(beams), [0.0, -math.pi, -1.0, -1.0, -1.0]))
        high = np.concatenate((np.full(beams, config.lidar.max_range_m),
                               [MAX_TARGET_DISTANCE_M, math.pi, 1.0, 1.0, 1.0]))
        self.observation_space = gym.spaces.Box(low.astype(np.float32), high.astype(np.float32),
                                                dtype=np.float32)

    def command(self, action: np.ndarray) -> Twist2D:
        a = clipped_action(action, 3).astype(np.float64)
        r = self.robot
        return Twist2D(vx=float(a[0] * r.max_linear_m_s), vy=float(a[1] * r.max_lateral_m_s),
                       wz=float(a[2] * r.max_angular_rad_s))

    def begin(self, frame: SensorFrame) -> EpisodeContext:
        return EpisodeContext(start=frame.pose)

    def observe(self, frame: SensorFrame, context: EpisodeContext,
                last_action: np.ndarray) -> np.ndarray:
        if frame.scan is None:
            raise ValueError("personMonitoring: the frame has no scan")
        lidar = self.config.lidar
        sectors = lidar_sectors(frame.scan.ranges, lidar.beams, lidar.max_range_m)
        distance, bearing = _person(frame)
        return np.concatenate((sectors, np.array([distance, bearing], np.float32),
                               clipped_action(last_action, 3)))

    def judge(self, previous: SensorFrame, frame: SensorFrame, context: EpisodeContext,
              collision_streak: int) -> Judgement:
        reward = self.config.reward
        distance, bearing = _person(frame)
        safety = assess(frame, self.robot, self.config, collision_streak)
        error = abs(distance - self.config.person.distance_m)
        terms = {"facing": reward.facing * math.cos(bearing),
                 "person_distance": -reward.person_distance * error,
                 "collision": reward.collision if safety.ended else 0.0,
                 "step": reward.step}
        return Judgement(terms=terms, outcome=Outcome.COLLISION if safety.ended else None,
                         collision=safety.collision, collision_streak=safety.streak,
                         warning=safety.warning, min_obstacle_m=safety.min_obstacle_m)


def _person(frame: SensorFrame) -> tuple[float, float]:
    """Distance (m) and bearing (rad) of the person from the robot."""
    if frame.person is None:
        raise ValueError("personMonitoring: the frame has no person pose")
    distance, bearing = target_polar(frame.pose, frame.person.x, frame.person.y)
    return min(distance, MAX_TARGET_DISTANCE_M), bearing
