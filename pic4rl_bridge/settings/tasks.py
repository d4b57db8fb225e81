"""The tasks: each declares here, in one entry, its env ids, the sensors it observes, its
config (its own reward scales, and its own section if it has one) and the experts that label
its states for imitation (the baselines name the tasks they drive in their own table,
``pic4rl_bridge.baselines.registry.BASELINE_TABLE``).

``TaskName``, ``SensorName``, ``make_task``, ``pic4rl_bridge.ENV_IDS``, imitation's experts and
the env's per-task choices derive from ``TASK_TABLE``. Pure dataclasses (no numpy, no ROS), so that
``import pic4rl_bridge`` registers the ids without importing a task's code, which
``TaskSpec.build`` names by string, as Gymnasium's entry points do. A user's package adds a
task without editing this table: its ``TaskSpec`` named in the entry-point group
``pic4rl.tasks`` (``pic4rl_base.plugins``), its code named by the spec's ``build``.

A params file keeps one ``reward:`` section: ``RewardConfig`` is every task's reward class
at once (each a subclass of ``CommonReward``), and a task reads only its own class's scales.
"""

from __future__ import annotations

import importlib
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

from pic4rl_base.plugins import load_group
from pic4rl_base.schema import NON_NEGATIVE, POSITIVE, ParamEnum, param, section

from ..errors import ConfigError, require
from .baselines import DwaConfig
from .observations import OBSERVED_TABLE


@dataclass(frozen=True)
class CommonReward:
    """The scales every task pays; each term is reported in ``info["reward_terms"]``."""

    collision: float = param(-150.0, doc="every task: the collision that ends the episode (r_c)")
    step: float = param(0.0, doc="every task: added each step (a time penalty when < 0)")


# -- goToPose ----------------------------------------------------------------------------------


class GoalInput(ParamEnum):
    GOAL = "goal"
    PLAN = "plan"
    EXPLORER = "explorer"
    UWB = "uwb"


@dataclass(frozen=True)
class GoToPoseReward(CommonReward):
    goal: float = param(1000.0, doc="goToPose: reaching the goal (the paper's r_g)")
    distance: float = param(1.0, doc="goToPose: times d_{t-1} - d_t (m), the paper's dense r_d")
    heading: float = param(0.0, doc="goToPose: times (1 - 2 sqrt(|goal angle| / pi)) (the "
                           "original code)")
    proximity: float = param(0.0, doc="goToPose: times max(0, 1 - clearance / "
                             "proximity_range_m)")
    proximity_range_m: float = param(0.5, doc="goToPose: clearance from which proximity starts",
                                     unit="m", range=POSITIVE)


# -- vineyard ----------------------------------------------------------------------------------


@dataclass(frozen=True)
class VineyardReward(CommonReward):
    progress: float = param(10.0, doc="vineyard: times the advance along the row (m)")
    centering: float = param(1.0, doc="vineyard: times -|offset from the row's centre line| (m)")
    row_end: float = param(100.0, doc="vineyard: reaching the row's end")


@dataclass(frozen=True)
class VineyardConfig:
    end_tolerance_m: float = param(0.5, doc="the row ends when this close to its last point "
                                   "(along it)", unit="m", range=NON_NEGATIVE)
    max_offset_m: float = param(0.9, doc="the row's end counts only this close to its centre "
                                "line: farther, the robot drove down another lane (half the "
                                "narrowest lane)", unit="m", range=POSITIVE)
    centerline: tuple[float, ...] = param((), doc="x0, y0, x1, y1, ... (m); empty: the world's "
                                          "lanes")

    def __post_init__(self) -> None:
        line = self.centerline
        require(len(line) == 0 or (len(line) >= 4 and len(line) % 2 == 0),
                "vineyard.centerline", line, "[] or x0, y0, x1, y1, ... (two or more points)")


# -- personMonitoring --------------------------------------------------------------------------


class PersonControl(ParamEnum):
    """personMonitoring: ``end_to_end``: the agent gives (vx, vy, ω); ``hybrid``: DWA gives
    (vx, vy), following the person and avoiding obstacles, and the agent only ω (Eirale et
    al. 2022)."""

    END_TO_END = "end_to_end"
    HYBRID = "hybrid"


