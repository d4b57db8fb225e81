"""explore: the reward is the area newly seen (analytic: a scan circle growing), the episode ends
at the coverage target of the world's free area (analytic: a room cut by a wall) or on a
collision, and the observation's crop shows what was seen round the robot."""

from __future__ import annotations

import math

import numpy as np
import pytest

from pic4rl_base.geometry import Footprint, Pose2D
from pic4rl_bridge.config import EnvConfig
from pic4rl_bridge.perception.frontiers import frontier_cells
from pic4rl_bridge.readings.frame import ScanData, SensorFrame
from pic4rl_bridge.robot_info import RobotInfo
from pic4rl_bridge.tasks import make_task
from pic4rl_bridge.tasks.explore import Explore, free_area_m2
from pic4rl_metrics.contract import Outcome
from pic4rl_sim.engine.geometry import Twist2D
from pic4rl_sim.engine.worlds.spec import Box, WorldSpec

BEAMS = 720
ROBOT = RobotInfo(name="test", footprint=Footprint(radius_m=0.2), omni=False,
                  min_linear_m_s=0.0, max_linear_m_s=0.5, max_angular_rad_s=1.0,
                  max_lateral_m_s=0.0, control_dt_s=0.1)
#: A 4 x 3 m room cut at x = 3 by a wall 0.2 m thick: 2.9 x 3 m on the start's side.
ROOM = WorldSpec("room", (0.0, 0.0, 4.0, 3.0), (Box(3.0, 1.5, 0.2, 3.0, 1.0),))


def frame(reach_m: float, t_s: float = 0.0, x: float = 1.5, y: float = 1.5,
          yaw: float = 0.0) -> SensorFrame:
    """A 360° scan at ``t_s`` seeing a circle of ``reach_m`` round the robot (a wall all round);
    the area seen counts a scan from the same place once a second (``SeenTrack``)."""
    ranges = np.full(BEAMS, reach_m, np.float32)
    scan = ScanData(ranges, -math.pi, 2 * math.pi / BEAMS, 0.05, 10.0)
    return SensorFrame(round(t_s * 1e9), Pose2D(x, y, yaw), Twist2D(), scan=scan)


def task(world: WorldSpec | None = ROOM, **params: object) -> Explore:
    config = EnvConfig(task="explore").replace(**params)
    built = make_task(config, ROBOT, world)
    assert isinstance(built, Explore)
    return built


def test_the_free_area_is_the_floor_connected_to_the_start():
    # the start's side of the wall: 2.9 x 3 m; from the other side: 0.9 x 3 m
    assert free_area_m2(ROOM, (1.0, 1.0)) == pytest.approx(2.9 * 3.0, abs=0.05 * 3.0)
    assert free_area_m2(ROOM, (3.6, 1.0)) == pytest.approx(0.9 * 3.0, abs=0.05 * 3.0)
    # a start inside the wall counts from the nearest free cell
    assert free_area_m2(ROOM, (3.0, 1.0)) in (pytest.approx(free_area_m2(ROOM, (1.0, 1.0))),
                                             pytest.approx(free_area_m2(ROOM, (3.6, 1.0))))


def test_the_reward_is_the_area_newly_seen():
    t = task(**{"reward.area": 2.0, "explore.coverage_target": 0.0})
    context = t.begin(frame(0.5))
    grid = context.extra["seen"].grid
    first = grid.area_m2
    assert first == pytest.approx(math.pi * 0.5**2, rel=0.03)
    same = t.judge(frame(0.5), frame(0.5, 1.0), context, 0)
    assert same.terms["area"] == 0.0 and same.outcome is None
    # a wider circle from the same place 0.1 s later is held, as the bag's metric holds it
    held = t.judge(frame(0.5, 1.0), frame(1.0, 1.1), context, 0)
    assert held.terms["area"] == 0.0 and grid.area_m2 == first
    wider = t.judge(frame(1.0, 1.1), frame(1.0, 2.0), context, 0)
    assert wider.terms["area"] == pytest.approx(2.0 * (grid.area_m2 - first), abs=1e-9)
    assert wider.terms["area"] == pytest.approx(2.0 * math.pi * (1.0**2 - 0.5**2), rel=0.03)
    assert wider.reward == pytest.approx(wider.terms["area"])
    assert set(wider.terms) == {"area", "step", "collision"}


def test_the_episode_ends_at_the_coverage_target():
    free = free_area_m2(ROOM, (1.5, 1.5))
    target = math.pi * 0.9**2 / free  # a circle of 0.9 m reaches it, one of 0.6 m does not
    t = task(**{"explore.coverage_target": target})
    context = t.begin(frame(0.6))
    assert context.goal is None and t.facts(context) == {"free_area_m2": free}
    assert t.judge(frame(0.6), frame(0.8, 1.0), context, 0).outcome is None
    ended = t.judge(frame(0.8, 1.0), frame(1.0, 2.0), context, 0)
    assert ended.outcome is Outcome.GOAL and ended.terms["collision"] == 0.0
    # no world (a real robot): no target, no fact
    blind = task(world=None)
    context = blind.begin(frame(0.6))
    assert blind.judge(frame(0.6), frame(9.0, 1.0), context, 0).outcome is None
    assert blind.facts(context) == {}


def test_a_collision_ends_the_episode_with_its_penalty():
    t = task(**{"reward.collision": -7.0, "explore.coverage_target": 0.0})
    context = t.begin(frame(2.0))
    crashed = t.judge(frame(2.0), frame(0.21), context, 0)
    assert crashed.outcome is Outcome.COLLISION and crashed.terms["collision"] == -7.0


def test_the_observation_is_sectors_last_action_and_the_seen_crop():
    t = task(**{"explore.crop_px": 4, "explore.crop_cell_m": 1.0, "lidar.sectors": 8})
    context = t.begin(frame(1.0))
    obs = t.observe(frame(1.0), context, np.array([0.5, -0.25]))
    assert obs.shape == t.observation_space.shape == (8 + 2 + 16,)
    assert t.observation_space.contains(obs)
    assert obs[:8] == pytest.approx(1.0, abs=1e-6) and obs[8:10].tolist() == [0.5, -0.25]
    crop = obs[10:].reshape(4, 4)
    # pixel centres 0.71 m from the robot lie in the 1 m circle seen, the others beyond it
    expected = np.zeros((4, 4))
    expected[1:3, 1:3] = 1.0
    assert crop.tolist() == expected.tolist()


def test_frontiers_are_known_free_cells_next_to_the_unknown():
    seen = np.zeros((5, 7), dtype=bool)
    seen[1:4, 1:5] = True
    occupied = np.zeros_like(seen)
    occupied[1:4, 1] = True  # a wall on the left of what was seen
    front = frontier_cells(seen, occupied)
    # the top, bottom and right borders, less the cells at or beside the wall
    assert front[1, 3] and front[3, 4] and front[2, 4] and not front[2, 3]
    assert not front[:, 1].any() and not front[:, 2].any()
