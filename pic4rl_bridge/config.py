"""The env's configuration: typed, frozen, read from the same ROS 2 parameter YAML as the nodes.

A config file holds one section per node, as ``--params-file`` expects::

    sim:                       # the sim node's parameters (pic4rl-sim reads this section)
      ros__parameters: {robot: jackal, world: indoor, ...}
    nav_env:                   # the env's parameters (this module)
      ros__parameters: {task: goToPose, sensor: lidar, reward: {goal: 1000.0}, ...}

Nested mappings are dotted names, as in ROS (``reward.goal``). Every key is checked: an
unknown one gets a "did you mean", a bad value names the key, the value and what was expected.
The in-process transport builds its engine from the ``sim`` section, so one file configures
both transports identically.
"""

from __future__ import annotations

import dataclasses
import math
import types
import typing
from collections.abc import Mapping
from dataclasses import dataclass, field
from enum import Enum
from pathlib import Path
from typing import Any, TypeVar

import yaml
from pic4rl_sim.engine.sampling import PAIR_KINDS

from .errors import ConfigError, require, unknown_key

T = TypeVar("T")
ENV_NODE = "nav_env"
SIM_NODE = "sim"
#: Topics recorded to each episode's bag by default (the bag contract; absent ones are skipped).
CONTRACT_TOPICS = ("clock", "ground_truth", "odom", "scan", "cmd_vel", "goal_pose",
                   "camera/depth/image_raw", "camera/depth/camera_info", "person/pose")


class TaskName(str, Enum):
    GO_TO_POSE = "goToPose"
    VINEYARD = "vineyard"
    PERSON_MONITORING = "personMonitoring"


class SensorName(str, Enum):
    LIDAR = "lidar"
    DEPTH = "depth"


class TransportName(str, Enum):
    INPROCESS = "inprocess"
    ROS = "ros"


class StepMode(str, Enum):
    """``lockstep``: one ``cmd_vel`` → wait for the sensor set it causes (our sim's lockstep
    clock); ``rate``: send, wait one control period of wall time, read the latest (a real robot
    or a real-time simulator)."""

    LOCKSTEP = "lockstep"
    RATE = "rate"


@dataclass(frozen=True)
class RewardConfig:
    """Reward scales; each term is reported in ``info["reward_terms"]``."""

    goal: float = 1000.0  # goToPose: reaching the goal (the paper's r_g)
    collision: float = -150.0  # every task: the collision that ends the episode (r_c)
    distance: float = 1.0  # goToPose: times d_{t-1} - d_t (m), the paper's dense r_d
    heading: float = 0.0  # goToPose: times (1 - 2 sqrt(|goal angle| / pi)) (the original code)
    step: float = 0.0  # every task: added each step (a time penalty when < 0)
    proximity: float = 0.0  # goToPose: times max(0, 1 - clearance / proximity_range_m)
    proximity_range_m: float = 0.5  # goToPose: clearance (m) from which proximity starts
    progress: float = 10.0  # vineyard: times the advance along the row (m)
    centering: float = 1.0  # vineyard: times -|offset from the row's centre line| (m)
    row_end: float = 100.0  # vineyard: reaching the row's end
    facing: float = 1.0  # personMonitoring: times cos(angle between heading and person)
    person_distance: float = 0.5  # personMonitoring: times -|distance - desired distance| (m)


@dataclass(frozen=True)
class LidarObsConfig:
    """The LiDAR observation: ``beams`` sectors, each the minimum range in it, clipped."""

    beams: int = 36
    max_range_m: float = 10.0


@dataclass(frozen=True)
class DepthObsConfig:
    """The depth observation: resized to ``width`` × ``height``, clipped at ``max_depth_m``;
    ``uint8`` scales [0, max_depth_m] to [0, 255] so SB3's CNN treats it as an image."""

    width: int = 80
    height: int = 60
    max_depth_m: float = 5.0
    encoding: str = "uint8"  # uint8 | float32


@dataclass(frozen=True)
class VineyardConfig:
    end_tolerance_m: float = 0.5  # the row ends when this close to its last point (along it)
    centerline: tuple[float, ...] = ()  # x0, y0, x1, y1, ... (m); empty: the world's lanes


@dataclass(frozen=True)
class PersonConfig:
    distance_m: float = 2.0  # desired distance to the person


