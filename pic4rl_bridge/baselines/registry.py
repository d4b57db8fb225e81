"""Classical references, run by ``pic4rl-test --baseline NAME`` like an agent; goToPose's
here, the vineyard's row followers in ``row_followers`` and the person follower's heading law
in ``follow``. ``BASELINE_TABLE`` is the one place a baseline is registered: the tasks it
drives, how it is made and the imitation expert it is, if any (``BASELINES``,
``BASELINE_TASKS``, ``--baseline``, the suites' checks and ``make_expert`` follow). A user's
package adds its own without editing it: a ``BaselineSpec`` named in the entry-point group
``pic4rl.baselines`` (``pic4rl_base.plugins``; ``docs/extending.md``).

- ``proportional``: turns toward the goal and drives when facing it, with no obstacle
  avoidance: the simplest baseline a learned policy should beat among obstacles, and a check
  that the env, transport and recorder work end to end (it reaches any goal in open space).
- ``dwa``: the Dynamic Window Approach (``pic4rl_bridge.baselines.dwa``), the local planner that
  nav2 and the BARN challenge compare learned planners with.
- ``planner``: the privileged planner (``pic4rl_bridge.baselines.planner``): the world's shortest
  path with a clearance margin, followed by pure pursuit; it knows the map, no agent does.
- ``predictive``: the privileged planner with its speed timed against the moving obstacles
  it tracks from the scan and predicts (``PredictiveController`` in
  ``pic4rl_bridge.baselines.planner``): the motion-aware reference for the dynamic BARN.
- ``explorer``: the mapless explorer (``pic4rl_bridge.baselines.explorer``): the shortest path on an
  occupancy grid of its own scans (unknown space free), kept until a new obstacle blocks it,
  followed by the planner's pursuit law; it knows no map, as no agent does. In a depth env it
  sees what a depth agent sees: the depth image's pseudo-scan.
- ``dwa_heading`` (personMonitoring): DWA follows the person and a proportional law on its
  bearing turns the base (``pic4rl_bridge.baselines.follow``): the classical version of the RL-DWA
  hybrid.
- ``orca``: Optimal Reciprocal Collision Avoidance (``pic4rl_bridge.baselines.orca``), the
  velocity-obstacle reference for crowds: the people of the ``people`` reading (their
  velocities by finite difference) and the scan's nearest returns as half-planes of
  velocities, goal-seeking otherwise.
- ``frontier`` and ``random_walk`` (explore): Yamauchi's frontier-based exploration on the
  robot's own grids and a random-walk floor (``pic4rl_bridge.baselines.exploration``).

The first two and ``explorer`` are pure numpy over the env's decoded frame (pose, goal, scan): no
ROS, no simulator.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Protocol

import numpy as np

from pic4rl_base.geometry import wrap_angle
from pic4rl_base.plugins import load_group

from ..config import EnvConfig
from ..control.actions import normalized_action
from ..errors import ConfigError
from ..readings.frame import SensorFrame
from ..robot_info import RobotInfo
from ..settings.baselines import BaselinesConfig
from ..settings.tasks import EXPERT_TASKS
from .dwa import DwaController

if TYPE_CHECKING:
    from pic4rl_sim.engine.worlds.spec import WorldSpec


def _bearing(dx: float, dy: float, yaw: float) -> float:
    """The angle (rad, in [-pi, pi)) of the vector (dx, dy) seen from heading ``yaw``."""
    return wrap_angle(math.atan2(dy, dx) - yaw)


class Baseline(Protocol):
    """A classical controller: ``reset`` at each episode's start, then one ``action`` (the
    goToPose normalised action) per frame."""

    def reset(self) -> None: ...

    def action(self, frame: SensorFrame) -> np.ndarray: ...


class GoToGoalController:
    """Normalized goToPose actions ([-1, 1]²) from the robot's pose and the goal:
    ω = ``turn_gain`` × bearing, v = ``speed_gain`` × distance × cos⁴(bearing), clipped to the
    robot's ranges (m/s, rad/s)."""

    def __init__(self, robot: RobotInfo, *, turn_gain: float = 2.0,
                 speed_gain: float = 1.0) -> None:
        self.robot = robot
        self.turn_gain = turn_gain
        self.speed_gain = speed_gain

    def reset(self) -> None:
        """Nothing to forget: the controller keeps no state."""

    def action(self, frame: SensorFrame) -> np.ndarray:
        if frame.goal is None:
            raise ValueError("GoToGoalController: the frame has no goal")
        r = self.robot
        dx, dy = frame.goal[0] - frame.pose.x, frame.goal[1] - frame.pose.y
        bearing = _bearing(dx, dy, frame.pose.yaw)
        w = float(np.clip(self.turn_gain * bearing, -r.max_angular_rad_s, r.max_angular_rad_s))
        v = self.speed_gain * math.hypot(dx, dy) * max(0.0, math.cos(bearing)) ** 4
        v = float(np.clip(v, r.min_linear_m_s, r.max_linear_m_s))
        return normalized_action(r, v, w)


