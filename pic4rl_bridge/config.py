"""The env's configuration: typed, frozen, read from the same ROS 2 parameter YAML as the nodes.

A config file holds one section per node, as ``--params-file`` expects::

    sim:                       # the sim node's parameters (pic4rl-sim reads this section)
      ros__parameters: {robot: jackal, world: indoor, ...}
    nav_env:                   # the env's parameters (this module)
      ros__parameters: {task: goToPose, sensor: lidar, reward: {goal: 1000.0}, ...}

Nested mappings are dotted names, as in ROS (``reward.goal``). Each field carries its
description, unit and range (``pic4rl_sim.schema``), from which come the checks, the docs'
table and the ``--help`` text; ``pic4rl_sim.params_file`` reads the sections. The in-process
transport builds its engine from the ``sim`` section, so one file configures both transports
identically.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from pic4rl_sim import params_file
from pic4rl_sim.engine.sampling import PAIR_KINDS
from pic4rl_sim.interfaces import (
    CMD_VEL,
    DEPTH_IMAGE,
    GOAL_POSE,
    ODOM,
    PERSON_POSE,
    PLAN,
    RECORDED,
    SCAN,
)
from pic4rl_sim.params_file import ENV_NODE, SIM_NODE
from pic4rl_sim.schema import (
    NON_NEGATIVE,
    POSITIVE,
    ParamEnum,
    Range,
    check,
    from_params,
    param,
    section,
    to_params,
)

from .errors import ConfigError, require


class TaskName(ParamEnum):
    GO_TO_POSE = "goToPose"
    VINEYARD = "vineyard"
    PERSON_MONITORING = "personMonitoring"


class PersonControl(ParamEnum):
    """personMonitoring: ``end_to_end``: the agent gives (vx, vy, ω); ``hybrid``: DWA gives
    (vx, vy), following the person and avoiding obstacles, and the agent only ω (Eirale et
    al. 2022)."""

    END_TO_END = "end_to_end"
    HYBRID = "hybrid"


class SensorName(ParamEnum):
    LIDAR = "lidar"
    DEPTH = "depth"


class GoalInput(ParamEnum):
    GOAL = "goal"
    PLAN = "plan"


class TransportName(ParamEnum):
    INPROCESS = "inprocess"
    ROS = "ros"


class StepMode(ParamEnum):
    """``lockstep``: one ``cmd_vel`` → wait for the sensor set it causes (our sim's lockstep
    clock); ``rate``: send, wait one control period of wall time, read the latest (a real robot
    or a real-time simulator)."""

    LOCKSTEP = "lockstep"
    RATE = "rate"


class CmdVelType(ParamEnum):
    TWIST = "Twist"
    TWIST_STAMPED = "TwistStamped"


class SensorQos(ParamEnum):
    BEST_EFFORT = "best_effort"
    RELIABLE = "reliable"


class Storage(ParamEnum):
    SQLITE3 = "sqlite3"
    MCAP = "mcap"


class DepthEncoding(ParamEnum):
    UINT8 = "uint8"
    FLOAT32 = "float32"


@dataclass(frozen=True)
class RewardConfig:
    """Reward scales; each term is reported in ``info["reward_terms"]``."""

    goal: float = param(1000.0, doc="goToPose: reaching the goal (the paper's r_g)")
    collision: float = param(-150.0, doc="every task: the collision that ends the episode (r_c)")
    distance: float = param(1.0, doc="goToPose: times d_{t-1} - d_t (m), the paper's dense r_d")
    heading: float = param(0.0, doc="goToPose: times (1 - 2 sqrt(|goal angle| / pi)) (the "
                           "original code)")
    step: float = param(0.0, doc="every task: added each step (a time penalty when < 0)")
    proximity: float = param(0.0, doc="goToPose: times max(0, 1 - clearance / "
                             "proximity_range_m)")
    proximity_range_m: float = param(0.5, doc="goToPose: clearance from which proximity starts",
                                     unit="m", range=POSITIVE)
    progress: float = param(10.0, doc="vineyard: times the advance along the row (m)")
    centering: float = param(1.0, doc="vineyard: times -|offset from the row's centre line| (m)")
    row_end: float = param(100.0, doc="vineyard: reaching the row's end")
    facing: float = param(1.0, doc="personMonitoring: times cos(angle between heading and "
                          "person)")
    person_distance: float = param(0.5, doc="personMonitoring: times -|distance - desired "
                                   "distance| (m)")
    bearing: float = param(0.0, doc="personMonitoring: times -|bearing of the person| (rad): "
                           "sharper near 0 than facing's cos")


@dataclass(frozen=True)
class LidarObsConfig:
    """The LiDAR observation: ``beams`` sectors, each the minimum range in it, clipped."""

    beams: int = param(36, doc="sectors of the observation, each the minimum range in it",
                       range=POSITIVE)
    max_range_m: float = param(10.0, doc="ranges clipped here", unit="m", range=POSITIVE)


@dataclass(frozen=True)
class DepthObsConfig:
    """The depth observation: resized to ``width`` × ``height``, clipped at ``max_depth_m``;
    ``uint8`` scales [0, max_depth_m] to [0, 255] so SB3's CNN treats it as an image."""

    width: int = param(80, doc="observation width", unit="px", range=POSITIVE)
    height: int = param(60, doc="observation height", unit="px", range=POSITIVE)
    max_depth_m: float = param(5.0, doc="depths clipped here", unit="m", range=POSITIVE)
    encoding: DepthEncoding = param(DepthEncoding.UINT8, doc="uint8 (an image for SB3's CNN) or "
                                    "float32 (metres)")


