"""The env's configuration: typed, frozen, read from the same ROS 2 parameter YAML as the nodes.

A config file holds one section per node, as ``--params-file`` expects::

    sim:                       # the sim node's parameters (pic4rl-sim reads this section)
      ros__parameters: {robot: jackal, world: indoor, ...}
    nav_env:                   # the env's parameters (this module)
      ros__parameters: {task: goToPose, sensor: lidar, reward: {goal: 1000.0}, ...}

Nested mappings are dotted names, as in ROS (``reward.goal``). Each field carries its
description, unit and range (``pic4rl_base.schema``), from which come the checks, the docs'
table and the ``--help`` text; ``pic4rl_base.params_file`` reads the sections. The in-process
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

from pic4rl_base import params_file
from pic4rl_base.goal import GOAL_TOLERANCE_M
from pic4rl_base.params_file import ENV_NODE, SIM_NODE
from pic4rl_base.schema import (NON_NEGATIVE, POSITIVE, ParamEnum, check, flatten, from_params,
                                param, section, to_params)
from pic4rl_metrics.contract import STORAGES
from pic4rl_sim.engine.sampling import PAIR_KINDS, check_pair_filter
from pic4rl_sim.interfaces import CMD_VEL, GOAL_POSE, ODOM, RECORDED

from .errors import ConfigError, require
from .readings.sensor_table import READING_TABLE
from .settings.baselines import PREFIX as BASELINES_PREFIX
from .settings.baselines import ExplorerConfig
from .settings.observations import (OBSERVED_TABLE, DepthObsConfig, LidarObsConfig,
                                     MemoryObsConfig, SonarObsConfig, StereoObsConfig)
from .settings.tasks import (TASK_TABLE, ExploreConfig, GoalInput, PersonConfig, RewardConfig,
                             SensorName, TaskName, VineyardConfig)


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
    world_variants: str = param("", doc="a world per episode: the sim's world_variant drawn "
                                "for each from these (comma-separated, each N or START:STOP"
                                "[:STEP], Python's range); empty: the sim's own")

    def __post_init__(self) -> None:
        check(self, "episodes.")
        check_pair_filter(self.min_distance_m, self.max_distance_m or math.inf,
                          self.max_detour or math.inf, prefix="episodes.")  # 0: the kind's


def _topics_config() -> type:
    """The ``topics:`` section: the command, pose and goal topics, then one per frame sensor
    (``READING_TABLE``: its sim topic, and its doc), so that a new sensor needs no field here."""
    fields = [
        ("cmd_vel", str, param(CMD_VEL.name, doc=f"velocity commands ({CMD_VEL.type} or "
                                                 "TwistStamped)")),
        ("pose", str, param(ODOM.name, doc=f"odom (wheel odometry) | ground_truth, or any "
                                           f"{ODOM.type} topic")),
        ("goal", str, param(GOAL_POSE.name, doc=GOAL_POSE.type)),
        *((s.name, str, param(s.default_topic, doc=s.topic_doc)) for s in READING_TABLE),
    ]
    return dataclasses.make_dataclass(
        "TopicsConfig", fields, frozen=True,
        namespace={"__module__": __name__,
                   "__doc__": "Topic names, relative to ``ros.namespace`` unless absolute."})


TopicsConfig = _topics_config()


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
    max_sensor_age_s: float = param(0.0, doc="rate mode: a needed topic silent this long stops "
                                    "the robot and aborts the episode; 0: 5 control periods",
                                    unit="s", range=NON_NEGATIVE)


@dataclass(frozen=True)
class RecordConfig:
    """Episode bags: ``<bags_dir>/<run>/<episode>/``, the run's config beside them."""

    enabled: bool = param(False, doc="record each episode to a bag")
    bags_dir: str = param("bags", doc="where runs of bags go")
    run: str = param("", doc="empty: <task>_<date>_<time>")
    storage: str = param(next(iter(STORAGES)), doc=" | ".join(STORAGES),
                         choices=tuple(STORAGES))
    topics: tuple[str, ...] = param(RECORDED, doc="topics recorded (absent ones are "
                                    "skipped)")
    flush_interval_s: float = param(1.0, doc="sqlite3: commit this often, so a killed recorder "
                                    "keeps data", unit="s", range=NON_NEGATIVE)


