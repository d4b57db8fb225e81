"""What every task is: spaces, the action → command map, and pure functions of sensor frames.

A task keeps no state between calls: the env passes the episode's context (from ``begin``),
the previous and current frames and the collision streak, and gets back named reward terms
(already scaled) and the outcome. So the same frames give the same rewards, whichever
transport made them, and tasks are tested without a simulator.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, ClassVar

import gymnasium as gym
import numpy as np

from pic4rl_base.goal import Goal
from pic4rl_metrics.contract import CollisionRule, Outcome
from pic4rl_base.geometry import Pose2D
from pic4rl_sim.engine.geometry import Twist2D

from ..config import EnvConfig
from ..readings.frame import SensorFrame
from ..robot_info import RobotInfo
from ..settings.tasks import task_spec

if TYPE_CHECKING:
    from pic4rl_sim.engine.worlds.spec import WorldSpec


@dataclass(frozen=True)
class EpisodeContext:
    """Facts of the episode fixed at its start: the start pose, the goal (if any) and, for
    the vineyard, the row's centre line (n × 2, oriented from the start)."""

    start: Pose2D
    goal: Goal | None = None
    centerline: np.ndarray | None = None
    extra: Mapping[str, Any] = field(default_factory=dict)


@dataclass(frozen=True)
class Judgement:
    """One step judged: named reward terms (scaled), the outcome that ends the episode
    (``GOAL`` or ``COLLISION``; ``None`` goes on), whether the footprint plus
    ``collision_tolerance_m`` is violated now, the streak of such steps, whether an obstacle is
    within ``warning_tolerance_m``, the nearest obstacle to the footprint (m, ``inf`` if
    none seen), and which rule made a ``COLLISION`` (``perception.collision.assess``)."""

    terms: Mapping[str, float]
    outcome: Outcome | None
    collision: bool
    collision_streak: int
    warning: bool
    min_obstacle_m: float
    collision_rule: CollisionRule | None = None

    @property
    def reward(self) -> float:
        return float(sum(self.terms.values()))

    def info(self, step: int, outcome: Outcome | None) -> dict[str, Any]:
        """The env's ``info`` for this step (``step`` of the episode), with the episode's
        ``outcome`` once it ends; ``is_success`` is how SB3 logs the success rate."""
        info: dict[str, Any] = {
            "reward_terms": dict(self.terms), "collision": self.collision,
            "warning": self.warning, "min_obstacle_m": self.min_obstacle_m, "step": step,
        }
        if outcome is not None:
            info["outcome"] = outcome.value
            info["is_success"] = outcome is Outcome.GOAL
        if outcome is Outcome.COLLISION and self.collision_rule is not None:
            info["collision_rule"] = self.collision_rule.value
        return info


class Task(ABC):
    """A navigation task over a robot (and, in simulation, a known world)."""

    name: ClassVar[str]
    #: Which ``SensorFrame`` fields must be present: some of "scan", "depth", "person", "goal".
    required: frozenset[str]
    observation_space: gym.Space[Any]
    #: Normalized to [-1, 1] per axis (SB3's advice); ``command`` maps it to velocities.
    action_space: gym.spaces.Box

    def __init__(self, config: EnvConfig, robot: RobotInfo) -> None:
        self.config = config
        self.robot = robot

    @abstractmethod
    def command(self, action: np.ndarray) -> Twist2D:
        """The velocity command (body frame) for a normalized ``action`` (clipped to [-1, 1])."""

    def command_at(self, action: np.ndarray, frame: SensorFrame) -> Twist2D:
        """The command the env sends for ``action`` at ``frame`` (the frame before the step):
        ``command``, unless a planner of the task's own reads the frame for its share."""
        return self.command(action)

    @abstractmethod
    def begin(self, frame: SensorFrame) -> EpisodeContext:
        """The episode's context from its first frame."""

    @abstractmethod
    def observe(self, frame: SensorFrame, context: EpisodeContext,
                last_action: np.ndarray) -> Any:
        """The observation (an element of ``observation_space``)."""

    @abstractmethod
    def judge(self, previous: SensorFrame, frame: SensorFrame, context: EpisodeContext,
              collision_streak: int) -> Judgement:
        """Reward terms and outcome of the step from ``previous`` to ``frame``;
        ``collision_streak`` counts the consecutive collision steps before this one."""

    def facts(self, context: EpisodeContext) -> dict[str, Any]:
        """Bag facts this task adds (e.g. ``row_centerline``)."""
        return {}


def make_task(config: EnvConfig, robot: RobotInfo, world: WorldSpec | None = None) -> Task:
    """The task ``config.task`` names (``pic4rl_bridge.settings.tasks.TASKS``), built by its
    entry's ``build``; ``world``, the simulated world of the episode, is passed on only to a
    task that reads it (``uses_world`` or ``judges_world``)."""
    spec = task_spec(config.task)
    reads = spec.uses_world or spec.judges_world
    task: Task = spec.make(config, robot, world if reads else None)
    return task