def _dwa(config: EnvConfig, robot: RobotInfo, world: WorldSpec | None,
         settings: BaselinesConfig) -> Baseline:
    return DwaController(robot, settings.dwa, collision_tolerance_m=config.collision_tolerance_m)


def _map(name: str, world: WorldSpec | None) -> WorldSpec:
    """``world``, or ``ConfigError`` for baseline ``name`` when there is none."""
    if world is None:
        raise ConfigError(f"--baseline {name}: it plans on the simulated world's map, and "
                          "this env has none (no 'sim:' section: a real robot)")
    return world


def _planner(config: EnvConfig, robot: RobotInfo, world: WorldSpec | None,
             settings: BaselinesConfig) -> Baseline:
    from .planner import PlannerController

    return PlannerController(robot, _map("planner", world), **dataclasses.asdict(settings.planner))


def _predictive(config: EnvConfig, robot: RobotInfo, world: WorldSpec | None,
                settings: BaselinesConfig) -> Baseline:
    from .planner import PredictiveController

    planner = {**dataclasses.asdict(settings.planner), **dataclasses.asdict(settings.predictive)}
    return PredictiveController(robot, _map("predictive", world), **planner)


def _explorer(config: EnvConfig, robot: RobotInfo, world: WorldSpec | None,
              settings: BaselinesConfig) -> Baseline:
    from .explorer import ExplorerController

    return ExplorerController.for_env(robot, config, settings.explorer)


def _orca(config: EnvConfig, robot: RobotInfo, world: WorldSpec | None,
          settings: BaselinesConfig) -> Baseline:
    from .orca import OrcaController

    return OrcaController(robot)


def _row_follower(name: str) -> Callable[..., Baseline]:
    def make(config: EnvConfig, robot: RobotInfo, world: WorldSpec | None,
             settings: BaselinesConfig) -> Baseline:
        from .row_followers import make_row_follower

        return make_row_follower(name, config, robot, world)
    return make


def _frontier(config: EnvConfig, robot: RobotInfo, world: WorldSpec | None,
              settings: BaselinesConfig) -> Baseline:
    from .exploration import FrontierExplorer

    return FrontierExplorer(robot, settings.explorer)


def _random_walk(config: EnvConfig, robot: RobotInfo, world: WorldSpec | None,
                 settings: BaselinesConfig) -> Baseline:
    from .exploration import RandomWalk

    return RandomWalk(robot)


def _heading(config: EnvConfig, robot: RobotInfo, world: WorldSpec | None,
             settings: BaselinesConfig) -> Baseline:
    from .follow import HeadingController

    return HeadingController(config, robot)


@dataclass(frozen=True)
class BaselineSpec:
    """One baseline: the tasks it drives (``TASK_TABLE``' names) and what makes it from the env's
    config, the robot, the simulated world (``None`` on a real robot) and the ``baselines:``
    section's settings; ``one_world``: it drives on one world's map (refused when the env
    draws a world per episode)."""

    tasks: tuple[str, ...]
    make: Callable[[EnvConfig, RobotInfo, WorldSpec | None, BaselinesConfig], Baseline]
    one_world: bool = False
    #: The ``imitation.expert`` name (a ``TASK_TABLE`` entry's ``experts``) under which it labels
    #: states for imitation; empty: no expert.
    expert: str = ""


