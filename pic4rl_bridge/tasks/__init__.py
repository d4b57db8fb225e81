"""Tasks: observation, reward and termination as pure functions of decoded sensor data."""

from __future__ import annotations

from typing import TYPE_CHECKING

from ..config import EnvConfig, SensorName, TaskName
from ..errors import ConfigError
from ..robot_info import RobotInfo
from .base import EpisodeContext, Judgement, Task

if TYPE_CHECKING:
    from pic4rl_sim.engine.world_spec import WorldSpec

__all__ = ["EpisodeContext", "Judgement", "Task", "make_task"]


def make_task(config: EnvConfig, robot: RobotInfo, world: WorldSpec | None = None) -> Task:
    """The task ``config.task`` names, observing through ``config.sensor`` (goToPose only:
    the vineyard task always sees depth, personMonitoring a LiDAR). ``world`` gives a
    vineyard's rows unless ``vineyard.centerline`` is set."""
    if config.task == TaskName.GO_TO_POSE.value:
        from .goto import GoToPoseDepth, GoToPoseLidar

        if config.sensor == SensorName.DEPTH.value:
            return GoToPoseDepth(config, robot)
        return GoToPoseLidar(config, robot)
    if config.task == TaskName.VINEYARD.value:
        from .vineyard import VineyardTask

        lanes = world.lanes if world is not None else ()
        if not lanes and not config.vineyard.centerline:
            where = "no world" if world is None else f"world {world.name!r} has no lanes"
            raise ConfigError(f"vineyard.centerline: [] is invalid for task 'vineyard' ({where});"
                              " expected the row's centre line x0, y0, x1, y1, ... or a "
                              "vineyard world")
        return VineyardTask(config, robot, lanes)
    if config.task == TaskName.PERSON_MONITORING.value:
        from .person import PersonMonitoringTask

        if not robot.omni:
            raise ConfigError(f"task: 'personMonitoring' needs an omnidirectional robot; "
                              f"robot {robot.name!r} is not omni (use an omni robot)")
        return PersonMonitoringTask(config, robot)
    raise ConfigError(f"task: {config.task!r} is invalid; expected one of "
                      f"{', '.join(t.value for t in TaskName)}")