@dataclass(frozen=True)
class DwaConfig:
    """The Dynamic Window Approach baseline (``pic4rl_bridge.baselines.DwaController``). The
    velocity ranges, acceleration limits, window period and footprint are the robot's."""

    horizon_s: float = 1.5  # each velocity sample is simulated this long
    rollout_dt_s: float = 0.1  # time between the simulated poses checked against the scan
    linear_samples: int = 7  # forward speeds sampled across the window (ends included)
    angular_samples: int = 15  # yaw rates sampled across the window (ends included)
    heading_weight: float = 1.0  # times 1 - |target bearing| / pi, from the nearest rollout pose
    clearance_weight: float = 0.4  # times the distance driven before a collision (capped)
    speed_weight: float = 0.3  # times v / max_linear_m_s
    clearance_cap_m: float = 0.6  # a rollout free of collisions scores this distance (m)
    lookahead_m: float = 2.0  # the target is the goal if a lane is free this far, else along
    # the free lane nearest the goal's bearing (m)
    safety_margin_m: float = 0.05  # beyond collision_tolerance_m: closer poses are collisions
    point_resolution_m: float = 0.05  # scan points merged on a grid this fine (m)

    def __post_init__(self) -> None:
        for key in ("horizon_s", "rollout_dt_s", "clearance_cap_m", "lookahead_m",
                    "point_resolution_m"):
            value = getattr(self, key)
            require(math.isfinite(value) and value > 0, f"baselines.dwa.{key}", value,
                    "a positive number")
        for key in ("heading_weight", "clearance_weight", "speed_weight", "safety_margin_m"):
            value = getattr(self, key)
            require(math.isfinite(value) and value >= 0, f"baselines.dwa.{key}", value,
                    "a number >= 0")
        for key in ("linear_samples", "angular_samples"):
            value = getattr(self, key)
            require(2 <= value <= 101, f"baselines.dwa.{key}", value, "an integer in [2, 101]")
        require(self.rollout_dt_s <= self.horizon_s, "baselines.dwa.rollout_dt_s",
                self.rollout_dt_s, f"at most horizon_s={self.horizon_s}")


@dataclass(frozen=True)
class BaselinesConfig:
    """The classical controllers ``pic4rl-test --baseline`` runs (the env ignores them)."""

    dwa: DwaConfig = field(default_factory=DwaConfig)


@dataclass(frozen=True)
class EpisodesConfig:
    """Where episodes start and end (see ``pic4rl_bridge.episodes``)."""

    file: str = ""  # a PIC4rl-gym goals_and_poses JSON; empty: sampled by the simulator
    change_goal_and_pose: int = 1  # draw a new pair of the file every N episodes
    starting_episodes: int = 0  # first N episodes: initial_pose and a random goal near it
    starting_goal_range_m: float = 2.9  # ... within ± this of the initial pose in x and y
    max_attempts: int = 20  # goals redrawn when the simulator rejects one
    ordered: bool = False  # walk the file's pairs in order (PIC4rl-gym's testing mode)
    # Sampled pairs (no file): a kind of pic4rl_sim.engine.sampling.PAIR_KINDS, any | paper; 0 below
    # keeps the kind's value. Other than plain "any", the env draws the pair (with a path check).
    pair_kind: str = "any"
    min_distance_m: float = 0.0  # straight start-goal distance at least (m)
    max_distance_m: float = 0.0  # ... and at most (m)
    max_detour: float = 0.0  # shortest collision-free path / straight line at most

    def __post_init__(self) -> None:
        require(self.pair_kind in PAIR_KINDS, "episodes.pair_kind", self.pair_kind,
                f"one of {', '.join(PAIR_KINDS)}")
        for key in ("min_distance_m", "max_distance_m"):
            value = getattr(self, key)
            require(math.isfinite(value) and value >= 0, f"episodes.{key}", value,
                    "a distance >= 0 m (0: the kind's)")
        require(self.max_detour == 0 or self.max_detour >= 1, "episodes.max_detour",
                self.max_detour, "0 (the kind's) or a ratio >= 1")


@dataclass(frozen=True)
class TopicsConfig:
    """Topic names, relative to ``ros.namespace`` unless absolute."""

    cmd_vel: str = "cmd_vel"
    pose: str = "odom"  # odom (wheel odometry) | ground_truth, or any nav_msgs/Odometry topic
    scan: str = "scan"
    depth: str = "camera/depth/image_raw"
    goal: str = "goal_pose"
    person: str = "person/pose"


