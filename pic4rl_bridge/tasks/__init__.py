"""Tasks: observation, reward and termination as pure functions of decoded sensor data."""

from __future__ import annotations

from typing import TYPE_CHECKING

from ..config import EnvConfig
from ..robot_info import RobotInfo
from ..task_registry import task_spec
from .base import EpisodeContext, Judgement, Task

if TYPE_CHECKING:
    from pic4rl_sim.engine.world_spec import WorldSpec

__all__ = ["EpisodeContext", "Judgement", "Task", "make_task"]


def make_task(config: EnvConfig, robot: RobotInfo, world: WorldSpec | None = None) -> Task:
    """The task ``config.task`` names (``pic4rl_bridge.task_registry.TASKS``), built by its
    entry's ``build``; ``world``, when the task reads it (``uses_world``), is the simulated
    world."""
    task: Task = task_spec(config.task).make(config, robot, world)
    return task