@dataclass(frozen=True)
class VineyardConfig:
    end_tolerance_m: float = param(0.5, doc="the row ends when this close to its last point "
                                   "(along it)", unit="m", range=NON_NEGATIVE)
    max_offset_m: float = param(0.9, doc="the row's end counts only this close to its centre "
                                "line: farther, the robot drove down another lane (half the "
                                "narrowest lane)", unit="m", range=POSITIVE)
    centerline: tuple[float, ...] = param((), doc="x0, y0, x1, y1, ... (m); empty: the world's "
                                          "lanes")


@dataclass(frozen=True)
class PersonConfig:
    distance_m: float = param(2.0, doc="desired distance to the person", unit="m",
                              range=NON_NEGATIVE)
    control: PersonControl = param(PersonControl.END_TO_END, doc="end_to_end (the agent gives "
                                   "vx, vy, yaw rate) | hybrid (DWA gives vx, vy following the "
                                   "person, the agent the yaw rate)")


@dataclass(frozen=True)
class DwaConfig:
    """The Dynamic Window Approach baseline (``pic4rl_bridge.baselines.DwaController``). The
    velocity ranges, acceleration limits, window period and footprint are the robot's."""

    horizon_s: float = param(1.5, doc="each velocity sample is simulated this long", unit="s",
                             range=POSITIVE)
    rollout_dt_s: float = param(0.1, doc="time between the simulated poses checked against the "
                                "scan", unit="s", range=POSITIVE)
    linear_samples: int = param(7, doc="forward speeds sampled across the window (ends "
                                "included)", range=Range(2, 101))
    angular_samples: int = param(15, doc="yaw rates sampled across the window (ends included)",
                                 range=Range(2, 101))
    heading_weight: float = param(1.0, doc="times 1 - |target bearing| / pi, from the nearest "
                                  "rollout pose", range=NON_NEGATIVE)
    clearance_weight: float = param(0.4, doc="times the distance driven before a collision "
                                    "(capped)", range=NON_NEGATIVE)
    speed_weight: float = param(0.3, doc="times v / max_linear_m_s", range=NON_NEGATIVE)
    clearance_cap_m: float = param(0.6, doc="a rollout free of collisions scores this distance",
                                   unit="m", range=POSITIVE)
    lookahead_m: float = param(2.0, doc="the target is the goal if a lane is free this far, else "
                               "along the free lane nearest the goal's bearing", unit="m",
                               range=POSITIVE)
    safety_margin_m: float = param(0.05, doc="beyond collision_tolerance_m: closer poses are "
                                   "collisions", unit="m", range=NON_NEGATIVE)
    point_resolution_m: float = param(0.05, doc="scan points merged on a grid this fine",
                                      unit="m", range=POSITIVE)

    def __post_init__(self) -> None:
        check(self, "baselines.dwa.")
        require(self.rollout_dt_s <= self.horizon_s, "baselines.dwa.rollout_dt_s",
                self.rollout_dt_s, f"at most horizon_s={self.horizon_s}")


@dataclass(frozen=True)
class BaselinesConfig:
    """The classical controllers ``pic4rl-test --baseline`` runs; ``dwa`` also plans the
    translation of a hybrid personMonitoring (``person.control: hybrid``)."""

    dwa: DwaConfig = section(DwaConfig)