@dataclass(frozen=True)
class RosConfig:
    namespace: str = ""
    domain_id: int = -1  # -1: ROS_DOMAIN_ID of the environment (or 0)
    node_name: str = ENV_NODE
    sim_node: str = SIM_NODE  # node whose parameters set seed/start/goal; empty: none (real robot)
    reset_service: str = "reset_world"  # empty: a reset waits for a new goal on topics.goal
    step_mode: str = StepMode.LOCKSTEP.value
    cmd_vel_type: str = "Twist"  # Twist | TwistStamped
    sensor_qos: str = "best_effort"  # best_effort (sensor data) | reliable
    timeout_s: float = 10.0  # waiting for a service or a message
    operator_timeout_s: float = 0.0  # real robot: wait this long for a new goal; 0 = forever


@dataclass(frozen=True)
class RecordConfig:
    """Episode bags: ``<bags_dir>/<run>/<episode>/``, the run's config beside them."""

    enabled: bool = False
    bags_dir: str = "bags"
    run: str = ""  # empty: <task>_<date>_<time>
    storage: str = "sqlite3"  # sqlite3 | mcap
    topics: tuple[str, ...] = CONTRACT_TOPICS
    flush_interval_s: float = 1.0  # sqlite3: commit this often, so a killed recorder keeps data


@dataclass(frozen=True)
class EnvConfig:
    """Everything ``NavEnv`` needs besides the simulator's own parameters (``sim_params``)."""

    task: str = TaskName.GO_TO_POSE.value
    sensor: str = SensorName.LIDAR.value
    transport: str = TransportName.INPROCESS.value
    agent: str = ""
    robot: str = ""  # empty: the sim section's robot; else a built-in name or robot YAML
    episode_max_steps: int = 500
    normalize_observations: bool = False  # goToPose: ranges and goal distance in [0, 1], angle / pi
    goal_tolerance_m: float = 0.4
    collision_tolerance_m: float = 0.05
    warning_tolerance_m: float = 0.1
    collision_steps: int = 1  # consecutive collision steps that end an episode (original: 3)
    max_linear_m_s: float = 0.0  # 0: the robot's limit
    min_linear_m_s: float = 0.0  # differential drive; the paper's: 0 (omni: -max_linear)
    max_angular_rad_s: float = 0.0  # 0: the robot's limit
    max_lateral_m_s: float = 0.0  # omni robots; 0: the robot's limit
    control_dt_s: float = 0.0  # 0: the sim section's control_dt_s (rate mode's period)
    reward: RewardConfig = field(default_factory=RewardConfig)
    lidar: LidarObsConfig = field(default_factory=LidarObsConfig)
    depth: DepthObsConfig = field(default_factory=DepthObsConfig)
    vineyard: VineyardConfig = field(default_factory=VineyardConfig)
    person: PersonConfig = field(default_factory=PersonConfig)
    episodes: EpisodesConfig = field(default_factory=EpisodesConfig)
    topics: TopicsConfig = field(default_factory=TopicsConfig)
    ros: RosConfig = field(default_factory=RosConfig)
    record: RecordConfig = field(default_factory=RecordConfig)
    baselines: BaselinesConfig = field(default_factory=BaselinesConfig)
    #: The sim node's parameters (the ``sim`` section), checked by pic4rl_sim when used.
    sim_params: Mapping[str, Any] = field(default_factory=dict, compare=False)

    def __post_init__(self) -> None:
        _choice("task", self.task, TaskName)
        _choice("sensor", self.sensor, SensorName)
        _choice("transport", self.transport, TransportName)
        _choice("ros.step_mode", self.ros.step_mode, StepMode)
        require(self.ros.cmd_vel_type in ("Twist", "TwistStamped"), "ros.cmd_vel_type",
                self.ros.cmd_vel_type, "Twist or TwistStamped")
        require(self.ros.sensor_qos in ("best_effort", "reliable"), "ros.sensor_qos",
                self.ros.sensor_qos, "best_effort or reliable")
        require(self.record.storage in ("sqlite3", "mcap"), "record.storage",
                self.record.storage, "sqlite3 or mcap")
        require(self.depth.encoding in ("uint8", "float32"), "depth.encoding",
                self.depth.encoding, "uint8 or float32")
        positive = {"episode_max_steps": self.episode_max_steps,
                    "goal_tolerance_m": self.goal_tolerance_m,
                    "collision_steps": self.collision_steps, "lidar.beams": self.lidar.beams,
                    "lidar.max_range_m": self.lidar.max_range_m,
                    "reward.proximity_range_m": self.reward.proximity_range_m,
                    "depth.width": self.depth.width, "depth.height": self.depth.height,
                    "depth.max_depth_m": self.depth.max_depth_m,
                    "episodes.change_goal_and_pose": self.episodes.change_goal_and_pose,
                    "episodes.max_attempts": self.episodes.max_attempts,
                    "ros.timeout_s": self.ros.timeout_s}
        for key, value in positive.items():
            require(math.isfinite(value) and value > 0, key, value, "a positive number")
        non_negative = {"collision_tolerance_m": self.collision_tolerance_m,
                        "warning_tolerance_m": self.warning_tolerance_m,
                        "max_linear_m_s": self.max_linear_m_s,
                        "max_angular_rad_s": self.max_angular_rad_s,
                        "max_lateral_m_s": self.max_lateral_m_s,
                        "control_dt_s": self.control_dt_s,
                        "episodes.starting_episodes": self.episodes.starting_episodes,
                        "episodes.starting_goal_range_m": self.episodes.starting_goal_range_m,
                        "person.distance_m": self.person.distance_m,
                        "vineyard.end_tolerance_m": self.vineyard.end_tolerance_m,
                        "ros.operator_timeout_s": self.ros.operator_timeout_s,
                        "record.flush_interval_s": self.record.flush_interval_s}
        for key, value in non_negative.items():
            require(math.isfinite(value) and value >= 0, key, value, "a number >= 0")
        require(math.isfinite(self.min_linear_m_s) and (
            self.max_linear_m_s == 0 or self.min_linear_m_s <= self.max_linear_m_s),
            "min_linear_m_s", self.min_linear_m_s,
            f"a finite speed <= max_linear_m_s={self.max_linear_m_s}")
        line = self.vineyard.centerline
        require(len(line) == 0 or (len(line) >= 4 and len(line) % 2 == 0),
                "vineyard.centerline", line, "[] or x0, y0, x1, y1, ... (two or more points)")

    def to_params(self) -> dict[str, Any]:
        """The flat dotted parameters of this config (``sim_params`` left out)."""
        return _flatten(self)

    def replace(self, **overrides: Any) -> EnvConfig:
        """A copy with dotted ``overrides`` applied (``{"reward.goal": 500.0}``)."""
        params = {**self.to_params(), **overrides}
        return env_config_from_params(params, sim_params=self.sim_params)


