"""The sim node's parameters as data, and the typed configuration built from their values.

``SimParams`` describes the node's own parameters (``pic4rl_base.schema``: description, unit,
range); the sensor parameters are the fields of the robot's sensor specs, with the robot's
values as defaults, and the world parameters those of the chosen generator, so the table is a
function of the robot (``parameter_table``). The node declares them from it and
``build_config`` turns a full set of values into frozen configs. Pure Python: the rules are
unit-tested without ROS.
"""

from __future__ import annotations

import dataclasses
import difflib
import math
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from typing import Any

from pic4rl_base.errors import ConfigError, require, unknown_key
from pic4rl_base.goal import Goal
from pic4rl_base.schema import (ParamEnum, ParamSpec, ParamType, Range, check, from_params, param,
                                param_names, specs)

from .engine.crowd.params import CrowdParams
from .engine.engine_config import EngineConfig
from pic4rl_base.geometry import Pose2D
from .engine.robot_specs import RobotSpec, load_robot
from .engine.sensors import SENSOR_TABLE
from .engine.worlds.generators import WORLD_TABLE, make_world
from .engine.worlds.spec import WorldSpec

MAX_SEED = 2**31 - 1
_SEED = Range(0, MAX_SEED)


class ClockMode(ParamEnum):
    """``lockstep``: each ``cmd_vel`` advances one control period; ``realtime``: a wall timer."""

    LOCKSTEP = "lockstep"
    REALTIME = "realtime"


@dataclass(frozen=True)
class SimParams:
    """The sim node's own parameters (the ``sim:`` section, less sensors and world settings)."""

    robot: str = param("jackal", doc="built-in robot (jackal, husky, burger, omni) or the path "
                       "of a robot YAML file")
    world: str = param("indoor", doc=f"world generator ({', '.join(WORLD_TABLE)}) or the path of "
                       "an MJCF .xml file")
    world_variant: int = param(0, doc="seed of the world generator: the same variant gives the "
                               "same geometry", range=_SEED)
    seed: int = param(0, doc="seed of the next episode (sampling and sensor noise); a "
                      "reset_world without a new value uses the previous episode's seed + 1",
                      range=_SEED)
    start_pose: tuple[float, ...] = param((), doc="[x, y, yaw] (m, m, rad) of the robot in the "
                                          "world frame at the next reset_world; empty = sampled "
                                          "with clearance")
    goal: tuple[float, ...] = param((), doc="[x, y] (m), or [x, y, yaw] (m, m, rad) with the "
                                    "heading a task may judge, of the goal in the world frame at "
                                    "the next reset_world; empty = sampled")
    clock_mode: ClockMode = param(ClockMode.LOCKSTEP, doc="lockstep: each cmd_vel advances one "
                                  "control period; realtime: a wall-clock timer steps with the "
                                  "latest command (applies immediately)")
    real_time_factor: float = param(1.0, doc="realtime mode: simulated seconds per wall-clock "
                                    "second, in (0, 1000] (applies immediately)",
                                    range=Range(0.0, 1000.0, lo_open=True))
    cmd_timeout_s: float = param(0.5, doc="realtime mode: a command older than this (sim time) "
                                 "is replaced by a stop (applies immediately)",
                                 range=Range(0.0, 3600.0))
    physics_dt_s: float = param(EngineConfig.physics_dt_s, doc="MuJoCo time step, in (0, 0.05]",
                                unit="s", range=Range(0.0, 0.05, lo_open=True))
    control_dt_s: float = param(EngineConfig.control_dt_s, doc="control period: one cmd_vel in "
                                "lockstep, one published set of sensor messages; a whole "
                                "multiple of physics_dt_s", unit="s",
                                range=Range(0.0, 10.0, lo_open=True))
    clearance_m: float = param(EngineConfig.clearance_m, doc="free space around the footprint "
                               "for sampled starts and goals", unit="m", range=Range(0.0, 100.0))
    min_goal_distance_m: float = param(EngineConfig.min_goal_distance_m, doc="least distance "
                                       "between a sampled start and goal", unit="m",
                                       range=Range(0.0, 1000.0))

    def __post_init__(self) -> None:
        check(self)


