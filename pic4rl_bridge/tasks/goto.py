"""goToPose: reach a goal point without colliding (PIC4rl-gym's main task).

The reward is the paper's: a dense ``d_{t-1} - d_t`` toward the goal, +1000 on reaching it,
-150 on a collision, plus the original code's optional heading and per-step terms. The
policy sees the goal in polar form in the robot's frame and its last action, beside the LiDAR
sectors or the depth image. With ``goal_input: plan`` the polar target is instead the point
``plan_lookahead_m`` along the global plan (``topics.plan``) beyond the robot's projection on
it, as DRL local planners are deployed beside a map (Arena-rosnav's subgoals); the reward and
the outcome still judge the final goal. ``goal_input: explorer`` points along the plan of the
mapless explorer instead (``pic4rl_bridge.baselines.explorer_plan``, made from the episode's
own scans and poses and kept in its context: mapless, a classical global planner beside a
learned local one). With ``memory.enabled`` the observation is a Dict
that adds ``memory``, an egocentric crop of an occupancy grid of the episode's own scans
(``pic4rl_bridge.perception.occupancy``; the grid lives in the episode's context, so the task keeps
no state), to the LiDAR vector (``lidar``) or the depth image and goal. With ``sensors: [lidar,
depth]`` (or ``[lidar, sonar]``, ``[stereo]``, any of ``OBSERVED_TABLE``) the observation is a
Dict of each sensor's part (``pic4rl_bridge.perception.sensor_parts``) and ``goal``.
Every term is reported every step (0 when not triggered) so that ``info["reward_terms"]`` keeps
one shape through an episode.
"""

from __future__ import annotations

import collections
import math
from typing import Any

import gymnasium as gym
import numpy as np

from pic4rl_base.geometry import project
from pic4rl_metrics.contract import Outcome
from pic4rl_sim.engine.geometry import Twist2D, point_along

from ..baselines.explorer_plan import ExplorerPlan
from ..config import EnvConfig
from ..control.actions import planar_action_space, planar_command
from ..perception.collision import assess
from ..perception.observations import (MAX_TARGET_DISTANCE_M, NORMALIZED_GOAL_DISTANCE_M,
                                       clipped_action, target_polar)
from ..perception.occupancy import OccupancyGrid, sensed_scans
from ..perception.sensor_parts import observable
from ..readings.frame import SensorFrame
from ..readings.uwb_goal import UwbGoal
from ..robot_info import RobotInfo
from ..settings.observations import OBSERVED_TABLE
from ..settings.tasks import GoalInput, GoToPoseReward
from .base import EpisodeContext, Judgement, Task


