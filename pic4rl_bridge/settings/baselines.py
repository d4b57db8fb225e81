"""The settings of the classical baselines: the ``baselines:`` section of a params file,
beside ``sim:`` and ``nav_env:``, which ``pic4rl-test --baseline`` reads (the env never
does)::

    baselines:
      ros__parameters:
        dwa.horizon_s: 2.0

On the command line: ``pic4rl-test --baseline dwa --ros-args -p baselines.dwa.horizon_s:=2.0``.
The person follower's DWA, which a hybrid personMonitoring env runs, is the env's
(``person.dwa.*``).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from pic4rl_base.schema import NON_NEGATIVE, POSITIVE, Range, check, from_params, param, section

from ..errors import ConfigError, require

BASELINES_NODE = "baselines"
#: ``-p`` keys with this prefix are the ``baselines:`` section's.
PREFIX = f"{BASELINES_NODE}."


@dataclass(frozen=True)
class DwaConfig:
    """The Dynamic Window Approach (``pic4rl_bridge.baselines.dwa.DwaController``, and the person
    follower of ``pic4rl_bridge.baselines.follow``). The velocity ranges, acceleration limits,
    window period and footprint are the robot's. Its owner's section checks it (``check_as``)."""

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

    def check_as(self, prefix: str) -> None:
        """``ConfigError`` naming the key as ``prefix`` + field (``person.dwa.``) for a field
        out of its range, or a rollout step longer than the horizon."""
        check(self, prefix)
        require(self.rollout_dt_s <= self.horizon_s, f"{prefix}rollout_dt_s",
                self.rollout_dt_s, f"at most {prefix}horizon_s={self.horizon_s}")


@dataclass(frozen=True)
class PlannerConfig:
    """The privileged planner (``pic4rl_bridge.baselines.planner.PlannerController``): how fast it
    goes against how wide it keeps of obstacles (BARN's dense fields want a slower, wider one)."""

    lookahead_m: float = param(0.4, doc="the steering target: the farthest point of the plan "
                               "this far ahead that the robot sees", unit="m", range=POSITIVE)
    turn_in_place_rad: float = param(0.8, doc="bearing of the target beyond which it turns in "
                                     "place; full speed within a third of it", unit="rad",
                                     range=Range(0.1, 3.1416))
    replan_distance_m: float = param(0.3, doc="plans again when this far off its plan",
                                     unit="m", range=POSITIVE)
    clearance_m: float = param(0.07, doc="beyond the bounding radius: the line of sight to the "
                               "target keeps this from obstacles", unit="m", range=NON_NEGATIVE)
    plan_margin_m: float = param(0.0, doc="beyond the bounding radius: the plan keeps at least "
                                 "this (0: the simulator's plan margins, widest first)",
                                 unit="m", range=NON_NEGATIVE)
    max_linear_m_s: float = param(0.0, doc="its speed limit; 0: the env's", unit="m/s",
                                  range=NON_NEGATIVE)
    people_replan_s: float = param(1.0, doc="among people (a people reading), plans round "
                                   "their current positions this often; 0: never (the "
                                   "world's map alone)", unit="s", range=NON_NEGATIVE)
    people_margin_m: float = param(0.5, doc="beyond the bounding radius: the plan keeps this "
                                   "from each person's centre", unit="m", range=NON_NEGATIVE)


@dataclass(frozen=True)
class PredictiveConfig:
    """The predictive planner (``pic4rl_bridge.baselines.planner.PredictiveController``): the
    planner's settings (``planner.*``) but its speed limit, and how far ahead and how wide it
    times its speed against the moving obstacles it tracks."""

    horizon_s: float = param(2.0, doc="each trial speed's progress along the plan is checked "
                             "against the movers' predictions this long", unit="s",
                             range=Range(0.1, 10.0))
    mover_margin_m: float = param(0.1, doc="beyond the bounding radius and a mover's: the "
                                  "clearance a trial speed keeps from every mover's "
                                  "prediction", unit="m", range=NON_NEGATIVE)
    max_linear_m_s: float = param(0.0, doc="its speed limit (not the planner's); 0: the env's",
                                  unit="m/s", range=NON_NEGATIVE)
    person_radius_m: float = param(0.25, doc="each person of the people reading is a disc of "
                                   "this radius (the crowd's crowd.radius_m)", unit="m",
                                   range=Range(0.05, 1.0))


@dataclass(frozen=True)
class ExplorerConfig:
    """The mapless explorer (``pic4rl_bridge.baselines.explorer.ExplorerController``): its plan's
    clearance beyond the footprint's circumscribed radius, when it plans anew, and how fast
    it goes (BARN's dense fields want it slower, as the planner)."""

    margin_m: float = param(0.10, doc="the plan keeps this beyond the circumscribed radius "
                            "from every cell seen occupied", unit="m", range=NON_NEGATIVE)
    narrow_margin_m: float = param(0.03, doc="... or this, when no path keeps margin_m (a "
                                   "narrow door)", unit="m", range=NON_NEGATIVE)
    replan_distance_m: float = param(0.3, doc="a new plan when the robot is this far off its "
                                     "plan (and when a newly seen obstacle blocks it)",
                                     unit="m", range=POSITIVE)
    squeeze_radius_m: float = param(0.0, doc="when no path keeps the circumscribed radius + "
                                    "narrow_margin_m, one that keeps this (a gap the footprint "
                                    "fits only driven along it); 0: none", unit="m",
                                    range=NON_NEGATIVE)
    max_linear_m_s: float = param(0.0, doc="its speed limit; 0: the env's", unit="m/s",
                                  range=NON_NEGATIVE)
    clear_free: bool = param(False, doc="each scan frees the occupied cells its beams pass "
                             "through short of their returns (nav2's raytrace clearing: people "
                             "and moving obstacles leave no trails); false: cells seen stay")


@dataclass(frozen=True)
class BaselinesConfig:
    """The classical controllers ``pic4rl-test --baseline`` runs."""

    dwa: DwaConfig = section(DwaConfig)
    planner: PlannerConfig = section(PlannerConfig)
    predictive: PredictiveConfig = section(PredictiveConfig)
    explorer: ExplorerConfig = section(ExplorerConfig)

    def __post_init__(self) -> None:
        self.dwa.check_as(f"{PREFIX}dwa.")
        check(self.planner, f"{PREFIX}planner.")
        check(self.predictive, f"{PREFIX}predictive.")
        check(self.explorer, f"{PREFIX}explorer.")


def baselines_config_from_params(params: Mapping[str, Any]) -> BaselinesConfig:
    """A ``BaselinesConfig`` from the ``baselines:`` section's dotted parameters."""
    return from_params(BaselinesConfig, params, where=f"{BASELINES_NODE} parameters")


def baselines_config(section: Mapping[str, Any], overrides: Mapping[str, Any] | None = None,
                     *, where: str = "") -> BaselinesConfig:
    """A ``BaselinesConfig`` from a ``baselines:`` section already read (from ``where``) and
    dotted ``overrides``; an error names ``where`` (or the command line)."""
    try:
        return baselines_config_from_params({**section, **(overrides or {})})
    except ConfigError as err:
        raise ConfigError(f"{where or 'command line'}: {err}") from err