_CORE = specs(SimParams)
ROBOT = _CORE[0]


def _world_params() -> tuple[ParamSpec, ...]:
    """``world.<kind>.<param>`` for every parameter of every generator."""
    return tuple(dataclasses.replace(spec, description=f"{kind} world: {spec.description}")
                 for kind, generator in WORLD_TABLE.items()
                 for spec in specs(generator.params, prefix=f"world.{kind}."))


def _sensor_params(robot: RobotSpec) -> tuple[ParamSpec, ...]:
    """Sensor overrides: the fields of the robot's sensor specs (``SENSOR_TABLE``), with the
    robot's own sensors as defaults (a sensor the robot lacks defaults to the stock one,
    disabled), after an ``<name>.enabled`` switch for each optional sensor."""
    switches = tuple(ParamSpec(f"{k.name}.enabled", ParamType.BOOL,
                               robot.sensors[k.name] is not None,
                               f"whether the robot carries its {k.label} "
                               f"(publishes {k.publishes})")
                     for k in SENSOR_TABLE if k.optional)
    fields = (specs(k.spec, defaults=robot.sensors[k.name] or k.spec(), prefix=f"{k.name}.")
              for k in SENSOR_TABLE)
    return (*switches, *(spec for group in fields for spec in group))


_CROWD = specs(CrowdParams, prefix="crowd.")


def parameter_table(robot: RobotSpec) -> tuple[ParamSpec, ...]:
    """Every parameter of the node, ``robot`` first, with ``robot``'s sensors as defaults,
    then the crowd's (``crowd.*``)."""
    return (*_CORE, *_world_params(), *_sensor_params(robot), *_CROWD)


def resolve(table: Iterable[ParamSpec], overrides: Mapping[str, Any], *,
            also_known: Iterable[str] = (), where: str = "parameters") -> dict[str, Any]:
    """The table's defaults updated with checked ``overrides`` (a params file, ``-p``).

    An override not in the table nor in ``also_known`` (rclpy's own parameters) is an error
    with a "did you mean", naming ``where``; so is a value of the wrong type or out of range.
    """
    specs = {spec.name: spec for spec in table}
    known = set(specs) | set(also_known)
    for name in sorted(overrides):
        if name not in known:
            raise unknown_key(name, known, where=where)
    values = {name: spec.default for name, spec in specs.items()}
    for name, value in overrides.items():
        if name in specs:
            values[name] = specs[name].check(value)
    return values


# -- typed configuration -----------------------------------------------------------------------


@dataclass(frozen=True)
class WorldChoice:
    """Which world to build: generator ``kind`` (or an MJCF path), its seed and parameters."""

    kind: str
    variant: int
    params: tuple[tuple[str, Any], ...] = ()

    def build(self) -> WorldSpec:
        """The world (``ConfigError`` or ``WorldError`` when it cannot be made)."""
        return make_world(self.kind, seed=self.variant, **dict(self.params))


@dataclass(frozen=True)
class ClockConfig:
    """How sim time advances; these apply at once, the rest of the config at ``reset_world``.
    Built from ``SimParams`` (``build_clock``), whose fields hold the defaults."""

    mode: ClockMode
    real_time_factor: float
    cmd_timeout_s: float


@dataclass(frozen=True)
class EpisodeConfig:
    """The next episode's seed, and its start and goal (``None``: sampled); built from
    ``SimParams``, whose fields hold the defaults."""

    seed: int
    start: Pose2D | None
    goal: tuple[float, float] | None


@dataclass(frozen=True)
class SimConfig:
    """Everything the node needs, typed and checked."""

    robot: RobotSpec
    world: WorldChoice
    engine: EngineConfig
    episode: EpisodeConfig
    clock: ClockConfig

    @property
    def build_key(self) -> tuple[RobotSpec, WorldChoice, EngineConfig]:
        """What an ``Engine`` is built from: a change needs a new one."""
        return self.robot, self.world, self.engine


