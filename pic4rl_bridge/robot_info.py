"""What the tasks and the recorder know of the robot and its world, from the config alone.

The sim section of the config (``sim_params``) names the robot, its sensors and the world, so
the env knows the footprint, the LiDAR's mount and a vineyard's rows without asking the
simulator; a real robot's config names the robot in ``robot`` instead (a built-in name or a
robot YAML), and has no world.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property
from typing import TYPE_CHECKING

from pic4rl_sim.engine.geometry import Footprint, Pose2D
from pic4rl_sim.engine.robot_specs import Drive, RobotSpec, load_robot
from pic4rl_sim.errors import SimError

from .config import EnvConfig
from .errors import ConfigError

if TYPE_CHECKING:  # pic4rl_sim.params imports mujoco: only when a sim section is used
    from pic4rl_sim.params import SimConfig
    from pic4rl_sim.engine.world_spec import WorldSpec


@dataclass(frozen=True)
class RobotInfo:
    """The robot as the tasks see it: footprint, drive, the commanded velocity ranges (the
    env's limits within the robot's), sensor mounts in the base frame, control period, and
    the robot's acceleration limits (m/s², rad/s²; ``inf`` when unknown)."""

    name: str
    footprint: Footprint
    omni: bool
    min_linear_m_s: float
    max_linear_m_s: float
    max_angular_rad_s: float
    max_lateral_m_s: float
    control_dt_s: float
    lidar_mount: Pose2D | None = None
    depth_mount: Pose2D | None = None
    depth_hfov_rad: float = math.radians(87.0)
    max_linear_accel_m_s2: float = math.inf  # the robot's (classical planners' window)
    max_angular_accel_rad_s2: float = math.inf


def _limit(wanted: float, robot_limit: float) -> float:
    return robot_limit if wanted <= 0 else min(wanted, robot_limit)


class Scenario:
    """The robot and world an env runs: from ``config.sim_params`` when present, else from
    ``config.robot`` (a real robot: no world)."""

    def __init__(self, config: EnvConfig) -> None:
        self.config = config
        self.sim: SimConfig | None = None
        if config.sim_params or config.transport == "inprocess":
            from pic4rl_sim.params import build_config, parameter_table, resolve

            try:
                robot = load_robot(config.robot or config.sim_params.get("robot", "jackal"))
                values = resolve(parameter_table(robot), config.sim_params, where="")
                if config.robot:
                    values["robot"] = config.robot
                self.sim = build_config(values)
            except (SimError, ConfigError) as err:
                raise ConfigError(f"sim parameters: {err}") from err
            self.spec: RobotSpec = self.sim.robot
        else:
            if not config.robot:
                raise ConfigError("robot: '' is invalid; expected a robot name or YAML path "
                                  "when the config has no sim section")
            try:
                self.spec = load_robot(config.robot)
            except (SimError, ConfigError) as err:
                raise ConfigError(f"robot: {err}") from err
        self.robot = self._robot_info()

    def _robot_info(self) -> RobotInfo:
        spec, c = self.spec, self.config
        control_dt = c.control_dt_s or (self.sim.engine.control_dt_s if self.sim else 0.1)
        omni = spec.drive is Drive.OMNI
        lidar = spec.lidar and Pose2D(spec.lidar.mount_xyz_m[0], spec.lidar.mount_xyz_m[1],
                                      spec.lidar.mount_yaw_rad)
        depth = spec.depth and Pose2D(spec.depth.mount_xyz_m[0], spec.depth.mount_xyz_m[1], 0.0)
        max_linear = _limit(c.max_linear_m_s, spec.max_linear_m_s)
        return RobotInfo(
            name=spec.name, footprint=spec.footprint, omni=omni,
            min_linear_m_s=-max_linear if omni else max(c.min_linear_m_s, -max_linear),
            max_linear_m_s=max_linear,
            max_angular_rad_s=_limit(c.max_angular_rad_s, spec.max_angular_rad_s),
            max_lateral_m_s=_limit(c.max_lateral_m_s, spec.max_lateral_m_s) if omni else 0.0,
            control_dt_s=control_dt, lidar_mount=lidar or None, depth_mount=depth or None,
            depth_hfov_rad=math.radians(spec.depth.hfov_deg) if spec.depth else math.radians(87),
            max_linear_accel_m_s2=spec.max_linear_accel_m_s2,
            max_angular_accel_rad_s2=spec.max_angular_accel_rad_s2)

    @cached_property
    def world(self) -> WorldSpec | None:
        """The simulated world (built once: a vineyard's rows, the bags' world name)."""
        return self.sim.world.build() if self.sim is not None else None

    @property
    def world_name(self) -> str:
        if self.sim is None:
            return ""
        return f"{self.sim.world.kind}:{self.sim.world.variant}"
