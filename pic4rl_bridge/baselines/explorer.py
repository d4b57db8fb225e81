"""The mapless explorer: a classical navigator that knows no map, only what it has seen.

It reads what a mapless agent reads, the scan (or the depth image's pseudo-scan) and the pose
topic, never the world, so it runs in process, through the sim node over ROS 2 and on a real
robot. Its plan is ``pic4rl_bridge.baselines.explorer_plan``'s (the shortest path on an
occupancy grid of its own scans, unknown space free, kept until something newly seen blocks
it), which a goToPose observation with ``goal_input: explorer`` points along too; it follows
that plan with the privileged planner's pursuit law (``pic4rl_bridge.control.pursuit``) within
its own speed limit (``max_linear_m_s``). In a depth env (``for_env``: the baseline and a depth
student's expert) it marks the depth image's pseudo-scan, as the student's memory does, even
where a scan is there.
"""

from __future__ import annotations

import numpy as np

from ..config import EnvConfig
from .explorer_plan import ExplorerPlan
from ..perception.occupancy import OccupancyGrid
from ..robot_info import RobotInfo
from ..control.actions import normalized_action
from ..readings.frame import SensorFrame
from ..settings.baselines import ExplorerConfig
from ..control.pursuit import pursuit_command


class ExplorerController:
    """The mapless explorer for goToPose (see the module's docstring); ``observe`` marks a
    frame's returns (``command`` and ``action`` do it too), ``reset`` forgets the grid."""

    def __init__(self, robot: RobotInfo, config: ExplorerConfig | None = None, *,
                 lookahead_m: float = 0.4, turn_in_place_rad: float = 0.8,
                 sensors: tuple[str, ...] = (), depth_rows: int = 0) -> None:
        self.robot, self.config = robot, config or ExplorerConfig()
        self.plan = ExplorerPlan(robot, self.config, sensors=sensors, depth_rows=depth_rows)
        self.lookahead_m, self.turn_in_place_rad = lookahead_m, turn_in_place_rad
        cap = self.config.max_linear_m_s
        self.max_linear_m_s = min(cap, robot.max_linear_m_s) if cap > 0 else robot.max_linear_m_s

    @classmethod
    def for_env(cls, robot: RobotInfo, env: EnvConfig,
                config: ExplorerConfig | None = None) -> ExplorerController:
        """The explorer that sees what ``env``'s agent sees (its observed sensors): in a depth
        env, the depth image's pseudo-scan (its LiDAR, if any, serves only the collision test),
        as a depth student's memory and plan do; with ``sensors: [lidar, depth]``, both fused
        in one grid; else the scan."""
        return cls(robot, config, sensors=env.observed, depth_rows=env.memory.depth_rows)

    def reset(self) -> None:
        """Forget the grid and the plan (a new episode)."""
        self.plan.reset()

    @property
    def grid(self) -> OccupancyGrid:
        """The occupancy grid of the scans seen this episode."""
        return self.plan.grid

    @property
    def plans(self) -> int:
        """Paths planned since the controller was made."""
        return self.plan.plans

    @property
    def path(self) -> np.ndarray | None:
        """The plan being followed (k × 2, m), or ``None`` before the first frame."""
        return self.plan.path

    def observe(self, frame: SensorFrame) -> np.ndarray:
        """Mark ``frame``'s returns (once per frame); the cells new to the grid (k, 2)."""
        return self.plan.observe(frame)

    def command(self, frame: SensorFrame) -> tuple[float, float]:
        """(v, ω) (m/s, rad/s) for ``frame`` (see the module's docstring)."""
        if frame.goal is None:
            raise ValueError("ExplorerController: the frame has no goal")
        path, s = self.plan.update(frame)
        return pursuit_command(self.robot, frame.pose, path, s, self.plan.visible,
                               lookahead_m=self.lookahead_m,
                               turn_in_place_rad=self.turn_in_place_rad,
                               max_linear_m_s=self.max_linear_m_s)

    def action(self, frame: SensorFrame) -> np.ndarray:
        """The goToPose normalised action of ``command``."""
        return normalized_action(self.robot, *self.command(frame))