def _choice(key: str, value: str, kind: type[Enum]) -> None:
    names = [m.value for m in kind]  # type: ignore[attr-defined]
    require(value in names, key, value, f"one of {', '.join(names)}")


# -- flat dotted parameters <-> nested dataclasses ----------------------------------------------


def _fields(cls: type) -> dict[str, dataclasses.Field[Any]]:
    return {f.name: f for f in dataclasses.fields(cls) if f.name != "sim_params"}


def _flatten(obj: Any, prefix: str = "") -> dict[str, Any]:
    out: dict[str, Any] = {}
    for name in _fields(type(obj)):
        value = getattr(obj, name)
        if dataclasses.is_dataclass(value):
            out.update(_flatten(value, f"{prefix}{name}."))
        else:
            out[f"{prefix}{name}"] = list(value) if isinstance(value, tuple) else value
    return out


def param_names(cls: type = EnvConfig, prefix: str = "") -> dict[str, type]:
    """Every dotted parameter of ``cls`` and its Python type."""
    hints = typing.get_type_hints(cls)
    out: dict[str, type] = {}
    for name in _fields(cls):
        kind = hints[name]
        if dataclasses.is_dataclass(kind):
            out.update(param_names(kind, f"{prefix}{name}."))  # type: ignore[arg-type]
        else:
            out[f"{prefix}{name}"] = kind
    return out


def _coerce(key: str, kind: Any, value: Any) -> Any:
    """``value`` as ``kind`` (int → float where a float is wanted), else ``ConfigError``."""
    origin = typing.get_origin(kind)
    if origin in (tuple, types.GenericAlias) or kind is tuple or origin is tuple:
        item = typing.get_args(kind)[0] if typing.get_args(kind) else Any
        require(isinstance(value, (list, tuple)), key, value, "a list")
        return tuple(_coerce(f"{key}[{i}]", item, v) for i, v in enumerate(value))
    if kind is bool:
        require(isinstance(value, bool), key, value, "true or false")
        return value
    if kind is int:
        require(isinstance(value, int) and not isinstance(value, bool), key, value, "an integer")
        return value
    if kind is float:
        ok = isinstance(value, (int, float)) and not isinstance(value, bool)
        require(ok, key, value, "a number")
        return float(value)
    if kind is str:
        require(isinstance(value, str), key, value, "a string")
        return value
    return value


