"""The sim node's parameters as data, and the typed configuration built from their values.

One table (``parameter_table``) gives each parameter its name, type, default, description and
range; the node declares them from it and ``build_config`` turns a full set of values into
frozen configs. Everything here is pure Python, so the rules are unit-tested without ROS.
Sensor defaults come from the chosen robot, hence the table is a function of the robot.
"""

from __future__ import annotations

import array
import dataclasses
import difflib
import math
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from enum import Enum
from typing import Any

from .engine.core import EngineConfig
from .errors import ConfigError, require, unknown_key
from .engine.geometry import Pose2D
from .engine.robot_specs import DepthCameraSpec, LidarSpec, RobotSpec, load_robot
from .engine.world_spec import WorldSpec
from .engine.world_generators import GENERATORS, generator_params, make_world

MAX_SEED = 2**31 - 1


class ParamType(str, Enum):
    """The ROS 2 parameter types the node uses (names as in ``rclpy.Parameter.Type``)."""

    BOOL = "BOOL"
    INTEGER = "INTEGER"
    DOUBLE = "DOUBLE"
    STRING = "STRING"
    DOUBLE_ARRAY = "DOUBLE_ARRAY"


_PYTHON_TYPES = {bool: ParamType.BOOL, int: ParamType.INTEGER, float: ParamType.DOUBLE,
                 str: ParamType.STRING}
_EXPECTED = {ParamType.BOOL: "a bool", ParamType.INTEGER: "an integer",
             ParamType.DOUBLE: "a number", ParamType.STRING: "a string",
             ParamType.DOUBLE_ARRAY: "a list of numbers"}


class ClockMode(str, Enum):
    """``lockstep``: each ``cmd_vel`` advances one control period; ``realtime``: a wall timer."""

    LOCKSTEP = "lockstep"
    REALTIME = "realtime"


@dataclass(frozen=True)
class ParamSpec:
    """One node parameter: ``range`` is inclusive (ROS ranges are); ``choices`` closes a string."""

    name: str
    type: ParamType
    default: Any
    description: str
    range: tuple[float, float] | None = None
    choices: tuple[str, ...] = ()

    def check(self, value: Any) -> Any:
        """``value`` in this parameter's type (an integer where a number is wanted becomes a
        float), or ``ConfigError`` naming the key, the value and what was expected."""
        typed = _coerce(self.type, value)
        require(typed is not None, self.name, value, _EXPECTED[self.type])
        value = typed
        if self.range is not None:
            lo, hi = self.range
            require(lo <= value <= hi, self.name, value, f"a value in [{lo}, {hi}]")
        if self.choices:
            require(value in self.choices, self.name, value, f"one of {', '.join(self.choices)}")
        return value


def _coerce(kind: ParamType, value: Any) -> Any:
    """``value`` as ``kind``, or ``None`` when it is not one."""
    is_int = isinstance(value, int) and not isinstance(value, bool)
    if kind is ParamType.BOOL:
        return value if isinstance(value, bool) else None
    if kind is ParamType.INTEGER:
        return value if is_int else None
    if kind is ParamType.DOUBLE:
        return float(value) if is_int or isinstance(value, float) else None
    if kind is ParamType.STRING:
        return value if isinstance(value, str) else None
    if isinstance(value, (list, tuple, array.array)):
        items = [_coerce(ParamType.DOUBLE, v) for v in value]
        return None if any(v is None for v in items) else items
    return None


# -- the table ---------------------------------------------------------------------------------

_ANY_M = (0.0, 1000.0)
_SENSOR_DOCS: dict[str, tuple[str, tuple[float, float]]] = {
    "lidar.beams": ("number of LiDAR beams", (1, 10_000)),
    "lidar.fov_deg": ("LiDAR field of view, centred on the mount's forward axis (deg)",
                      (0.0, 360.0)),
    "lidar.range_min_m": ("LiDAR minimum range; closer returns read -inf (m)", _ANY_M),
    "lidar.range_max_m": ("LiDAR maximum range; farther returns read +inf (m)", _ANY_M),
    "lidar.noise_std_m": ("standard deviation of the Gaussian noise on each range (m)",
                          (0.0, 10.0)),
    "lidar.dropout_prob": ("probability that a beam is dropped (reads +inf)", (0.0, 1.0)),
    "depth.width": ("depth image width (px)", (1, 4096)),
    "depth.height": ("depth image height (px)", (1, 4096)),
    "depth.hfov_deg": ("depth camera horizontal field of view (deg)", (0.0, 180.0)),
    "depth.min_depth_m": ("depth camera minimum depth; closer pixels read -inf (m)", _ANY_M),
    "depth.max_depth_m": ("depth camera maximum depth; farther pixels read +inf (m)", _ANY_M),
    "depth.noise_std_m": ("standard deviation of the Gaussian noise on each pixel (m)",
                          (0.0, 10.0)),
    "imu.gyro_noise_std_rad_s": ("standard deviation of the gyro's white noise (rad/s)",
                                 (0.0, 10.0)),
    "imu.accel_noise_std_m_s2": ("standard deviation of the accelerometer's white noise (m/s^2)",
                                 (0.0, 100.0)),
    "odometry.linear_scale_error": ("systematic wheel-odometry error on distance "
                                    "(0.02 = 2 % too far)", (-1.0, 1.0)),
    "odometry.angular_scale_error": ("systematic wheel-odometry error on rotation", (-1.0, 1.0)),
    "odometry.linear_noise_std": ("relative noise on each period's odometry displacement",
                                  (0.0, 0.999)),
    "odometry.angular_noise_std": ("relative noise on each period's odometry rotation",
                                   (0.0, 0.999)),
}

