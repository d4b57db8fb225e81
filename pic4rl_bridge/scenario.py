"""The robot and world an env runs, from the config alone (``Scenario``).

The sim section of the config (``sim_params``) names the robot, its sensors and the world, so
the env knows the footprint, the LiDAR's mount and a vineyard's rows without asking the
simulator; a real robot's config names the robot in ``robot`` instead (a built-in name or a
robot YAML), and has no world. Defaults (the robot, the control period) are ``SimParams``'.
"""

from __future__ import annotations

from functools import cached_property
from typing import TYPE_CHECKING

from pic4rl_sim.engine.robot_specs import RobotSpec, load_robot
from pic4rl_sim.errors import SimError

from .config import EnvConfig
from .errors import ConfigError
from .robot_info import RobotInfo

if TYPE_CHECKING:  # pic4rl_sim.params imports mujoco: only when a sim section is used
    from pic4rl_sim.engine.worlds.spec import WorldSpec
    from pic4rl_sim.params import SimConfig


class Scenario:
    """The robot and world an env runs: from ``config.sim_params`` when the env drives a
    simulator (``EnvConfig.simulated``), else from ``config.robot`` (a real robot: no world;
    a sim section there, such as a trained agent's, gives only its robot and control period
    when ``robot`` and ``control_dt_s`` are unset)."""

    def __init__(self, config: EnvConfig) -> None:
        self.config = config
        self.sim: SimConfig | None = None
        if config.transport == "inprocess" or (config.sim_params and config.simulated):
            from pic4rl_sim.params import SimParams, build_config, parameter_table, resolve

            try:
                robot = load_robot(config.robot or config.sim_params.get("robot",
                                                                         SimParams.robot))
                values = resolve(parameter_table(robot), config.sim_params, where="")
                if config.robot:
                    values["robot"] = config.robot
                self.sim = build_config(values)
            except (SimError, ConfigError) as err:
                raise ConfigError(f"sim parameters: {err}") from err
            self.spec: RobotSpec = self.sim.robot
            control_dt = self.sim.engine.control_dt_s
        else:
            from pic4rl_sim.params import SimParams

            robot = robot_of(config)
            if not robot:
                raise ConfigError("robot: '' is invalid; expected a robot name or YAML path "
                                  "when the config has no sim section")
            try:
                self.spec = load_robot(robot)
            except (SimError, ConfigError) as err:
                raise ConfigError(f"robot: {err}") from err
            control_dt = float(config.sim_params.get("control_dt_s", SimParams.control_dt_s))
        self.robot = RobotInfo.of(self.spec, config, config.control_dt_s or control_dt)

    @cached_property
    def world(self) -> WorldSpec | None:
        """The simulated world (built once: a vineyard's rows, the bags' world name)."""
        return self.sim.world.build() if self.sim is not None else None

    @property
    def world_name(self) -> str:
        if self.sim is None:
            return ""
        return f"{self.sim.world.kind}:{self.sim.world.variant}"


def robot_of(config: EnvConfig) -> str:
    """The robot (a built-in name or a robot YAML) of an env without a simulator: ``robot``,
    else its sim section's, else none (``""``)."""
    from pic4rl_sim.params import SimParams

    sim = config.sim_params
    return config.robot or (str(sim.get("robot", SimParams.robot)) if sim else "")