@dataclass(frozen=True)
class PersonReward(CommonReward):
    facing: float = param(1.0, doc="personMonitoring: times cos(angle between heading and "
                          "person)")
    person_distance: float = param(0.5, doc="personMonitoring: times -|distance - desired "
                                   "distance| (m)")
    bearing: float = param(0.0, doc="personMonitoring: times -|bearing of the person| (rad): "
                           "sharper near 0 than facing's cos")


@dataclass(frozen=True)
class PersonConfig:
    distance_m: float = param(2.0, doc="desired distance to the person", unit="m",
                              range=NON_NEGATIVE)
    control: PersonControl = param(PersonControl.END_TO_END, doc="end_to_end (the agent gives "
                                   "vx, vy, yaw rate) | hybrid (DWA gives vx, vy following the "
                                   "person, the agent the yaw rate)")
    dwa: DwaConfig = section(DwaConfig, "The DWA that follows the person: the translation of "
                             "a hybrid env, and the dwa_heading baseline's")

    def __post_init__(self) -> None:
        self.dwa.check_as("person.dwa.")


# -- explore ------------------------------------------------------------------------------------


@dataclass(frozen=True)
class ExploreReward(CommonReward):
    area: float = param(1.0, doc="explore: times the area newly seen this step (m², the "
                        "episode's seen grid)")


@dataclass(frozen=True)
class ExploreConfig:
    coverage_target: float = param(0.9, doc="the episode ends (a goal) once the area seen "
                                   "reaches this share of the world's free area; 0: only at "
                                   "the time budget or a collision (a real robot: the world "
                                   "unknown)", range=NON_NEGATIVE)
    crop_px: int = param(8, doc="the observation's seen-grid crop: this many pixels a side, "
                         "round the robot, heading up", range=POSITIVE)
    crop_cell_m: float = param(1.0, doc="the crop's pixel size", unit="m", range=POSITIVE)

    def __post_init__(self) -> None:
        require(self.coverage_target <= 1.0, "explore.coverage_target", self.coverage_target,
                "a share in [0, 1]")


# -- the registry ------------------------------------------------------------------------------


@dataclass(frozen=True)
class EnvId:
    """A registered Gymnasium id: its sensor, sim parameters for keys a config's sim section
    leaves unset, and the sensors it observes together (the env's ``sensors``; empty: its
    ``sensor`` alone)."""

    id: str
    sensor: str
    sim_defaults: Mapping[str, Any] = field(default_factory=dict)
    sensors: tuple[str, ...] = ()


@dataclass(frozen=True)
class TaskSpec:
    """One task. ``sensors``: the ``sensor`` values it observes through (the first its
    default); ``reward``: its scales' class; ``section``: its own ``nav_env`` section (name,
    class), if any; ``experts``: the ``imitation.expert`` names that label its states;
    ``build``: ``"module:function"`` making the task from ``(config, robot, world)``;
    ``uses_world``: it reads the simulated world (the vineyard's lanes); ``judges_world``: only
    its judgement reads it, not its observation (explore: the free area to cover), so it may
    draw a world per episode (the env hands it each episode's); ``per_sensor``: its
    bags' task fact names the sensor (``goToPose/lidar``); ``headline``: the outcome that is
    the task's normal good end and its words in a test's table (personMonitoring has no goal:
    its episodes should last the time budget, ``timeout``, without a collision)."""

    name: str
    env_ids: tuple[EnvId, ...]
    sensors: tuple[str, ...]
    reward: type[CommonReward]
    build: str
    experts: tuple[str, ...] = ()
    section: tuple[str, type] | None = None
    uses_world: bool = False
    judges_world: bool = False
    per_sensor: bool = False
    headline: tuple[str, str] = ("goal", "goals")

    def __post_init__(self) -> None:
        for env in self.env_ids:
            for sensor in (env.sensor, *env.sensors):
                if sensor not in self.sensors:
                    raise ConfigError(f"task {self.name!r}: id {env.id!r} observes through "
                                      f"{sensor!r}; expected one of {', '.join(self.sensors)}")

    def make(self, config: Any, robot: Any, world: Any) -> Any:
        """The task for ``config`` (its code imported now, not at registration)."""
        module, _, attr = self.build.partition(":")
        return getattr(importlib.import_module(module), attr)(config, robot, world)

    def fact_name(self, sensor: str) -> str:
        """The task as its bags' facts name it."""
        return f"{self.name}/{sensor}" if self.per_sensor else self.name


