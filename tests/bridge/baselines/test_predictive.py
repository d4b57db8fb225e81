"""The predictive planner (``PredictiveController``, the ``predictive`` baseline): the planner
itself in a world without movers; the speed cap worked by hand against a mover crossing its
way (full speed meets it, half speed passes behind it), a mover moving away leaves full speed,
a mover coming head-on gets the fastest speed that keeps clear over the horizon, or the one
that meets it latest when none does; a person of the ``people`` reading, whose velocity comes
from two frames, caps it the same way in a world with no moving obstacles; made by name
from the ``baselines:`` section, refused without a map."""

from __future__ import annotations

import math

import numpy as np
import pytest

from pic4rl_base.geometry import Footprint, Pose2D
from pic4rl_bridge.baselines.planner import PlannerController, PredictiveController
from pic4rl_bridge.baselines.registry import make_baseline
from pic4rl_bridge.config import EnvConfig
from pic4rl_bridge.errors import ConfigError
from pic4rl_bridge.readings.frame import SensorFrame
from pic4rl_bridge.robot_info import RobotInfo
from pic4rl_bridge.settings.baselines import BaselinesConfig, PredictiveConfig
from pic4rl_sim.engine.geometry import Twist2D
from pic4rl_sim.engine.worlds.spec import MovingObstacles, WorldSpec

ROBOT = RobotInfo(name="disc", footprint=Footprint(radius_m=0.2), omni=False,
                  min_linear_m_s=0.0, max_linear_m_s=1.0, max_angular_rad_s=2.0,
                  max_lateral_m_s=0.0, control_dt_s=0.1)
BOUNDS = (-4.0, -4.0, 4.0, 4.0)
MOVING = MovingObstacles(BOUNDS, ((0.0, 3.0),), (0.0,), (1.0,), (0.1, 1.5), 2.0, radius_m=0.15)
ROOM = WorldSpec("room", BOUNDS, moving=MOVING)
START, GOAL = (-1.0, 0.0), (3.5, 0.0)


def _frame(speed: float = 1.0) -> SensorFrame:
    return SensorFrame(0, Pose2D(*START, 0.0), Twist2D(vx=speed), goal=GOAL)


def _with_mover(position: tuple[float, float], velocity: tuple[float, float]) -> PredictiveController:
    """The controller on its straight plan with one track (its contact distance: 0.2 + 0.1
    + 0.15 = 0.45 m)."""
    controller = PredictiveController(ROBOT, ROOM, horizon_s=2.0, mover_margin_m=0.1)
    controller.command(_frame())  # plans the straight line; the scan-less frame tracks nobody
    assert controller.tracker is not None
    controller.tracker.pos = np.array([position], dtype=float)
    controller.tracker.vel = np.array([velocity], dtype=float)
    return controller


def test_without_moving_obstacles_it_is_the_planner() -> None:
    still = WorldSpec("room", BOUNDS)
    frame = _frame()
    predictive = PredictiveController(ROBOT, still)
    assert predictive.tracker is None
    assert predictive.command(frame) == PlannerController(ROBOT, still).command(frame)


def test_a_mover_crossing_its_way_caps_the_speed_to_pass_behind_it() -> None:
    # The mover reaches the plan at x = 1 at t = 2 s, where full speed (x = -1 + t) takes the
    # robot: within 0.45 m from t = 1.7 s. At 0.75 m/s (reached at once: no acceleration
    # limit) the robot is at x = 0.5 at t = 2 s, 0.5 m short of it, and clear before.
    controller = _with_mover((1.0, -2.0), (0.0, 1.0))
    assert controller.speed_cap(_frame()) == pytest.approx(0.75)
    clear = _with_mover((1.0, -2.0), (0.0, -1.0))  # moving away
    assert clear.speed_cap(_frame()) == pytest.approx(1.0)


def test_a_mover_coming_head_on_gets_the_fastest_clear_speed_or_the_latest_contact() -> None:
    # A mover coming down the plan at 1 m/s from x = 2.5 (3.5 m ahead): the gap closes to
    # 0.45 m at t = 3.05 s / (v + 1 m/s): 1.53 s at 1 m/s, 1.74 s at 0.75, 2.03 s at 0.5,
    # the fastest that keeps clear over the 2 s horizon.
    controller = _with_mover((2.5, 0.0), (-1.0, 0.0))
    assert controller.speed_cap(_frame()) == pytest.approx(0.5)
    # From 2.2 m ahead every speed meets it within the horizon: stopped latest (1.75 s).
    near = _with_mover((1.2, 0.0), (-1.0, 0.0))
    assert near.speed_cap(_frame()) == 0.0


def _people_frame(stamp_ns: int, people: list[list[float]]) -> SensorFrame:
    return SensorFrame(stamp_ns, Pose2D(*START, 0.0), Twist2D(vx=1.0), goal=GOAL,
                       readings={"people": np.array(people)})


def test_a_person_crossing_its_way_caps_the_speed_as_a_mover_does() -> None:
    # No moving obstacles, one person (a disc of 0.15 m: the same 0.45 m contact distance as
    # the mover above) walking up across the plan at 1 m/s, seen at (1, -2.1) then (1, -2.0)
    # 0.1 s later: the crossing of the mover test, so 0.75 m/s passes behind it.
    still = WorldSpec("room", BOUNDS)
    controller = PredictiveController(ROBOT, still, mover_margin_m=0.1, person_radius_m=0.15)
    assert controller.tracker is None
    controller.command(_people_frame(0, [[1.0, -2.1, 0.0]]))
    v, _ = controller.command(_people_frame(100_000_000, [[1.0, -2.0, 0.0]]))
    np.testing.assert_allclose(controller.predictions()[0][-1], [[1.0, 0.0]], atol=1e-9)
    assert controller.speed_cap(_people_frame(100_000_000, [[1.0, -2.0, 0.0]])) == \
        pytest.approx(0.75)
    assert v == pytest.approx(0.75)
    # Walking away, the person leaves the planner's command as it is.
    away = PredictiveController(ROBOT, still, mover_margin_m=0.1, person_radius_m=0.15)
    away.command(_people_frame(0, [[1.0, -1.9, 0.0]]))
    frame = _people_frame(100_000_000, [[1.0, -2.0, 0.0]])
    assert away.command(frame) == PlannerController(ROBOT, still).command(frame)
    away.reset()  # forgotten: the next frame's person stands still
    away.command(frame)
    assert not away.predictions()[0].std(axis=0).any()


def test_it_is_made_by_name_from_the_baselines_section_and_needs_a_map() -> None:
    settings = BaselinesConfig(predictive=PredictiveConfig(horizon_s=1.5, mover_margin_m=0.2,
                                                           person_radius_m=0.3))
    controller = make_baseline("predictive", EnvConfig(), ROBOT, ROOM, settings)
    assert isinstance(controller, PredictiveController)
    assert len(controller._times) == 15 and math.isclose(controller._reach_m, 0.55)
    assert math.isclose(controller._person_reach_m, 0.7)
    with pytest.raises(ConfigError, match="--baseline predictive: it plans on the simulated"):
        make_baseline("predictive", EnvConfig(), ROBOT, None, settings)