def parse_start(value: list[float]) -> Pose2D | None:
    """``start_pose`` as a pose: empty → ``None``, else three finite numbers."""
    if len(value) == 0:
        return None
    ok = len(value) == 3 and all(math.isfinite(v) for v in value)
    require(ok, "start_pose", list(value), "[] or [x, y, yaw] of finite numbers (m, m, rad)")
    return Pose2D(float(value[0]), float(value[1]), float(value[2]))


def parse_goal(value: list[float]) -> Goal | None:
    """``goal`` as a goal: empty → ``None``, else two finite numbers, or three with a heading."""
    if len(value) == 0:
        return None
    ok = len(value) in (2, 3) and all(math.isfinite(v) for v in value)
    require(ok, "goal", list(value), "[], [x, y] or [x, y, yaw] of finite numbers (m, m, rad)")
    return Goal(*value)


def build_robot(values: Mapping[str, Any]) -> RobotSpec:
    """The ``robot`` parameter's robot with the sensor parameters applied."""
    robot = load_robot(values["robot"])
    changes: dict[str, Any] = {}
    for kind in SENSOR_TABLE:
        if kind.optional and not values[f"{kind.name}.enabled"]:
            changes[kind.name] = None
            continue
        stock = robot.sensors[kind.name] or kind.spec()
        fields = {f.name for f in dataclasses.fields(stock)}
        given = {k.split(".")[1]: v for k, v in values.items()
                 if k.startswith(f"{kind.name}.") and k.split(".")[1] in fields}
        changes[kind.name] = dataclasses.replace(stock, **given)
    return robot.with_sensors(**changes)


def build_world_choice(values: Mapping[str, Any]) -> WorldChoice:
    """The ``world`` parameter with its variant and the parameters of its generator."""
    kind = values["world"]
    if kind.endswith(".xml"):
        return WorldChoice(kind, values["world_variant"])
    if kind not in WORLD_TABLE:
        close = difflib.get_close_matches(kind, WORLD_TABLE, n=1)
        hint = f"; did you mean {close[0]!r}?" if close else ""
        raise ConfigError(f"world: {kind!r} is invalid; expected a generator "
                          f"({', '.join(WORLD_TABLE)}) or a path ending in .xml{hint}")
    params = tuple((name, values[f"world.{kind}.{name}"])
                   for name in param_names(WORLD_TABLE[kind].params))
    return WorldChoice(kind, values["world_variant"], params)


def build_clock(values: Mapping[str, Any]) -> ClockConfig:
    """The clock parameters, which apply at once (checked against ``SimParams``' ranges)."""
    core = _core(values)
    return ClockConfig(core.clock_mode, core.real_time_factor, core.cmd_timeout_s)


def _core(values: Mapping[str, Any]) -> SimParams:
    """The node's own parameters of ``values``, typed and checked (open bounds included)."""
    return from_params(SimParams, {spec.name: values[spec.name] for spec in _CORE},
                       where="sim parameters")


def build_config(values: Mapping[str, Any]) -> SimConfig:
    """A ``SimConfig`` from a full set of parameter values (``resolve``'s result)."""
    core = _core(values)
    engine = EngineConfig(physics_dt_s=core.physics_dt_s, control_dt_s=core.control_dt_s,
                          clearance_m=core.clearance_m,
                          min_goal_distance_m=core.min_goal_distance_m,
                          crowd=from_params(CrowdParams, {spec.name.removeprefix("crowd."):
                                                          values[spec.name] for spec in _CROWD},
                                            where="crowd parameters"))
    episode = EpisodeConfig(core.seed, parse_start(list(core.start_pose)),
                            parse_goal(list(core.goal)))
    return SimConfig(build_robot(values), build_world_choice(values), engine, episode,
                     ClockConfig(core.clock_mode, core.real_time_factor, core.cmd_timeout_s))
