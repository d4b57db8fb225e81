"""A user's task, its code: escape (``escape_entry`` is its table entry). The policy sees how
far it has come (in radii), the nearest obstacle and its last action; it is paid for each
metre gained away from the start, and the episode ends at 1 m (a goal) or on a collision."""

import math

import gymnasium as gym
import numpy as np

from pic4rl_bridge.control.actions import planar_action_space, planar_command
from pic4rl_bridge.perception.collision import assess, obstacle_distance
from pic4rl_bridge.tasks.base import EpisodeContext, Judgement, Task
from pic4rl_metrics.contract import Outcome

RADIUS_M = 1.0
SEEN_M = 5.0  # the nearest obstacle is clipped here


def _away(frame, context):
    return math.hypot(frame.pose.x - context.start.x, frame.pose.y - context.start.y)


class Escape(Task):
    name = "escape"
    required = frozenset({"scan"})

    def __init__(self, config, robot):
        super().__init__(config, robot)
        self.action_space = planar_action_space()
        self.observation_space = gym.spaces.Box(-1.0, math.inf, (4,), np.float32)

    def command(self, action):
        return planar_command(action, self.robot)

    def begin(self, frame):
        return EpisodeContext(start=frame.pose)

    def observe(self, frame, context, last_action):
        nearest = min(obstacle_distance(frame, self.robot), SEEN_M) / SEEN_M
        return np.array([_away(frame, context) / RADIUS_M, nearest, *last_action[:2]],
                        np.float32)

    def judge(self, previous, frame, context, collision_streak):
        reward = self.config.reward
        safety = assess(frame, self.robot, self.config, collision_streak)
        gained = _away(frame, context) - _away(previous, context)
        done = _away(frame, context) >= RADIUS_M
        crashed = safety.ended and not done
        terms = {"away": reward.away * gained, "escaped": reward.escaped if done else 0.0,
                 "collision": reward.collision if crashed else 0.0, "step": reward.step}
        outcome = Outcome.GOAL if done else Outcome.COLLISION if crashed else None
        return Judgement(terms=terms, outcome=outcome, collision=safety.collision,
                         collision_streak=safety.streak, warning=safety.warning,
                         min_obstacle_m=safety.min_obstacle_m)


def build(config, robot, world):
    """The task (its table entry's ``build``)."""
    return Escape(config, robot)