TASK_TABLE: dict[str, TaskSpec] = {spec.name: spec for spec in (
    TaskSpec("goToPose",
             (EnvId("pic4rl/GoToPoseLidar-v0", "lidar"),
              EnvId("pic4rl/GoToPoseDepth-v0", "depth", {"depth.enabled": True}),
              EnvId("pic4rl/GoToPoseLidarDepth-v0", "lidar", {"depth.enabled": True},
                    sensors=("lidar", "depth"))),
             sensors=tuple(OBSERVED_TABLE), reward=GoToPoseReward,
             build="pic4rl_bridge.tasks.goto:build",
             experts=("planner", "explorer", "predictive"), per_sensor=True),
    TaskSpec("vineyard",
             (EnvId("pic4rl/Vineyard-v0", "depth",
                    {"world": "vineyard", "depth.enabled": True}),),
             sensors=("depth",), reward=VineyardReward,
             build="pic4rl_bridge.tasks.vineyard:build",
             experts=("centerline",),
             section=("vineyard", VineyardConfig), uses_world=True,
             headline=("goal", "row ends")),
    TaskSpec("personMonitoring",
             (EnvId("pic4rl/PersonMonitoring-v0", "lidar", {"robot": "omni", "world": "person"}),),
             sensors=("lidar",), reward=PersonReward,
             build="pic4rl_bridge.tasks.person:build",
             experts=("dwa_heading",), section=("person", PersonConfig),
             headline=("timeout", "full runs")),
    TaskSpec("explore",
             (EnvId("pic4rl/ExploreLidar-v0", "lidar"),
              EnvId("pic4rl/ExploreDepth-v0", "depth", {"depth.enabled": True})),
             sensors=("lidar", "depth"), reward=ExploreReward,
             build="pic4rl_bridge.tasks.explore:build",
             section=("explore", ExploreConfig), judges_world=True, per_sensor=True,
             headline=("goal", "covered")),
)}
#: A user's tasks: each a ``TaskSpec`` that its package names in this entry-point group under
#: the task's name; read before anything below derives from the table.
TASK_GROUP = "pic4rl.tasks"
TASK_TABLE.update(load_group(TASK_GROUP, TaskSpec, taken=TASK_TABLE))

#: The task choice of ``nav_env``'s ``task`` key, one value per registered task.
TaskName = ParamEnum("TaskName", {name: name for name in TASK_TABLE})  # type: ignore[misc]
#: The ``sensor`` choice: every sensor a task observes through, in the table's order.
SensorName = ParamEnum("SensorName",  # type: ignore[misc]
                       {s: s for spec in TASK_TABLE.values() for s in spec.sensors})
#: Each ``imitation.expert`` name → the task it labels.
EXPERT_TASKS = {name: spec.name for spec in TASK_TABLE.values() for name in spec.experts}


def _reward_class() -> type:
    """Every task's reward class at once: the ``reward:`` section a params file writes."""
    # Reversed: a dataclass collects fields from its last base first; the table follows TASK_TABLE.
    bases = tuple(dict.fromkeys(spec.reward for spec in reversed(TASK_TABLE.values())))
    cls = type("RewardConfig", bases, {"__doc__": "Reward scales; each term is reported in "
                                                  "``info[\"reward_terms\"]``.",
                                       "__module__": __name__})
    return dataclass(frozen=True)(cls)


RewardConfig = _reward_class()


def env_ids() -> dict[str, dict[str, Any]]:
    """Every registered id → the ``NavEnv`` keyword arguments that make it."""
    out: dict[str, dict[str, Any]] = {}
    for spec in TASK_TABLE.values():
        for env in spec.env_ids:
            kwargs: dict[str, Any] = {"task": spec.name, "sensor": env.sensor}
            if env.sim_defaults:
                kwargs["sim_defaults"] = dict(env.sim_defaults)
            if env.sensors:
                kwargs["sensors"] = list(env.sensors)
            out[env.id] = kwargs
    return out


def task_spec(name: str) -> TaskSpec:
    """The entry of task ``name`` (``ConfigError`` naming the registered ones)."""
    if name not in TASK_TABLE:
        raise ConfigError(f"task: {name!r} is invalid; expected one of {', '.join(TASK_TABLE)}")
    return TASK_TABLE[name]

