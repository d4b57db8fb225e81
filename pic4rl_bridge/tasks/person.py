"""personMonitoring: an omnidirectional robot keeps a walking person in view, at a distance.

An omni base can strafe while turning. With ``person.control: end_to_end`` the action is 3-D
(forward, left, yaw rate); with ``hybrid`` it is the yaw rate alone, and DWA
(``pic4rl_bridge.baselines.follow.PersonFollower``) adds the translation that follows the person and
avoids obstacles (Eirale et al. 2022). The reward pays facing the person (``cos`` of the
bearing: 1 ahead, -1 behind) and penalizes the error from the desired distance. There is no
goal: an episode ends on a collision or on the env's time limit.
"""

from __future__ import annotations

import math
from typing import Any

import gymnasium as gym
import numpy as np

from pic4rl_metrics.contract import Outcome
from pic4rl_sim.engine.geometry import Twist2D

from ..config import EnvConfig
from ..errors import ConfigError
from ..perception.collision import assess
from ..perception.observations import (MAX_TARGET_DISTANCE_M, clipped_action, lidar_sectors,
                                       target_polar)
from ..robot_info import RobotInfo
from ..readings.frame import SensorFrame
from .base import EpisodeContext, Judgement, Task
from ..settings.tasks import PersonControl, PersonReward


class PersonMonitoringTask(Task):
    """Observation: [LiDAR sectors (m), person distance (m), person bearing (rad, left
    positive), the person's walking direction seen from the robot's heading (rad), last
    action]; action, each in [-1, 1]: forward, left, yaw rate (end to end) or
    the yaw rate alone (hybrid)."""

    name = "personMonitoring"
    required = frozenset({"scan", "person"})

    def __init__(self, config: EnvConfig, robot: RobotInfo) -> None:
        super().__init__(config, robot)
        self.follower = None
        if config.person.control == PersonControl.HYBRID.value:
            from ..baselines.follow import PersonFollower

            self.follower = PersonFollower(robot, config.person.dwa,
                                           distance_m=config.person.distance_m,
                                           collision_tolerance_m=config.collision_tolerance_m)
        size = 1 if self.follower is not None else 3
        self.action_space = gym.spaces.Box(-1.0, 1.0, (size,), np.float32)
        beams = config.lidar.sectors
        low = np.concatenate((np.zeros(beams), [0.0, -math.pi, -math.pi], -np.ones(size)))
        high = np.concatenate((np.full(beams, config.lidar.clip_m),
                               [MAX_TARGET_DISTANCE_M, math.pi, math.pi], np.ones(size)))
        self.observation_space = gym.spaces.Box(low.astype(np.float32), high.astype(np.float32),
                                                dtype=np.float32)

    def command(self, action: np.ndarray) -> Twist2D:
        """The agent's share of the command: all of it end to end; hybrid, ω alone
        (``command_at`` adds DWA's translation)."""
        r = self.robot
        if self.follower is not None:
            return Twist2D(wz=float(clipped_action(action, 1)[0]) * r.max_angular_rad_s)
        a = clipped_action(action, 3).astype(np.float64)
        return Twist2D(vx=float(a[0] * r.max_linear_m_s), vy=float(a[1] * r.max_lateral_m_s),
                       wz=float(a[2] * r.max_angular_rad_s))

    def command_at(self, action: np.ndarray, frame: SensorFrame) -> Twist2D:
        own = self.command(action)
        if self.follower is None:
            return own
        vx, vy = self.follower.translation(frame, own.wz)
        return Twist2D(vx=vx, vy=vy, wz=own.wz)

    def begin(self, frame: SensorFrame) -> EpisodeContext:
        return EpisodeContext(start=frame.pose)

    def observe(self, frame: SensorFrame, context: EpisodeContext,
                last_action: np.ndarray) -> np.ndarray:
        if frame.scan is None:
            raise ValueError("personMonitoring: the frame has no scan")
        lidar = self.config.lidar
        sectors = lidar_sectors(frame.scan, lidar)
        distance, bearing = _person(frame)
        assert frame.person is not None  # _person checked it
        walking = math.remainder(frame.person.yaw - frame.pose.yaw, math.tau)
        return np.concatenate((sectors, np.array([distance, bearing, walking], np.float32),
                               clipped_action(last_action, self.action_space.shape[0])))

    def judge(self, previous: SensorFrame, frame: SensorFrame, context: EpisodeContext,
              collision_streak: int) -> Judgement:
        reward: PersonReward = self.config.reward
        distance, bearing = _person(frame)
        safety = assess(frame, self.robot, self.config, collision_streak)
        error = abs(distance - self.config.person.distance_m)
        terms = {"facing": reward.facing * math.cos(bearing),
                 "bearing": -reward.bearing * abs(bearing),
                 "person_distance": -reward.person_distance * error,
                 "collision": reward.collision if safety.ended else 0.0,
                 "step": reward.step}
        return Judgement(terms=terms, outcome=Outcome.COLLISION if safety.ended else None,
                         collision=safety.collision, collision_streak=safety.streak,
                         warning=safety.warning, min_obstacle_m=safety.min_obstacle_m,
                         collision_rule=safety.rule)

    def facts(self, context: EpisodeContext) -> dict[str, Any]:
        """The desired distance and the camera's field of view, which the person metrics
        judge by, and who gave which part of the command."""
        return {"person_distance_m": self.config.person.distance_m,
                "camera_fov_rad": self.robot.depth_hfov_rad,
                "person_control": self.config.person.control}


def build(config: EnvConfig, robot: RobotInfo, world: object = None) -> PersonMonitoringTask:
    """personMonitoring on an omnidirectional robot (its registry entry's ``build``)."""
    if not robot.omni:
        raise ConfigError(f"task: 'personMonitoring' needs an omnidirectional robot; "
                          f"robot {robot.name!r} is not omni (use an omni robot)")
    return PersonMonitoringTask(config, robot)


def _person(frame: SensorFrame) -> tuple[float, float]:
    """Distance (m) and bearing (rad) of the person from the robot."""
    if frame.person is None:
        raise ValueError("personMonitoring: the frame has no person pose")
    distance, bearing = target_polar(frame.pose, frame.person.x, frame.person.y)
    return min(distance, MAX_TARGET_DISTANCE_M), bearing