@dataclass(frozen=True)
class EpisodesConfig:
    """Where episodes start and end (see ``pic4rl_bridge.episodes``)."""

    file: str = param("", doc="a PIC4rl-gym goals_and_poses JSON; empty: sampled by the "
                      "simulator")
    change_goal_and_pose: int = param(1, doc="draw a new pair of the file every N episodes",
                                      range=POSITIVE)
    starting_episodes: int = param(0, doc="first N episodes: initial_pose and a random goal "
                                   "near it", range=NON_NEGATIVE)
    starting_goal_range_m: float = param(2.9, doc="... within ± this of the initial pose in x "
                                         "and y", unit="m", range=NON_NEGATIVE)
    max_attempts: int = param(20, doc="goals redrawn when the simulator rejects one",
                              range=POSITIVE)
    ordered: bool = param(False, doc="walk the file's pairs in order (PIC4rl-gym's testing "
                          "mode)")
    pair_kind: str = param("any", doc="sampled pairs (no file): a kind of "
                           "pic4rl_sim.engine.sampling.PAIR_KINDS; other than plain any, the env "
                           "draws the pair (with a path check)", choices=tuple(PAIR_KINDS))
    min_distance_m: float = param(0.0, doc="straight start-goal distance at least; 0: the "
                                  "kind's", unit="m", range=NON_NEGATIVE)
    max_distance_m: float = param(0.0, doc="... and at most; 0: the kind's", unit="m",
                                  range=NON_NEGATIVE)
    max_detour: float = param(0.0, doc="shortest collision-free path / straight line at most; "
                              "0: the kind's")

    def __post_init__(self) -> None:
        check(self, "episodes.")
        require(self.max_detour == 0 or self.max_detour >= 1, "episodes.max_detour",
                self.max_detour, "0 (the kind's) or a ratio >= 1")


@dataclass(frozen=True)
class TopicsConfig:
    """Topic names, relative to ``ros.namespace`` unless absolute."""

    cmd_vel: str = param(CMD_VEL.name, doc=f"velocity commands ({CMD_VEL.type} or "
                         "TwistStamped)")
    pose: str = param(ODOM.name, doc=f"odom (wheel odometry) | ground_truth, or any {ODOM.type} "
                      "topic")
    scan: str = param(SCAN.name, doc=SCAN.type)
    depth: str = param(DEPTH_IMAGE.name, doc=f"{DEPTH_IMAGE.type} (32FC1)")
    goal: str = param(GOAL_POSE.name, doc=GOAL_POSE.type)
    person: str = param(PERSON_POSE.name, doc=f"{PERSON_POSE.type} (personMonitoring)")
    plan: str = param(PLAN.name, doc=f"{PLAN.type}: the global plan of goal_input plan (the "
                      "sim's, or any planner's, e.g. nav2's /plan)")


@dataclass(frozen=True)
class RosConfig:
    namespace: str = param("", doc="the robot's namespace")
    domain_id: int = param(-1, doc="-1: ROS_DOMAIN_ID of the environment (or 0)")
    node_name: str = param(ENV_NODE, doc="this env's node name")
    sim_node: str = param(SIM_NODE, doc="node whose parameters set seed/start/goal; empty: none "
                          "(real robot)")
    reset_service: str = param("reset_world", doc="empty: a reset waits for a new goal on "
                               "topics.goal")
    step_mode: StepMode = param(StepMode.LOCKSTEP, doc="lockstep (our sim's lockstep clock) or "
                                "rate (a real robot or a real-time simulator)")
    cmd_vel_type: CmdVelType = param(CmdVelType.TWIST, doc="Twist | TwistStamped")
    sensor_qos: SensorQos = param(SensorQos.BEST_EFFORT, doc="best_effort (sensor data) | "
                                  "reliable")
    timeout_s: float = param(10.0, doc="waiting for a service or a message", unit="s",
                             range=POSITIVE)
    operator_timeout_s: float = param(0.0, doc="real robot: wait this long for a new goal; 0 = "
                                      "forever", unit="s", range=NON_NEGATIVE)


@dataclass(frozen=True)
class RecordConfig:
    """Episode bags: ``<bags_dir>/<run>/<episode>/``, the run's config beside them."""

    enabled: bool = param(False, doc="record each episode to a bag")
    bags_dir: str = param("bags", doc="where runs of bags go")
    run: str = param("", doc="empty: <task>_<date>_<time>")
    storage: Storage = param(Storage.SQLITE3, doc="sqlite3 | mcap")
    topics: tuple[str, ...] = param(RECORDED, doc="topics recorded (absent ones are "
                                    "skipped)")
    flush_interval_s: float = param(1.0, doc="sqlite3: commit this often, so a killed recorder "
                                    "keeps data", unit="s", range=NON_NEGATIVE)


