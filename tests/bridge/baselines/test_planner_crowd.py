"""The privileged planner among people (issue 41 item 4): a person standing on the straight
way to the goal is planned round with the keep-off distance (analytic, an empty room), a
person at the robot is blocked only up to the robot, people closing every way leave the
world's plan; a plan the people have not moved into is kept; in a seeded crowd of 10 in
the indoor world the planner replans round the people as they walk into its plan, and with
``people_replan_s`` 0 never."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from pic4rl_base.geometry import Footprint, Pose2D
from pic4rl_bridge.baselines.crowd_plan import blocks, people_discs, plan_around_people
from pic4rl_bridge.baselines.planner import PlannerController
from pic4rl_bridge.baselines.registry import make_baseline
from pic4rl_bridge.readings.frame import SensorFrame
from pic4rl_bridge.recording import make_env
from pic4rl_bridge.robot_info import RobotInfo
from pic4rl_bridge.settings.baselines import BaselinesConfig, PlannerConfig
from pic4rl_sim.engine.geometry import Twist2D
from pic4rl_sim.engine.paths import PLAN_MARGINS_M
from pic4rl_sim.engine.worlds.spec import Box, WorldSpec

ROOM = WorldSpec("room", (-4.0, -4.0, 4.0, 4.0))
ROBOT = RobotInfo(name="disc", footprint=Footprint(radius_m=0.2), omni=False,
                  min_linear_m_s=0.0, max_linear_m_s=0.5, max_angular_rad_s=1.0,
                  max_lateral_m_s=0.0, control_dt_s=0.1)
START, GOAL, KEEP_OFF = (-3.0, 0.0), (3.0, 0.0), 0.7
CONFIG = Path(__file__).resolve().parents[3] / "config" / "env_crowd.yaml"


def _distance_to(path: np.ndarray, point: np.ndarray) -> float:
    """The least distance (m) from ``point`` to the polyline ``path``."""
    a, b = path[:-1], path[1:]
    t = np.clip(np.sum((point - a) * (b - a), axis=1) / np.sum((b - a) ** 2, axis=1), 0, 1)
    return float(np.hypot(*(a + t[:, None] * (b - a) - point).T).min())


def test_a_person_on_the_way_is_planned_round_with_the_keep_off_distance() -> None:
    person = np.array([[0.0, 0.05]])
    path = plan_around_people(ROOM, START, GOAL, person, robot_radius_m=0.2,
                              margins_m=PLAN_MARGINS_M, keep_off_m=KEEP_OFF)
    assert path is not None
    np.testing.assert_allclose(path[0], START)
    np.testing.assert_allclose(path[-1], GOAL)
    assert _distance_to(path, person[0]) >= KEEP_OFF - 0.05  # bends on the grid's cells
    assert _distance_to(path, person[0]) < KEEP_OFF + 0.3  # round them, not far off
    assert path[:, 1].min() < -0.5  # the free side: below, away from the person's offset
    alone = plan_around_people(ROOM, START, GOAL, np.empty((0, 2)), robot_radius_m=0.2,
                               margins_m=PLAN_MARGINS_M, keep_off_m=KEEP_OFF)
    assert alone is not None and len(alone) == 2  # nobody: the straight line


def test_a_person_at_the_robot_is_blocked_only_up_to_it() -> None:
    discs = people_discs(np.array([[-2.7, 0.0], [0.0, 2.0], [2.98, 0.0]]), np.array(START),
                         np.array(GOAL), KEEP_OFF)
    np.testing.assert_allclose(discs, [[-2.7, 0.0, 0.25], [0.0, 2.0, KEEP_OFF]])


def test_people_closing_every_way_leave_the_world_s_plan() -> None:
    corridor = WorldSpec("corridor", (-4.0, -1.0, 4.0, 1.0), boxes=(
        Box(0.0, 0.9, 8.0, 0.2, 1.0), Box(0.0, -0.9, 8.0, 0.2, 1.0)))
    wall_of_people = np.array([[0.0, y] for y in (-0.6, -0.2, 0.2, 0.6)])
    assert plan_around_people(corridor, START, GOAL, wall_of_people, robot_radius_m=0.2,
                              margins_m=PLAN_MARGINS_M, keep_off_m=KEEP_OFF) is None
    planner = PlannerController(ROBOT, corridor)
    frame = SensorFrame(0, Pose2D(*START, 0.0), Twist2D(), goal=GOAL,
                        readings={"people": np.column_stack((wall_of_people, np.zeros(4)))})
    planner.command(frame)
    assert planner.plans == 1 and planner.people_plans == 0
    assert planner.path is not None and len(planner.path) == 2  # the world's straight plan


def test_a_plan_is_blocked_only_by_a_person_ahead_of_the_robot() -> None:
    path = np.array([START, GOAL])
    ahead, behind = np.array([[1.0, 0.3]]), np.array([[-2.0, 0.3]])
    assert blocks(path, 2.0, (-1.0, 0.0), ahead, KEEP_OFF)
    assert not blocks(path, 2.0, (-1.0, 0.0), behind, KEEP_OFF)  # passed already
    assert not blocks(path, 2.0, (-1.0, 0.0), ahead + [0.0, 1.0], KEEP_OFF)  # 1.3 m off


@pytest.mark.parametrize("period_s", [1.0, 0.0])
def test_in_a_seeded_crowd_the_planner_replans_round_the_people(period_s: float) -> None:
    """80 steps (8 s) of episode 0, seed 7, the plan checked every 10 steps (1 s): people
    walk into it and it is made again round them, each plan round the people where they
    stood then; with period 0, plans on the map alone."""
    env = make_env(CONFIG, overrides={"episode_max_steps": 80})
    nav = env.unwrapped
    settings = BaselinesConfig(planner=PlannerConfig(people_replan_s=period_s))
    try:
        planner = make_baseline("planner", nav.config, nav.scenario.robot, nav.scenario.world,
                                settings)
        env.reset(seed=7)
        planner.reset()
        paths, steps = [], 0
        for steps in range(1, 81):
            frame = nav.frame
            before = planner.people_plans
            _, _, terminated, truncated, _ = env.step(planner.action(frame))
            if planner.people_plans > before:  # a plan round the people of this frame
                people = np.asarray(frame.readings["people"])[:, :2]
                paths.append((planner.path.copy(), people))
            if terminated or truncated:
                break
    finally:
        env.close()
    if period_s == 0:
        assert planner.people_plans == 0 and not paths
        return
    assert steps >= 30, "the episode ended too soon to see replanning"
    assert planner.people_plans >= 2 and planner.plans >= 3
    # each plan keeps 0.5 m beyond the robot's radius off the people of its frame (those
    # beyond their disc of the robot and the goal)
    keep_off = nav.scenario.robot.footprint.bounding_radius_m + 0.5
    for path, people in paths:
        far = np.hypot(*(people - path[0]).T) > keep_off + 0.1
        far &= np.hypot(*(people - path[-1]).T) > keep_off + 0.1
        assert all(_distance_to(path, p) >= keep_off - 0.08 for p in people[far])
    assert len({p.tobytes() for p, _ in paths}) > 1  # the plan changed as the people moved