BASELINE_TABLE: dict[str, BaselineSpec] = {
    "proportional": BaselineSpec(("goToPose",), lambda c, robot, w, s: GoToGoalController(robot)),
    "dwa": BaselineSpec(("goToPose",), _dwa),
    "planner": BaselineSpec(("goToPose",), _planner, one_world=True, expert="planner"),
    "predictive": BaselineSpec(("goToPose",), _predictive, one_world=True,
                               expert="predictive"),
    "explorer": BaselineSpec(("goToPose",), _explorer, expert="explorer"),
    "orca": BaselineSpec(("goToPose",), _orca),
    "centerline": BaselineSpec(("vineyard",), _row_follower("centerline"), one_world=True,
                               expert="centerline"),
    "row_follower": BaselineSpec(("vineyard",), _row_follower("row_follower"), one_world=True),
    "dwa_heading": BaselineSpec(("personMonitoring",), _heading, expert="dwa_heading"),
    "frontier": BaselineSpec(("explore",), _frontier),
    "random_walk": BaselineSpec(("explore",), _random_walk),
}
#: A user's baselines: each a ``BaselineSpec`` that its package names in this entry-point group.
BASELINE_GROUP = "pic4rl.baselines"
BASELINE_TABLE.update(load_group(BASELINE_GROUP, BaselineSpec, taken=BASELINE_TABLE))
#: Each imitation expert (``EXPERT_TASKS``' names) → the baseline that labels under it.
EXPERT_BASELINES = {spec.expert: name for name, spec in BASELINE_TABLE.items() if spec.expert}
#: Each baseline → the tasks it drives.
BASELINE_TASKS = {name: spec.tasks for name, spec in BASELINE_TABLE.items()}
BASELINES = tuple(BASELINE_TABLE)


def make_baseline(name: str, config: EnvConfig, robot: RobotInfo,
                  world: WorldSpec | None = None,
                  settings: BaselinesConfig | None = None) -> Baseline:
    """The baseline ``name`` for an env of ``config`` and ``robot`` (``planner``: on the
    simulated ``world``; ``centerline``: on its lanes or ``vineyard.centerline``), with the
    ``baselines:`` section's ``settings`` (defaults when ``None``); ``ConfigError`` when it
    does not fit (before anything runs)."""
    if name not in BASELINES:
        raise ConfigError(f"--baseline {name!r}: expected one of {', '.join(BASELINES)}")
    check_fits(name, config)
    return BASELINE_TABLE[name].make(config, robot, world, settings or BaselinesConfig())


def check_fits(name: str, config: EnvConfig) -> None:
    """``ConfigError`` unless baseline ``name`` can drive ``config``'s task (``BASELINE_TASKS``:
    goToPose's goal and (v, ω) action, or personMonitoring's person) or a map-aware one
    would drive on another episode's world."""
    tasks = BASELINE_TASKS[name]
    if config.task not in tasks:
        fits = [b for b, t in BASELINE_TASKS.items() if config.task in t]
        other = f"--baseline {' or '.join(fits)}" if fits else "an --agent"
        raise ConfigError(f"--baseline {name}: it drives {' or '.join(tasks)}; this env's task "
                          f"is {config.task!r}. Test it with {other}, or give a "
                          f"{tasks[0]} config")
    if BASELINE_TABLE[name].one_world and config.episodes.world_variants:
        raise ConfigError(f"--baseline {name}: it drives on one world's map; this env draws "
                          "its world per episode (episodes.world_variants): unset it")


def make_expert(name: str, config: EnvConfig, robot: RobotInfo, world: WorldSpec | None,
                settings: BaselinesConfig | None = None) -> Baseline:
    """The baseline that labels states as imitation's expert ``name`` (``EXPERT_BASELINES``),
    made as ``make_baseline`` makes it; ``ConfigError`` when no baseline labels under ``name``
    or the task table and the baseline table disagree on its task."""
    baseline = EXPERT_BASELINES.get(name)
    if baseline is None or EXPERT_TASKS.get(name) not in BASELINE_TASKS[baseline]:
        raise ConfigError(f"imitation.expert: {name!r} is no baseline's expert; expected one of "
                          f"{', '.join(EXPERT_BASELINES)}")
    return BASELINE_TABLE[baseline].make(config, robot, world, settings or BaselinesConfig())