@dataclass(frozen=True)
class EnvConfig:
    """Everything ``NavEnv`` needs besides the simulator's own parameters (``sim_params``)."""

    task: TaskName = param(TaskName.GO_TO_POSE, doc="goToPose | vineyard | personMonitoring")
    sensor: SensorName = param(SensorName.LIDAR, doc="lidar | depth")
    transport: TransportName = param(TransportName.INPROCESS, doc="inprocess (the engine in "
                                     "this process) | ros (topics and services)")
    agent: str = param("", doc="the agent's name, recorded in each bag")
    robot: str = param("", doc="empty: the sim section's robot; else a built-in name or robot "
                       "YAML")
    episode_max_steps: int = param(500, doc="steps before an episode is truncated",
                                   range=POSITIVE)
    normalize_observations: bool = param(False, doc="goToPose: ranges and goal distance in "
                                         "[0, 1], angle / pi")
    goal_input: GoalInput = param(GoalInput.GOAL, doc="goToPose: what the goal part of the "
                                  "observation points at: goal (the final goal, mapless: the "
                                  "paper's) | plan (a look-ahead point on topics.plan)")
    plan_lookahead_m: float = param(1.5, doc="goal_input plan: the point this far along the "
                                    "plan beyond the robot's projection on it", unit="m",
                                    range=POSITIVE)
    goal_tolerance_m: float = param(0.4, doc="the goal is reached this close", unit="m",
                                    range=POSITIVE)
    collision_tolerance_m: float = param(0.05, doc="a scan point this close to the footprint is "
                                         "a collision", unit="m", range=NON_NEGATIVE)
    warning_tolerance_m: float = param(0.1, doc="closer than this (beyond the collision "
                                       "tolerance) is a near miss", unit="m",
                                       range=NON_NEGATIVE)
    collision_steps: int = param(1, doc="consecutive collision steps that end an episode "
                                 "(original: 3)", range=POSITIVE)
    max_linear_m_s: float = param(0.0, doc="0: the robot's limit", unit="m/s",
                                  range=NON_NEGATIVE)
    min_linear_m_s: float = param(0.0, doc="differential drive; the paper's: 0 (omni: "
                                  "-max_linear)", unit="m/s")
    max_angular_rad_s: float = param(0.0, doc="0: the robot's limit", unit="rad/s",
                                     range=NON_NEGATIVE)
    max_lateral_m_s: float = param(0.0, doc="omni robots; 0: the robot's limit", unit="m/s",
                                   range=NON_NEGATIVE)
    control_dt_s: float = param(0.0, doc="0: the sim section's control_dt_s (rate mode's "
                                "period)", unit="s", range=NON_NEGATIVE)
    reward: RewardConfig = section(RewardConfig)
    lidar: LidarObsConfig = section(LidarObsConfig)
    depth: DepthObsConfig = section(DepthObsConfig)
    vineyard: VineyardConfig = section(VineyardConfig)
    person: PersonConfig = section(PersonConfig)
    episodes: EpisodesConfig = section(EpisodesConfig)
    topics: TopicsConfig = section(TopicsConfig)
    ros: RosConfig = section(RosConfig)
    record: RecordConfig = section(RecordConfig)
    baselines: BaselinesConfig = section(BaselinesConfig)
    #: The sim node's parameters (the ``sim`` section), checked by pic4rl_sim when used.
    sim_params: Mapping[str, Any] = field(default_factory=dict, compare=False)

    def __post_init__(self) -> None:
        check(self)
        require(math.isfinite(self.min_linear_m_s) and (
            self.max_linear_m_s == 0 or self.min_linear_m_s <= self.max_linear_m_s),
            "min_linear_m_s", self.min_linear_m_s,
            f"a finite speed <= max_linear_m_s={self.max_linear_m_s}")
        line = self.vineyard.centerline
        require(len(line) == 0 or (len(line) >= 4 and len(line) % 2 == 0),
                "vineyard.centerline", line, "[] or x0, y0, x1, y1, ... (two or more points)")

    def to_params(self) -> dict[str, Any]:
        """The flat dotted parameters of this config (``sim_params`` left out)."""
        return to_params(self)

    def replace(self, **overrides: Any) -> EnvConfig:
        """A copy with dotted ``overrides`` applied (``{"reward.goal": 500.0}``)."""
        params = {**self.to_params(), **overrides}
        return env_config_from_params(params, sim_params=self.sim_params)


def env_config_from_params(params: Mapping[str, Any], *,
                           sim_params: Mapping[str, Any] | None = None) -> EnvConfig:
    """An ``EnvConfig`` from dotted (or nested) parameters; unknown keys are errors."""
    config = from_params(EnvConfig, params, where=f"{ENV_NODE} parameters")
    return dataclasses.replace(config, sim_params=dict(sim_params or {}))


def load_env_config(path: str | Path, *, node: str = ENV_NODE, **overrides: Any) -> EnvConfig:
    """Read ``path``: the env's section (``node``) and the sim's (``sim``; a sim-only file's
    ``/**`` section counts as the sim's), then dotted ``overrides``. A relative
    ``episodes.file`` is found as ``params_file`` finds it, whoever loads the file."""
    sections = params_file.load([path], (node, SIM_NODE))
    try:
        return env_config_from_params({**sections[node], **overrides},
                                      sim_params=sections[SIM_NODE])
    except ConfigError as err:
        raise ConfigError(f"{path}: {err}") from err
