"""vineyard: follow a row between crops from the depth image alone (position-agnostic).

The policy never sees its pose (a row's GNSS-free navigation): its observation is the depth
image only, a ``Box`` so SB3's ``CnnPolicy`` applies. The reward, computed from the pose the
env knows, pays the advance along the row's centre line and penalizes the lateral offset from
it; the episode succeeds at the row's end, reached in the row (within
``vineyard.max_offset_m`` of its centre line: a robot that went through a gap and down the next
lane has not followed its row). The centre line is the world's lane nearest the
start, oriented from the start, or ``vineyard.centerline`` when the config gives one.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from pic4rl_base.geometry import project
from pic4rl_metrics.contract import Outcome
from pic4rl_sim.engine.geometry import Twist2D, polyline_length

from ..config import EnvConfig
from ..control.actions import planar_action_space, planar_command
from ..errors import ConfigError
from ..perception.collision import assess
from ..perception.observations import depth_observation, depth_space
from ..perception.rows import centerlines, row_centerline
from ..readings.frame import SensorFrame
from ..robot_info import RobotInfo
from ..settings.tasks import VineyardReward
from .base import EpisodeContext, Judgement, Task

if TYPE_CHECKING:
    from pic4rl_sim.engine.worlds.spec import WorldSpec


class VineyardTask(Task):
    """Row following from depth: 2-D actions as goToPose, observation = the depth image."""

    name = "vineyard"
    required = frozenset({"depth"})

    def __init__(self, config: EnvConfig, robot: RobotInfo,
                 lanes: Sequence[Sequence[Sequence[float]]]) -> None:
        super().__init__(config, robot)
        self.lanes = centerlines(config, lanes)
        self.action_space = planar_action_space()
        self.observation_space = depth_space(config.depth)

    def command(self, action: np.ndarray) -> Twist2D:
        return planar_command(action, self.robot)

    def begin(self, frame: SensorFrame) -> EpisodeContext:
        lane = row_centerline(self.lanes, (frame.pose.x, frame.pose.y))
        return EpisodeContext(start=frame.pose, goal=(float(lane[-1, 0]), float(lane[-1, 1])),
                              centerline=lane)

    def observe(self, frame: SensorFrame, context: EpisodeContext,
                last_action: np.ndarray) -> np.ndarray:
        if frame.depth is None:
            raise ValueError("vineyard: the frame has no depth image")
        c = self.config.depth
        return depth_observation(frame.depth, c.obs_width, c.obs_height, c.clip_m, c.encoding)

    def judge(self, previous: SensorFrame, frame: SensorFrame, context: EpisodeContext,
              collision_streak: int) -> Judgement:
        line = _centerline(context)
        reward: VineyardReward = self.config.reward
        s_prev, _ = project(line, (previous.pose.x, previous.pose.y))
        s, offset = project(line, (frame.pose.x, frame.pose.y))
        safety = assess(frame, self.robot, self.config, collision_streak)
        row = self.config.vineyard
        done = s >= polyline_length(line) - row.end_tolerance_m and abs(offset) <= row.max_offset_m
        crashed = safety.ended and not done
        terms = {"progress": reward.progress * (s - s_prev),
                 "centering": -reward.centering * abs(offset),
                 "row_end": reward.row_end if done else 0.0,
                 "collision": reward.collision if crashed else 0.0,
                 "step": reward.step}
        outcome = Outcome.GOAL if done else Outcome.COLLISION if crashed else None
        return Judgement(terms=terms, outcome=outcome, collision=safety.collision,
                         collision_streak=safety.streak, warning=safety.warning,
                         min_obstacle_m=safety.min_obstacle_m, collision_rule=safety.rule)

    def facts(self, context: EpisodeContext) -> dict[str, Any]:
        return {"row_centerline": _centerline(context).tolist()}


def build(config: EnvConfig, robot: RobotInfo, world: WorldSpec | None) -> VineyardTask:
    """The vineyard task on ``world``'s lanes, unless ``vineyard.centerline`` is set (its
    registry entry's ``build``)."""
    lanes = world.lanes if world is not None else ()
    if not lanes and not config.vineyard.centerline:
        where = "no world" if world is None else f"world {world.name!r} has no lanes"
        raise ConfigError(f"vineyard.centerline: [] is invalid for task 'vineyard' ({where}); "
                          "expected the row's centre line x0, y0, x1, y1, ... or a vineyard "
                          "world")
    return VineyardTask(config, robot, lanes)


def _centerline(context: EpisodeContext) -> np.ndarray:
    if context.centerline is None:
        raise ValueError("vineyard: the episode's context has no centre line")
    return context.centerline