@dataclass(frozen=True)
class EnvConfig:
    """Everything ``NavEnv`` needs besides the simulator's own parameters (``sim_params``)."""

    task: TaskName = param(TaskName(next(iter(TASK_TABLE))), doc=" | ".join(TASK_TABLE))
    sensor: SensorName = param(SensorName(next(iter(SensorName)).value),
                               doc=" | ".join(s.value for s in SensorName))
    sensors: tuple[str, ...] = param((), doc="goToPose: the sensors observed together, each "
                                     "with its own section (lidar.*, depth.*, sonar.*, "
                                     "stereo.*), `sensor` among "
                                     "them; two or more: a Dict observation, a key each beside "
                                     "goal; empty: `sensor` alone")
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
                                  "paper's) | plan (a look-ahead point on topics.plan) | "
                                  "explorer (a look-ahead point on the mapless explorer's plan, "
                                  "made from the episode's own scans: mapless) | uwb (the goal's "
                                  "tag as the robot's UWB anchors range it: no pose used)")
    plan_lookahead_m: float = param(1.5, doc="goal_input plan or explorer: the point this far "
                                    "along the plan beyond the robot's projection on it",
                                    unit="m", range=POSITIVE)
    goal_tolerance_m: float = param(GOAL_TOLERANCE_M, doc="the goal is reached this close",
                                    unit="m", range=POSITIVE)
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
    sonar: SonarObsConfig = section(SonarObsConfig)
    stereo: StereoObsConfig = section(StereoObsConfig)
    memory: MemoryObsConfig = section(MemoryObsConfig)
    explorer: ExplorerConfig = section(ExplorerConfig, "goal_input explorer: the plan's "
                                       "settings, as the explorer baseline's (its speed limit "
                                       "unused)")
    vineyard: VineyardConfig = section(VineyardConfig)
    person: PersonConfig = section(PersonConfig)
    explore: ExploreConfig = section(ExploreConfig)
    episodes: EpisodesConfig = section(EpisodesConfig)
    topics: TopicsConfig = section(TopicsConfig)
    ros: RosConfig = section(RosConfig)
    record: RecordConfig = section(RecordConfig)
    #: The sim node's parameters (the ``sim`` section), checked by pic4rl_sim when used.
    sim_params: Mapping[str, Any] = field(default_factory=dict, compare=False)

    def __post_init__(self) -> None:
        check(self)
        known, given = [s.value for s in SensorName], list(self.sensors)
        require(set(given) <= set(known) and len(set(given)) == len(given) and (
            not given or self.sensor in given), "sensors", given, f"distinct sensors of "
            f"{', '.join(known)}, sensor ({self.sensor}: the explorer's, the memory's) among them")
        require(math.isfinite(self.min_linear_m_s) and (
            self.max_linear_m_s == 0 or self.min_linear_m_s <= self.max_linear_m_s),
            "min_linear_m_s", self.min_linear_m_s,
            f"a finite speed <= max_linear_m_s={self.max_linear_m_s}")

    @property
    def observed(self) -> tuple[str, ...]:
        """The sensors the observation holds: ``sensors``, or ``sensor`` alone."""
        return self.sensors or (self.sensor,)

    @property
    def sensor_label(self) -> str:  # bags' task fact, runs' names: lidar, lidar+depth
        return "+".join(self.observed)

    @property
    def recorded_topics(self) -> tuple[str, ...]:
        """What a bag records: ``record.topics``, then the topics of every observed sensor's
        readings that the sim does not record by default (``topics.<reading>``: the sonar ring's
        cones, the stereo camera's depth), so that every sensor an agent observes is in its
        bags."""
        kinds = {OBSERVED_TABLE[name].kind for name in self.observed}
        extra = (getattr(self.topics, s.name) for s in READING_TABLE
                 if s.kind in kinds and s.interface.record_order is None)
        return tuple(dict.fromkeys((*self.record.topics, *extra)))

    @property
    def simulated(self) -> bool:
        """Whether the env drives a pic4rl simulator: in process, or a sim node over ROS
        (``ros.sim_node``). Only then do the ``sim:`` section's world and its facts apply;
        ``transport: ros`` with ``ros.sim_node: ""`` is a real robot (or another simulator)."""
        return self.transport == TransportName.INPROCESS.value or bool(self.ros.sim_node)

    def to_params(self) -> dict[str, Any]:
        """The flat dotted parameters of this config (``sim_params`` left out)."""
        return to_params(self)

    def replace(self, **overrides: Any) -> EnvConfig:
        """A copy with dotted ``overrides`` applied (``{"reward.goal": 500.0}``)."""
        params = {**self.to_params(), **overrides}
        return env_config_from_params(params, sim_params=self.sim_params)


#: The settings that shape what a trained agent observes and what its actions do: with the
#: section of each sensor it observes (``lidar.*``, ``depth.*``), ``agent_keys`` gives them. A
#: test takes them from the agent's own config; ``pic4rl-test`` and ``pic4rl-bench`` refuse an
#: env file or override that contradicts one, or observes other sensors (``agent_conflicts``).
#: Another ``task`` gives other spaces, which the model's own space check refuses.
AGENT_KEYS = ("normalize_observations", "goal_input", "plan_lookahead_m", "max_linear_m_s",
              "min_linear_m_s", "max_angular_rad_s", "max_lateral_m_s", "person.", "explorer.")


def agent_keys(config: EnvConfig) -> tuple[str, ...]:
    """The dotted names of ``AGENT_KEYS`` (a name ending in a dot is a section) and of the
    section of each sensor ``config`` observes."""
    wanted = (*AGENT_KEYS, *(f"{s}." for s in config.observed))
    return tuple(k for k in config.to_params()
                 if any(k == w or (w.endswith(".") and k.startswith(w)) for w in wanted))


def agent_conflicts(trained: EnvConfig, test: EnvConfig) -> list[tuple[str, Any, Any]]:
    """``(key, trained value, test value)`` of every ``agent_keys`` setting ``test`` changes,
    the observed sensors first (``sensors``: ``sensor: lidar`` and ``sensors: [lidar]`` are
    alike)."""
    mine, theirs = trained.to_params(), test.to_params()
    observed = ([("sensors", list(trained.observed), list(test.observed))]
                if trained.observed != test.observed else [])
    return observed + [(k, mine[k], theirs[k]) for k in agent_keys(trained)
                       if mine[k] != theirs[k]]


def env_config_from_params(params: Mapping[str, Any], *,
                           sim_params: Mapping[str, Any] | None = None) -> EnvConfig:
    """An ``EnvConfig`` from dotted (or nested) parameters; unknown keys are errors."""
    moved = sorted(k for k in flatten(params) if k.startswith(BASELINES_PREFIX))
    if moved:
        raise ConfigError(f"{ENV_NODE} parameters: {moved[0]!r} is no env parameter: baseline "
                          f"settings are the params file's '{BASELINES_PREFIX[:-1]}:' section "
                          f"({moved[0][len(BASELINES_PREFIX):]}); the person follower's DWA is "
                          "person.dwa.*")
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