class _GoToPose(Task):
    """What both goToPose variants share: actions, context, reward; not the observation."""

    name = "goToPose"

    def __init__(self, config: EnvConfig, robot: RobotInfo) -> None:
        super().__init__(config, robot)
        self.action_space = planar_action_space()
        self._plan = config.goal_input == GoalInput.PLAN.value
        self._explorer = config.goal_input == GoalInput.EXPLORER.value
        if self._plan:
            self.required = self.required | {"plan"}
        self._uwb = (UwbGoal.of(robot.specs) if config.goal_input == GoalInput.UWB.value
                     else None)
        if self._uwb is not None:
            self.required = self.required | set(self._uwb.readings)

    def command(self, action: np.ndarray) -> Twist2D:
        return planar_command(action, self.robot)

    def begin(self, frame: SensorFrame) -> EpisodeContext:
        if frame.goal is None:
            raise ValueError("goToPose: the episode's first frame has no goal")
        extra: dict[str, Any] = {"memory": OccupancyGrid()} if self.config.memory.enabled else {}
        if self._explorer:
            extra["explorer"] = ExplorerPlan(self.robot, self.config.explorer,
                                             sensors=self.config.observed,
                                             depth_rows=self.config.memory.depth_rows)
        if self.config.lidar.history > 1:
            extra["scan_history"] = collections.deque(maxlen=self.config.lidar.history)
        return EpisodeContext(start=frame.pose, goal=(float(frame.goal[0]), float(frame.goal[1])),
                              extra=extra)

    def _memory_space(self, space: gym.Space[Any]) -> gym.Space[Any]:
        """``space`` with the memory crop beside it (a Dict), or alone without memory."""
        if not self.config.memory.enabled:
            return space
        n = self.config.memory.size_px
        parts = dict(space.spaces) if isinstance(space, gym.spaces.Dict) else {"lidar": space}
        return gym.spaces.Dict({"memory": gym.spaces.Box(0, 255, (1, n, n), np.uint8), **parts})

    def _remember(self, obs: Any, frame: SensorFrame, context: EpisodeContext) -> Any:
        """``obs`` with the memory crop: the episode's grid (its context's) marked with the
        frame's returns (its observed sensors', ``sensed_scans``), then cropped round the
        pose, heading up. Marking is idempotent: observing a frame twice changes nothing."""
        m = self.config.memory
        if not m.enabled:
            return obs
        grid: OccupancyGrid = context.extra["memory"]
        for scan in sensed_scans(frame, self.robot, self.config.observed, m.depth_rows):
            grid.mark_scan(scan, frame.pose)
        crop = grid.crop(frame.pose, m.size_px, m.resolution_m)[None]
        return {"memory": crop, **(obs if isinstance(obs, dict) else {"lidar": obs})}

    def _goal_space(self) -> gym.spaces.Box:
        """Goal distance (m), goal angle (rad), last action: the vector beside the sensor;
        normalised, distance / ``NORMALIZED_GOAL_DISTANCE_M`` clipped to 1 and angle / pi.
        With ``goal_input: uwb`` the anchors' mask (1: range received) follows the angle."""
        far, turn = ((1.0, 1.0) if self.config.normalize_observations
                     else (MAX_TARGET_DISTANCE_M, math.pi))
        n = 0 if self._uwb is None else len(self._uwb.readings)
        return gym.spaces.Box(np.array([0.0, -turn, *[0.0] * n, -1.0, -1.0], np.float32),
                              np.array([far, turn, *[1.0] * n, 1.0, 1.0], np.float32),
                              dtype=np.float32)

    def _goal_vector(self, frame: SensorFrame, context: EpisodeContext,
                     last_action: np.ndarray) -> np.ndarray:
        if self._uwb is not None:  # the tag's ranges alone: no pose, no goal
            distance, angle, mask = self._uwb.estimate(self._uwb.ranges(frame.readings))
        else:
            distance, angle = target_polar(frame.pose, *self._target(frame, context))
            mask = np.zeros(0, np.float32)
        if self.config.normalize_observations:
            distance, angle = min(distance / NORMALIZED_GOAL_DISTANCE_M, 1.0), angle / math.pi
        else:
            distance = min(distance, MAX_TARGET_DISTANCE_M)
        return np.concatenate((np.array([distance, angle], np.float32), mask,
                               clipped_action(last_action, 2)))

    def _target(self, frame: SensorFrame, context: EpisodeContext) -> tuple[float, float]:
        """What the observation points at: the goal, or the look-ahead point of the plan (the
        topic's, or the explorer's of the episode's own scans)."""
        if self._explorer:
            plan, s = context.extra["explorer"].update(frame)
        elif not self._plan:
            return _goal(context)
        else:
            plan = frame.plan
            if plan is None or len(plan) == 0:
                raise ValueError(f"goToPose (goal_input plan): no plan on topic "
                                 f"{self.config.topics.plan!r} for this episode")
            s = project(plan, (frame.pose.x, frame.pose.y))[0] if len(plan) > 1 else 0.0
        x, y = point_along(plan, s + self.config.plan_lookahead_m)
        return float(x), float(y)

    def judge(self, previous: SensorFrame, frame: SensorFrame, context: EpisodeContext,
              collision_streak: int) -> Judgement:
        reward: GoToPoseReward = self.config.reward
        goal = _goal(context)
        d_prev, _ = target_polar(previous.pose, *goal)
        d, angle = target_polar(frame.pose, *goal)
        safety = assess(frame, self.robot, self.config, collision_streak)
        reached = d <= self.config.goal_tolerance_m
        crashed = safety.ended and not reached
        terms = {"distance": reward.distance * (d_prev - d),
                 "heading": reward.heading * (1.0 - 2.0 * math.sqrt(abs(angle) / math.pi)),
                 "step": reward.step,
                 "proximity": reward.proximity * max(
                     0.0, 1.0 - safety.min_obstacle_m / reward.proximity_range_m),
                 "goal": reward.goal if reached else 0.0,
                 "collision": reward.collision if crashed else 0.0}
        outcome = Outcome.GOAL if reached else Outcome.COLLISION if crashed else None
        return Judgement(terms=terms, outcome=outcome, collision=safety.collision,
                         collision_streak=safety.streak, warning=safety.warning,
                         min_obstacle_m=safety.min_obstacle_m, collision_rule=safety.rule)