def _build(cls: type, params: Mapping[str, Any], prefix: str) -> Any:
    hints = typing.get_type_hints(cls)
    kwargs: dict[str, Any] = {}
    for name in _fields(cls):
        kind = hints[name]
        key = f"{prefix}{name}"
        if dataclasses.is_dataclass(kind):
            kwargs[name] = _build(kind, params, f"{key}.")  # type: ignore[arg-type]
        elif key in params:
            kwargs[name] = _coerce(key, kind, params[key])
    return cls(**kwargs)


def flatten_params(data: Mapping[str, Any], prefix: str = "") -> dict[str, Any]:
    """Nested mappings as dotted names, as ROS 2 reads ``ros__parameters``."""
    out: dict[str, Any] = {}
    for key, value in data.items():
        name = f"{prefix}{key}"
        if isinstance(value, Mapping):
            out.update(flatten_params(value, f"{name}."))
        else:
            out[name] = value
    return out


def dataclass_from_params(cls: type[T], params: Mapping[str, Any], *, where: str) -> T:
    """A frozen config dataclass ``cls`` from dotted (or nested) parameters; an unknown key is
    an error naming ``where`` ("nav_env parameters") with a "did you mean"."""
    flat = flatten_params(params)
    known = param_names(cls)
    for key in sorted(flat):
        if key not in known:
            raise unknown_key(key, known, where=where)
    return _build(cls, flat, "")  # type: ignore[no-any-return]


def dataclass_params(obj: Any) -> dict[str, Any]:
    """The flat dotted parameters of a config dataclass (lists for tuples)."""
    return _flatten(obj)


def env_config_from_params(params: Mapping[str, Any], *,
                           sim_params: Mapping[str, Any] | None = None) -> EnvConfig:
    """An ``EnvConfig`` from dotted (or nested) parameters; unknown keys are errors."""
    config = dataclass_from_params(EnvConfig, params, where=f"{ENV_NODE} parameters")
    return dataclasses.replace(config, sim_params=dict(sim_params or {}))


# -- parameter files --------------------------------------------------------------------------


def node_section(data: Mapping[str, Any], node: str, *, source: str) -> dict[str, Any] | None:
    """The flat ``ros__parameters`` of the first section for ``node`` (``node``, ``/node``,
    ``/**/node``), or ``None`` when the file has none."""
    for key in (node, f"/{node}", f"/**/{node}"):
        if key in data:
            section = data[key]
            params = section.get("ros__parameters") if isinstance(section, Mapping) else None
            if not isinstance(params, Mapping):
                raise ConfigError(f"{source}: section {key!r} needs a 'ros__parameters' mapping")
            return flatten_params(params)
    return None


def read_params_file(path: str | Path) -> Mapping[str, Any]:
    """The node sections of a ROS 2 parameter YAML, or ``ConfigError`` naming the file."""
    path = Path(path)
    try:
        data = yaml.safe_load(path.read_text())
    except OSError as err:
        raise ConfigError(f"{path}: cannot read the config file: {err.strerror}") from err
    except yaml.YAMLError as err:
        raise ConfigError(f"{path}: not valid YAML: {err}") from err
    if not isinstance(data, Mapping):
        raise ConfigError(f"{path}: expected a mapping of node sections "
                          "(sim:, nav_env:, ...: ros__parameters: ...)")
    return data


def load_env_config(path: str | Path, *, node: str = ENV_NODE, **overrides: Any) -> EnvConfig:
    """Read ``path``: the env's section (``node``) and the sim's (``sim``; a sim-only file's
    ``/**`` section counts as the sim's), then dotted ``overrides``."""
    path = Path(path)
    data = read_params_file(path)
    env = node_section(data, node, source=str(path))
    sim = node_section(data, SIM_NODE, source=str(path))
    if sim is None and "/**" in data:  # a sim-only file such as config/sim_indoor_jackal.yaml
        sim = node_section({"/**": data["/**"]}, "/**", source=str(path))
    if env is None and sim is None:
        raise ConfigError(f"{path}: no section for {node!r} or {SIM_NODE!r} "
                          f"(expected '{node}: ros__parameters: ...')")
    try:
        return env_config_from_params({**(env or {}), **overrides}, sim_params=sim or {})
    except ConfigError as err:
        raise ConfigError(f"{path}: {err}") from err
