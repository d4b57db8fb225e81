"""The robot and world an env runs, from the config alone (``Scenario``): the one place the
config's sim section is resolved, once, at the edge (``make_vec_env``, ``make_env``, the tests'
plan, imitation), and the layers below get its typed values.

The sim section of the config (``sim_params``) names the robot, its sensors and the world, so
the env knows the footprint, the LiDAR's mount and a vineyard's rows without asking the
simulator; a real robot's config names the robot in ``robot`` instead (a built-in name or a
robot YAML), and has no world. Defaults (the robot, the control period) are ``SimParams``'.
With ``episodes.world_variants`` each episode runs one of several variants of the sim's world
(``select``); every variant is built once, when the scenario is made, so a bad one fails then.
``for_env`` hands one scenario to several envs: each selects its own world, the built ones shared.
"""

from __future__ import annotations

import copy
import dataclasses
from typing import TYPE_CHECKING, Any

from pic4rl_sim.engine.robot_specs import RobotSpec, load_robot
from pic4rl_sim.errors import SimError

from .config import EnvConfig
from .errors import ConfigError
from .robot_info import RobotInfo
from .settings.tasks import task_spec

if TYPE_CHECKING:  # pic4rl_sim.config imports mujoco: only when a sim section is used
    from pic4rl_sim.engine.worlds.spec import WorldSpec
    from pic4rl_sim.config import SimConfig


#: The env settings a ``Scenario`` resolves from (with the sim section): an env made from it
#: (``for_env``) has the same.
RESOLVED_KEYS = ("transport", "robot", "control_dt_s", "task", "ros.sim_node",
                 "episodes.world_variants")


class Scenario:
    """The robot and world an env runs: from ``config.sim_params`` when the env drives a
    simulator (``EnvConfig.simulated``), else from ``config.robot`` (a real robot: no world;
    a sim section there, such as a trained agent's, gives only its robot and control period
    when ``robot`` and ``control_dt_s`` are unset)."""

    def __init__(self, config: EnvConfig) -> None:
        self.config = config
        self.sim: SimConfig | None = None
        #: The sim's parameters, its robot's defaults filled in (empty without a simulator).
        self.values: dict[str, Any] = {}
        if config.transport == "inprocess" or (config.sim_params and config.simulated):
            from pic4rl_sim.config import SimParams, build_config, parameter_table, resolve

            try:
                robot = load_robot(config.robot or config.sim_params.get("robot",
                                                                         SimParams.robot))
                values = resolve(parameter_table(robot), config.sim_params, where="")
                if config.robot:
                    values["robot"] = config.robot
                self.sim, self.values = build_config(values), values
            except (SimError, ConfigError) as err:
                raise ConfigError(f"sim parameters: {err}") from err
            self.spec: RobotSpec = self.sim.robot
            control_dt = self.sim.engine.control_dt_s
        else:
            from pic4rl_sim.config import SimParams

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
        #: The variants the episodes draw from (``episodes.world_variants``), and the current
        #: episode's (``None``: the sim's ``world_variant``).
        self.variants = parse_variants(config.episodes.world_variants)
        self.variant: int | None = None
        self._worlds: dict[int | None, WorldSpec | None] = {}
        if self.variants:
            if self.sim is None or config.episodes.file or task_spec(config.task).uses_world:
                raise ConfigError("episodes.world_variants: a world per episode needs a "
                                  "simulated world (a 'sim:' section), no episodes.file (its "
                                  "pairs are in one world) and a task that knows no world's map")
            for variant in self.variants:
                self.world_at(variant)

    def for_env(self, config: EnvConfig | None = None) -> Scenario:
        """This scenario for one more env: its own current world (``select``), the worlds built
        so far shared (they are immutable); ``config``, when given, is that env's config, which
        may differ from this one's in what the resolution does not read (``RESOLVED_KEYS`` and
        the sim section: each env's namespace, a test's episodes, its recording); the robot's
        speed limits follow it."""
        if config is not None:
            mine, theirs = self.config.to_params(), config.to_params()
            keys = RESOLVED_KEYS + (("episodes.file",) if self.variants else ())
            changed = [k for k in keys if mine[k] != theirs[k]]
            if changed or config.sim_params != self.config.sim_params:
                raise ConfigError(f"{(changed or ['sim'])[0]}: differs from the scenario's "
                                  f"config; expected the same {', '.join(RESOLVED_KEYS)} and "
                                  "sim section")
        twin = copy.copy(self)
        twin.config, twin.variant = config or self.config, None
        if config is not None:
            twin.robot = RobotInfo.of(self.spec, config, self.robot.control_dt_s)
        return twin

    @property
    def node_values(self) -> dict[str, Any]:
        """``values`` as a sim node's params file carries them (``pic4rl-run``'s, a suite's ROS
        cells', a stack's driver's): empty arrays left out, as a ROS params file cannot type
        one (the sim's array parameters default to empty)."""
        return {k: v for k, v in self.values.items()
                if not (isinstance(v, (list, tuple)) and not v)}

    def world_at(self, variant: int | None) -> WorldSpec | None:
        """Variant ``variant`` of the simulated world (``None``: the sim's own), built once."""
        if variant not in self._worlds:
            if self.sim is None:
                return None
            choice = self.sim.world if variant is None else dataclasses.replace(
                self.sim.world, variant=variant)
            try:
                self._worlds[variant] = choice.build()
            except (SimError, ConfigError) as err:
                key = "sim parameters" if variant is None else "episodes.world_variants"
                raise ConfigError(f"{key}: {err}") from err
        return self._worlds[variant]

    def select(self, variant: int | None) -> bool:
        """Make ``variant`` the current episode's world; whether that changed it."""
        changed, self.variant = variant != self.variant, variant
        return changed

    @property
    def world(self) -> WorldSpec | None:
        """The current episode's simulated world (a vineyard's rows, the bags' world name)."""
        return self.world_at(self.variant)

    @property
    def world_name(self) -> str:
        if self.sim is None:
            return ""
        variant = self.sim.world.variant if self.variant is None else self.variant
        return f"{self.sim.world.kind}:{variant}"


def parse_variants(text: str, key: str = "episodes.world_variants") -> tuple[int, ...]:
    """The variants of ``text``: comma-separated, each ``N`` or ``START:STOP[:STEP]`` (Python's
    ``range``), in order; ``ConfigError`` naming ``key`` for anything else."""
    variants: list[int] = []
    for item in (part.strip() for part in text.split(",") if part.strip()):
        try:
            numbers = [int(v) for v in item.split(":")]
            found = numbers if len(numbers) == 1 else list(range(*numbers))
        except (ValueError, TypeError):
            found = []
        if not found:
            raise ConfigError(f"{key}: {item!r} is invalid; expected a variant N or a range "
                              "START:STOP[:STEP] holding one or more")
        variants += found
    return tuple(variants)


def robot_of(config: EnvConfig) -> str:
    """The robot (a built-in name or a robot YAML) of an env without a simulator: ``robot``,
    else its sim section's, else none (``""``)."""
    from pic4rl_sim.config import SimParams

    sim = config.sim_params
    return config.robot or (str(sim.get("robot", SimParams.robot)) if sim else "")