def _goal(context: EpisodeContext) -> tuple[float, float]:
    if context.goal is None:
        raise ValueError("goToPose: the episode's context has no goal")
    return context.goal


def build(config: EnvConfig, robot: RobotInfo, world: object = None) -> _GoToPose:
    """goToPose through ``config.observed`` (its registry entry's ``build``), each a sensor of
    ``OBSERVED_TABLE`` the robot carries: one whose entry is ``flat_alone`` (the LiDAR) alone
    in one vector with the goal, else a Dict of each sensor's part and the goal."""
    entries = observable(config, robot)
    if len(entries) == 1 and entries[0].flat_alone:
        return GoToPoseLidar(config, robot)
    return GoToPoseSensors(config, robot)


class GoToPoseLidar(_GoToPose):
    """goToPose from LiDAR (the observed sensor ``flat_alone``): a flat vector [sectors (m),
    goal distance (m), goal angle (rad), last action (2)]; normalised, sectors /
    ``lidar.clip_m`` and the goal as above. With ``lidar.history`` N > 1 the sectors are the
    last N scans', newest first (a frame stack, the episode's context's: the memory study's
    alternative to the occupancy crop)."""

    required = frozenset({"goal", "scan"})

    def __init__(self, config: EnvConfig, robot: RobotInfo) -> None:
        super().__init__(config, robot)
        self._part = OBSERVED_TABLE[config.observed[0]].part
        self.required = self.required | self._part.readings(robot)
        sensor, goal = self._part.space(config, robot), self._goal_space()
        low, high = (np.concatenate((sensor.low, goal.low)),
                     np.concatenate((sensor.high, goal.high)))
        self.observation_space = self._memory_space(gym.spaces.Box(low, high, dtype=np.float32))

    def observe(self, frame: SensorFrame, context: EpisodeContext,
                last_action: np.ndarray) -> Any:
        vector = np.concatenate((self._part.value(self.config, self.robot, frame, context.extra),
                                 self._goal_vector(frame, context, last_action)))
        return self._remember(vector, frame, context)


class GoToPoseSensors(_GoToPose):
    """goToPose from a Dict of the observed sensors (``sensors: [lidar, depth]``, ``[depth]``,
    ``[lidar, sonar]``, ``[stereo]``, ...): a key per sensor, its part's value (``lidar``: the
    sectors, ``depth`` and ``stereo``: the image, ``sonar``: a range a cone), beside
    ``goal``: [distance (m), angle (rad), last action (2)]. A scan, when present, still serves
    the collision test."""

    required = frozenset({"goal"})

    def __init__(self, config: EnvConfig, robot: RobotInfo) -> None:
        super().__init__(config, robot)
        self._parts = {s: OBSERVED_TABLE[s].part for s in config.observed}
        for part in self._parts.values():
            self.required = self.required | part.readings(robot)
        self.observation_space = self._memory_space(gym.spaces.Dict(
            {**{s: part.space(config, robot) for s, part in self._parts.items()},
             "goal": self._goal_space()}))

    def observe(self, frame: SensorFrame, context: EpisodeContext,
                last_action: np.ndarray) -> dict[str, Any]:
        parts = {s: part.value(self.config, self.robot, frame, context.extra)
                 for s, part in self._parts.items()}
        return self._remember({**parts, "goal": self._goal_vector(frame, context, last_action)},
                              frame, context)
