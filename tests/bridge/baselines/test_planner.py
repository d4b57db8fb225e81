"""The privileged planner's plans and labels against a wall with a gap (analytic): the plan
goes through the gap, with its clearance; a label from a pose that faces the wall turns toward
the gap, from a pose that faces the plan it drives; the plan is kept until the robot is off it.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from pic4rl_base.geometry import Footprint, Pose2D
from pic4rl_bridge.baselines.planner import PlannerController
from pic4rl_bridge.control.actions import planar_command
from pic4rl_bridge.readings.frame import SensorFrame
from pic4rl_bridge.robot_info import RobotInfo
from pic4rl_sim.engine.geometry import Twist2D
from pic4rl_sim.engine.paths import PLAN_MARGINS_M, plan_path
from pic4rl_sim.engine.worlds.spec import Box, WorldSpec

GAP = (0.5, 2.0)  # the gap in the wall along x = 0 (y, m)
WORLD = WorldSpec("gap", (-4.0, -4.0, 4.0, 4.0), boxes=(
    Box(0.0, (-4.0 + GAP[0]) / 2, 0.1, GAP[0] + 4.0, 1.0),
    Box(0.0, (GAP[1] + 4.0) / 2, 0.1, 4.0 - GAP[1], 1.0)))
ROBOT = RobotInfo(name="disc", footprint=Footprint(radius_m=0.2), omni=False,
                  min_linear_m_s=0.0, max_linear_m_s=0.5, max_angular_rad_s=1.0,
                  max_lateral_m_s=0.0, control_dt_s=0.1)
START, GOAL = (-2.0, -1.0), (2.0, -1.0)


def _frame(x: float, y: float, yaw: float) -> SensorFrame:
    return SensorFrame(0, Pose2D(x, y, yaw), Twist2D(), goal=GOAL)


def _through_gap(points: np.ndarray) -> float:
    """The y at which the polyline crosses x = 0."""
    for a, b in zip(points, points[1:]):
        if a[0] < 0 <= b[0]:
            return float(a[1] + (b[1] - a[1]) * (0 - a[0]) / (b[0] - a[0]))
    raise AssertionError("the route does not cross the wall")


def test_the_plan_goes_through_the_gap_with_the_margin():
    path = plan_path(WORLD, START, GOAL, robot_radius_m=0.2)
    inflated = 0.2 + PLAN_MARGINS_M[0]
    assert GAP[0] + inflated - 0.05 <= _through_gap(path) <= GAP[1] - inflated + 0.05
    assert WORLD.clearance(path).min() >= inflated - 0.05  # bends on the grid's cells


def test_the_expert_follows_the_plan_the_sim_publishes():
    planner = PlannerController(ROBOT, WORLD)
    planner.command(_frame(*START, 0.0))
    assert planner.path is not None
    assert np.array_equal(planner.path, plan_path(WORLD, START, GOAL, robot_radius_m=0.2))
    assert GAP[0] < _through_gap(planner.path) < GAP[1]


def test_facing_the_wall_the_label_turns_toward_the_gap_and_facing_the_route_it_drives():
    planner = PlannerController(ROBOT, WORLD)
    v, w = planner.command(_frame(-0.8, -1.0, -0.4))  # the goal ahead, behind the wall
    assert w > 0.5 and v == pytest.approx(0.0)  # turn left, in place
    v, w = planner.command(_frame(-0.8, -1.0, math.radians(75)))  # toward the gap
    assert v > 0.2 and abs(w) < 1.0
    v, w = planner.command(_frame(-0.8, -1.0, math.radians(-90)))  # away from it
    assert w > 0.5 and v == pytest.approx(0.0)
    action = planner.action(_frame(-0.8, -1.0, math.radians(75)))
    command = planar_command(action, ROBOT)
    assert (command.vx, command.wz) == pytest.approx(planner.command(
        _frame(-0.8, -1.0, math.radians(75))), abs=1e-6)


def test_the_plan_is_kept_until_the_robot_leaves_it():
    """A plan per episode (the commitment a student can learn), and a new one from wherever
    the robot is once it is more than replan_distance_m off it."""
    planner = PlannerController(ROBOT, WORLD, replan_distance_m=0.3)
    planner.command(_frame(*START, 0.0))
    first = planner.path
    assert first is not None
    for s in (0.2, 0.5, 1.0):  # along the plan, a little to its side
        x, y = first[0] + s * (first[1] - first[0]) / np.linalg.norm(first[1] - first[0])
        planner.command(_frame(float(x) + 0.1, float(y), 0.0))
    assert planner.plans == 1
    planner.command(_frame(-2.0, -3.0, 0.0))  # 2 m off
    assert planner.plans == 2 and np.allclose(planner.path[0], (-2.0, -3.0))
    planner.reset()
    planner.command(_frame(*START, 0.0))
    assert planner.plans == 3 and np.array_equal(planner.path, first)