ROBOT = ParamSpec("robot", ParamType.STRING, "jackal",
                  "built-in robot (jackal, husky, burger, omni) or the path of a robot YAML file")

_CORE = (
    ParamSpec("world", ParamType.STRING, "indoor",
              f"world generator ({', '.join(GENERATORS)}) or the path of an MJCF .xml file"),
    ParamSpec("world_variant", ParamType.INTEGER, 0,
              "seed of the world generator: the same variant gives the same geometry",
              (0, MAX_SEED)),
    ParamSpec("seed", ParamType.INTEGER, 0,
              "seed of the next episode (sampling and sensor noise); a reset_world without a new "
              "value uses the previous episode's seed + 1", (0, MAX_SEED)),
    ParamSpec("start_pose", ParamType.DOUBLE_ARRAY, [],
              "[x, y, yaw] (m, m, rad) of the robot in the world frame at the next reset_world; "
              "empty = sampled with clearance"),
    ParamSpec("goal", ParamType.DOUBLE_ARRAY, [],
              "[x, y] (m) of the goal in the world frame at the next reset_world; empty = sampled"),
    ParamSpec("clock_mode", ParamType.STRING, ClockMode.LOCKSTEP.value,
              "lockstep: each cmd_vel advances one control period; realtime: a wall-clock timer "
              "steps with the latest command (applies immediately)",
              choices=tuple(m.value for m in ClockMode)),
    ParamSpec("real_time_factor", ParamType.DOUBLE, 1.0,
              "realtime mode: simulated seconds per wall-clock second, in (0, 1000] (applies "
              "immediately)", (0.0, 1000.0)),
    ParamSpec("cmd_timeout_s", ParamType.DOUBLE, 0.5,
              "realtime mode: a command older than this (sim time) is replaced by a stop "
              "(applies immediately)", (0.0, 3600.0)),
    ParamSpec("physics_dt_s", ParamType.DOUBLE, EngineConfig.physics_dt_s,
              "MuJoCo time step, in (0, 0.05] (s)", (0.0, 0.05)),
    ParamSpec("control_dt_s", ParamType.DOUBLE, EngineConfig.control_dt_s,
              "control period: one cmd_vel in lockstep, one published set of sensor messages; a "
              "whole multiple of physics_dt_s (s)", (0.0, 10.0)),
    ParamSpec("clearance_m", ParamType.DOUBLE, EngineConfig.clearance_m,
              "free space around the footprint for sampled starts and goals (m)", (0.0, 100.0)),
    ParamSpec("min_goal_distance_m", ParamType.DOUBLE, EngineConfig.min_goal_distance_m,
              "least distance between a sampled start and goal (m)", (0.0, 1000.0)),
)


def _world_params() -> tuple[ParamSpec, ...]:
    """``world.<kind>.<param>`` for every parameter of every generator."""
    specs = []
    for kind in GENERATORS:
        for name, (kind_type, default, doc) in generator_params(kind).items():
            specs.append(ParamSpec(f"world.{kind}.{name}", _PYTHON_TYPES[kind_type], default,
                                   f"{kind} world: {doc}"))
    return tuple(specs)


def _sensor_params(robot: RobotSpec) -> tuple[ParamSpec, ...]:
    """Sensor overrides, with the robot's own sensors as defaults (a sensor the robot lacks
    defaults to the stock one, disabled)."""
    defaults = {"lidar": robot.lidar or LidarSpec(), "depth": robot.depth or DepthCameraSpec(),
                "imu": robot.imu, "odometry": robot.odometry}
    specs = [
        ParamSpec("lidar.enabled", ParamType.BOOL, robot.lidar is not None,
                  "whether the robot carries its LiDAR (publishes scan)"),
        ParamSpec("depth.enabled", ParamType.BOOL, robot.depth is not None,
                  "whether the robot carries its depth camera (publishes camera/depth/*)"),
    ]
    for name, (doc, bounds) in _SENSOR_DOCS.items():
        sensor, field = name.split(".")
        default = getattr(defaults[sensor], field)
        specs.append(ParamSpec(name, _PYTHON_TYPES[type(default)], default, doc, bounds))
    return tuple(specs)


def parameter_table(robot: RobotSpec) -> tuple[ParamSpec, ...]:
    """Every parameter of the node, ``robot`` first, with ``robot``'s sensors as defaults."""
    return (ROBOT, *_CORE, *_world_params(), *_sensor_params(robot))


def resolve(table: Iterable[ParamSpec], overrides: Mapping[str, Any], *,
            also_known: Iterable[str] = ()) -> dict[str, Any]:
    """The table's defaults updated with checked ``overrides`` (a params file, ``-p``).

    An override not in the table nor in ``also_known`` (rclpy's own parameters) is an error
    with a "did you mean"; so is a value of the wrong type or out of range.
    """
    specs = {spec.name: spec for spec in table}
    known = set(specs) | set(also_known)
    for name in sorted(overrides):
        if name not in known:
            raise unknown_key(name, known, where="parameters")
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
    """How sim time advances; these apply at once, the rest of the config at ``reset_world``."""

    mode: ClockMode = ClockMode.LOCKSTEP
    real_time_factor: float = 1.0
    cmd_timeout_s: float = 0.5

    def __post_init__(self) -> None:
        require(0 < self.real_time_factor <= 1000, "real_time_factor", self.real_time_factor,
                "a factor in (0, 1000]")
        require(self.cmd_timeout_s >= 0, "cmd_timeout_s", self.cmd_timeout_s, "a time >= 0 s")


@dataclass(frozen=True)
class EpisodeConfig:
    """The next episode's seed, and its start and goal (``None``: sampled)."""

    seed: int = 0
    start: Pose2D | None = None
    goal: tuple[float, float] | None = None


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


def parse_goal(value: list[float]) -> tuple[float, float] | None:
    """``goal`` as a point: empty → ``None``, else two finite numbers."""
    if len(value) == 0:
        return None
    ok = len(value) == 2 and all(math.isfinite(v) for v in value)
    require(ok, "goal", list(value), "[] or [x, y] of finite numbers (m)")
    return float(value[0]), float(value[1])


def build_robot(values: Mapping[str, Any]) -> RobotSpec:
    """The ``robot`` parameter's robot with the sensor parameters applied."""
    robot = load_robot(values["robot"])
    changes: dict[str, Any] = {}
    for sensor, stock in (("lidar", robot.lidar or LidarSpec()),
                          ("depth", robot.depth or DepthCameraSpec())):
        fields = {f.name for f in dataclasses.fields(stock)}
        if values[f"{sensor}.enabled"]:
            given = {k.split(".")[1]: v for k, v in values.items()
                     if k.startswith(f"{sensor}.") and k.split(".")[1] in fields}
            changes[sensor] = dataclasses.replace(stock, **given)
        else:
            changes[sensor] = None
    for sensor in ("imu", "odometry"):
        stock = getattr(robot, sensor)
        given = {k.split(".")[1]: v for k, v in values.items() if k.startswith(f"{sensor}.")}
        changes[sensor] = dataclasses.replace(stock, **given)
    return robot.with_sensors(**changes)


def build_world_choice(values: Mapping[str, Any]) -> WorldChoice:
    """The ``world`` parameter with its variant and the parameters of its generator."""
    kind = values["world"]
    if kind.endswith(".xml"):
        return WorldChoice(kind, values["world_variant"])
    if kind not in GENERATORS:
        close = difflib.get_close_matches(kind, GENERATORS, n=1)
        hint = f"; did you mean {close[0]!r}?" if close else ""
        raise ConfigError(f"world: {kind!r} is invalid; expected a generator "
                          f"({', '.join(GENERATORS)}) or a path ending in .xml{hint}")
    params = tuple((name, values[f"world.{kind}.{name}"]) for name in generator_params(kind))
    return WorldChoice(kind, values["world_variant"], params)


def build_clock(values: Mapping[str, Any]) -> ClockConfig:
    """The clock parameters, which apply at once."""
    return ClockConfig(ClockMode(values["clock_mode"]), values["real_time_factor"],
                       values["cmd_timeout_s"])


def build_config(values: Mapping[str, Any]) -> SimConfig:
    """A ``SimConfig`` from a full set of parameter values (``resolve``'s result)."""
    engine = EngineConfig(physics_dt_s=values["physics_dt_s"],
                          control_dt_s=values["control_dt_s"],
                          clearance_m=values["clearance_m"],
                          min_goal_distance_m=values["min_goal_distance_m"])
    episode = EpisodeConfig(values["seed"], parse_start(values["start_pose"]),
                            parse_goal(values["goal"]))
    return SimConfig(build_robot(values), build_world_choice(values), engine, episode,
                     build_clock(values))
