"""goToPose: the action map, observations and the paper's reward on known motions."""

from __future__ import annotations

import dataclasses
import math
import subprocess
import sys

import gymnasium as gym
import numpy as np
import pytest

from pic4rl_base.geometry import Footprint, Pose2D
from pic4rl_bridge.config import EnvConfig
from pic4rl_bridge.readings.frame import ScanData, SensorFrame
from pic4rl_bridge.robot_info import RobotInfo
from pic4rl_bridge.tasks import make_task
from pic4rl_bridge.tasks.goto import GoToPoseLidar, GoToPoseSensors
from pic4rl_metrics.contract import Outcome
from pic4rl_sim.engine.geometry import Twist2D
from pic4rl_sim.engine.robot_specs import DepthCameraSpec, LidarSpec

INC = 2 * math.pi / 360
SENSORS = {"lidar": LidarSpec(), "depth": DepthCameraSpec()}  # what the robot carries
TERMS = {"distance", "heading", "step", "proximity", "goal", "collision"}


def robot(min_linear: float = 0.0) -> RobotInfo:
    return RobotInfo(name="test", footprint=Footprint(radius_m=0.3), omni=False,
                     min_linear_m_s=min_linear, max_linear_m_s=0.5, max_angular_rad_s=2.0,
                     max_lateral_m_s=0.0, control_dt_s=0.1, specs=SENSORS)


def scan(ahead_m: float = math.inf) -> ScanData:
    ranges = np.full(360, np.inf, np.float32)
    ranges[180] = ahead_m  # the beam at 0 rad
    return ScanData(ranges, -math.pi, INC, 0.1, 30.0)


def frame(x: float, y: float = 0.0, yaw: float = 0.0, goal=(3.0, 0.0), ahead_m=math.inf,
          depth: np.ndarray | None = None) -> SensorFrame:
    return SensorFrame(0, Pose2D(x, y, yaw), Twist2D(), goal=goal, scan=scan(ahead_m),
                       depth=depth)


@pytest.mark.parametrize("min_linear, a0, v", [(0.0, -1.0, 0.0), (0.0, 0.0, 0.25),
                                               (0.0, 1.0, 0.5), (-0.2, 0.0, 0.15),
                                               (-0.2, -1.0, -0.2), (0.0, 3.0, 0.5)])
def test_action_to_command(min_linear, a0, v):
    task = GoToPoseLidar(EnvConfig(), robot(min_linear))
    for a1, w in ((-1.0, -2.0), (0.0, 0.0), (1.0, 2.0), (-7.0, -2.0)):
        assert task.command(np.array([a0, a1], np.float32)) == pytest.approx(Twist2D(v, 0.0, w))


def test_lidar_observation_values_and_space():
    config = EnvConfig()
    task = GoToPoseLidar(config, robot())
    start = frame(0.0, yaw=math.pi / 2, goal=(1.0, 0.0), ahead_m=2.0)
    context = task.begin(start)
    assert context.goal == (1.0, 0.0) and context.start == start.pose
    obs = task.observe(start, context, np.array([0.5, -2.0]))
    assert obs.shape == (config.lidar.sectors + 4,) and task.observation_space.contains(obs)
    assert obs[config.lidar.sectors // 2] == 2.0 and obs[0] == config.lidar.clip_m
    np.testing.assert_allclose(obs[-4:], [1.0, -math.pi / 2, 0.5, -1.0], rtol=1e-6)
    behind = task.observe(frame(4.0, goal=(1.0, 0.0)), context, np.zeros(2))
    assert task.observation_space.contains(behind) and abs(abs(behind[-3]) - math.pi) < 1e-6


def test_normalized_lidar_observation_is_the_raw_one_scaled():
    raw_task = GoToPoseLidar(EnvConfig(), robot())
    task = GoToPoseLidar(EnvConfig(normalize_observations=True), robot())
    beams, max_range = task.config.lidar.sectors, task.config.lidar.clip_m
    for goal, ahead in (((1.0, 0.0), 2.0), ((30.0, -4.0), 0.3)):
        start = frame(0.0, yaw=math.pi / 2, goal=goal, ahead_m=ahead)
        raw = raw_task.observe(start, raw_task.begin(start), np.array([0.5, -2.0]))
        obs = task.observe(start, task.begin(start), np.array([0.5, -2.0]))
        assert task.observation_space.contains(obs)
        assert task.observation_space.high.max() == 1.0
        np.testing.assert_allclose(obs[:beams], raw[:beams] / max_range, rtol=1e-6)
        np.testing.assert_allclose(obs[beams], min(raw[beams] / 10.0, 1.0), rtol=1e-6)
        np.testing.assert_allclose(obs[beams + 1], raw[beams + 1] / math.pi, rtol=1e-6)
        np.testing.assert_allclose(obs[-2:], raw[-2:])


def test_normalized_depth_goal_vector():
    task = GoToPoseSensors(EnvConfig(sensor="depth", normalize_observations=True), robot())
    start = frame(0.0, goal=(0.0, 5.0), depth=np.full((60, 80), 2.0, np.float32))
    obs = task.observe(start, task.begin(start), np.zeros(2))
    assert task.observation_space.contains(obs)
    np.testing.assert_allclose(obs["goal"][:2], [0.5, 0.5], rtol=1e-6)


@pytest.mark.parametrize("encoding", ["uint8", "float32"])
def test_depth_observation_is_a_dict_in_its_space(encoding):
    config = EnvConfig().replace(sensor="depth", **{"depth.encoding": encoding})
    task = make_task(config, robot())
    assert isinstance(task, GoToPoseSensors) and task.required == {"goal", "depth"}
    image = np.full((120, 160), 3.0, np.float32)
    f = frame(0.0, depth=image)
    obs = task.observe(f, task.begin(f), np.zeros(2))
    assert task.observation_space.contains(obs)
    assert obs["depth"].shape == (1, 60, 80)
    np.testing.assert_allclose(obs["goal"], [3.0, 0.0, 0.0, 0.0])


def test_distance_reward_over_a_known_motion():
    config = EnvConfig().replace(**{"reward.distance": 2.0, "reward.step": -0.1})
    task = GoToPoseLidar(config, robot())
    context = task.begin(frame(0.0))
    j = task.judge(frame(0.0), frame(0.5, 0.3), context, 0)
    d = math.hypot(2.5, 0.3)
    assert set(j.terms) == TERMS and j.outcome is None
    assert j.terms["distance"] == pytest.approx(2.0 * (3.0 - d))
    assert j.terms["heading"] == 0.0 and j.terms["step"] == -0.1
    assert j.reward == pytest.approx(2.0 * (3.0 - d) - 0.1)
    back = task.judge(frame(0.5), frame(0.0), context, 0)
    assert back.terms["distance"] == pytest.approx(-1.0)


@pytest.mark.parametrize("ahead_m, expected", [(math.inf, 0.0), (0.3 + 0.5, 0.0),
                                               (0.3 + 0.25, -0.5), (0.3 + 0.1, -0.8)])
def test_proximity_term(ahead_m, expected):
    # The test robot is a disc of 0.3 m at the scan's origin: clearance = range - 0.3.
    config = EnvConfig().replace(**{"reward.proximity": -1.0})
    task = GoToPoseLidar(config, robot())
    context = task.begin(frame(0.0))
    j = task.judge(frame(0.0), frame(0.0, ahead_m=ahead_m), context, 0)
    assert j.terms["proximity"] == pytest.approx(expected, abs=1e-6)
    off = GoToPoseLidar(EnvConfig(), robot()).judge(frame(0.0), frame(0.0, ahead_m=0.4),
                                                    context, 0)
    assert off.terms["proximity"] == 0.0


@pytest.mark.parametrize("yaw, expected", [(0.0, 1.0), (math.pi / 4, 0.0), (math.pi, -1.0)])
def test_heading_term(yaw, expected):
    task = GoToPoseLidar(EnvConfig().replace(**{"reward.heading": 1.0}), robot())
    context = task.begin(frame(0.0))
    j = task.judge(frame(0.0, yaw=yaw), frame(0.0, yaw=yaw), context, 0)
    assert j.terms["heading"] == pytest.approx(expected)


def test_goal_outcome_has_priority_over_collision():
    task = GoToPoseLidar(EnvConfig(), robot())
    context = task.begin(frame(0.0))
    j = task.judge(frame(2.5), frame(2.7, ahead_m=0.31), context, 0)
    assert j.collision and j.collision_streak == 1
    assert j.outcome is Outcome.GOAL and set(j.terms) == TERMS
    assert (j.terms["goal"], j.terms["collision"]) == (1000.0, 0.0)
    short = task.judge(frame(2.5), frame(2.59), context, 0)  # 0.41 m: not yet
    assert short.outcome is None and short.terms["goal"] == 0.0


def test_collision_streak_ends_the_episode_at_collision_steps():
    task = GoToPoseLidar(EnvConfig().replace(collision_steps=3), robot())
    context = task.begin(frame(0.0))
    streak, outcomes = 0, []
    for _ in range(3):
        j = task.judge(frame(0.0), frame(0.0, ahead_m=0.32), context, streak)
        assert j.collision and j.min_obstacle_m == pytest.approx(0.02, abs=1e-6)
        streak = j.collision_streak
        outcomes.append((j.outcome, j.terms["collision"]))
    assert outcomes == [(None, 0.0), (None, 0.0), (Outcome.COLLISION, -150.0)]
    clear = task.judge(frame(0.0), frame(0.0, ahead_m=0.38), context, 2)
    assert (clear.collision, clear.warning, clear.collision_streak) == (False, True, 0)
    assert clear.outcome is None


def test_make_task_and_required_sensors():
    task = make_task(EnvConfig(), robot())
    assert isinstance(task, GoToPoseLidar) and task.name == "goToPose"
    assert task.required == {"goal", "scan"}
    assert task.action_space.shape == (2,) and task.action_space.dtype == np.float32


def test_importing_tasks_pulls_in_neither_ros_nor_mujoco():
    code = ("import sys, pic4rl_bridge.tasks as t, pic4rl_bridge.tasks.goto, "
            "pic4rl_bridge.tasks.vineyard, pic4rl_bridge.tasks.person; "
            "print(sorted(m for m in sys.modules if m.split('.')[0] in "
            "('rclpy', 'mujoco', 'torch')))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True)
    assert out.stdout.strip() == "[]"


def _with_plan(plan: np.ndarray | None) -> SensorFrame:
    base = frame(0.0, goal=(3.0, 0.0))
    return SensorFrame(base.stamp_ns, base.pose, base.twist, base.goal, scan=base.scan, plan=plan)


@pytest.mark.parametrize("sensor", ["lidar", "depth"])
def test_the_mapless_observation_holds_no_path_information(sensor):
    """goal_input goal (the paper's): the same observation whatever plan the frame carries,
    and the same space as without one; goal_input plan: the target is the plan's point
    plan_lookahead_m ahead (here round an obstacle: up, then across)."""
    detour = np.array([[0.0, 0.0], [0.0, 2.0], [3.0, 2.0], [3.0, 0.0]])
    depth = np.full((60, 80), 2.0, np.float32)
    frames = [dataclasses.replace(_with_plan(p), depth=depth)
              for p in (None, detour, detour[::-1], np.array([[0.0, 0.0], [3.0, 0.0]]))]
    config = EnvConfig(sensor=sensor, normalize_observations=True)
    task = make_task(config, robot(), None)
    context = task.begin(frames[0])
    observations = [task.observe(f, context, np.zeros(2)) for f in frames]
    goal_parts = [o["goal"] if sensor == "depth" else o[-4:] for o in observations]
    assert all(np.array_equal(goal_parts[0], g) for g in goal_parts[1:])
    planned = make_task(config.replace(goal_input="plan", plan_lookahead_m=1.0), robot(), None)
    assert planned.observation_space == task.observation_space
    assert "plan" in planned.required and "plan" not in task.required
    obs = planned.observe(frames[1], context, np.zeros(2))
    goal = obs["goal"] if sensor == "depth" else obs[-4:]
    np.testing.assert_allclose(goal[:2], [1.0 / 10.0, 0.5], rtol=1e-6)  # (0, 1): 1 m at +90°
    with pytest.raises(ValueError, match="plan"):
        planned.observe(frames[0], context, np.zeros(2))


@pytest.mark.parametrize("sensor", ["lidar", "depth"])
def test_the_memory_observation_is_the_episodes_own_scans_and_holds_no_plan(sensor):
    """memory.enabled: a Dict with the crop of the episode's grid beside the usual parts;
    frames that differ only in their plan give the same observation (nothing of the plan,
    and the task has no world); a new episode's context starts an empty grid."""
    detour = np.array([[0.0, 0.0], [0.0, 2.0], [3.0, 2.0], [3.0, 0.0]])
    depth = np.full((60, 80), 2.0, np.float32)
    wall = frame(0.0, goal=(3.0, 0.0), ahead_m=1.5, depth=depth)
    frames = [wall, dataclasses.replace(wall, plan=detour)]
    config = EnvConfig(sensor=sensor, normalize_observations=True).replace(**{
        "memory.enabled": True, "memory.size_px": 32, "memory.resolution_m": 0.25})
    task = make_task(config, robot(), None)
    space = task.observation_space
    assert isinstance(space, gym.spaces.Dict) and space["memory"].shape == (1, 32, 32)
    assert set(space) == ({"memory", "lidar"} if sensor == "lidar"
                          else {"memory", "depth", "goal"})
    context = task.begin(frames[0])
    first, second = (task.observe(f, context, np.zeros(2)) for f in frames)
    assert space.contains(first) and first.keys() == second.keys()
    assert all(np.array_equal(first[k], second[k]) for k in first)
    assert first["memory"].any()  # the wall ahead: lit pixels above the centre
    rows = np.argwhere(first["memory"][0])[:, 0]
    assert (rows < 16).all()
    fresh = task.begin(frames[0])
    assert not fresh.extra["memory"].cells.size


def test_the_explorer_target_points_along_the_plan_of_the_episodes_own_scans():
    """goal_input explorer: the target is the explorer's plan's point plan_lookahead_m ahead,
    made from the frames' scans alone (the frame's own plan is ignored, the task has no
    world): straight at the goal while nothing is seen, off the line once a wall ahead is;
    the space is the paper's; a new episode's context starts an empty grid and no plan."""
    config = EnvConfig(normalize_observations=True).replace(goal_input="explorer",
                                                              plan_lookahead_m=1.0)
    task = make_task(config, robot(), None)
    assert task.observation_space == make_task(EnvConfig(normalize_observations=True),
                                               robot(), None).observation_space
    open_ = frame(0.0, goal=(3.0, 0.0))
    context = task.begin(open_)
    obs = task.observe(dataclasses.replace(open_, plan=np.array([[0.0, 0.0], [0.0, 3.0]])),
                       context, np.zeros(2))
    np.testing.assert_allclose(obs[-4:-2], [1.0 / 10.0, 0.0], atol=1e-6)  # 1 m dead ahead
    walled = dataclasses.replace(frame(0.0, goal=(3.0, 0.0), ahead_m=1.0), stamp_ns=1)
    walled.scan.ranges[170:191] = 1.0  # a wall across the way, 1 m ahead
    obs = task.observe(walled, context, np.zeros(2))
    assert abs(obs[-3]) > 0.05  # the target left the straight line
    plan = context.extra["explorer"].path
    assert plan is not None and np.allclose(plan[-1], (3.0, 0.0))
    assert task.observe(walled, context, np.zeros(2)).tolist() == obs.tolist()  # idempotent
    fresh = task.begin(open_)
    assert fresh.extra["explorer"].path is None and not len(fresh.extra["explorer"].grid.cells)


def test_a_depth_agents_explorer_plan_is_made_from_its_depth_image_not_the_scan():
    """goal_input explorer with sensor depth: the plan marks the depth image's pseudo-scan
    even when the frame carries a scan (the LiDAR a depth env keeps for its collision test):
    a wall the scan shows and the camera does not leaves the plan straight."""
    config = EnvConfig(sensor="depth", normalize_observations=True).replace(
        goal_input="explorer")
    task = make_task(config, robot(), None)
    walled = frame(0.0, goal=(3.0, 0.0), ahead_m=1.0,
                   depth=np.full((60, 80), np.inf, np.float32))
    walled.scan.ranges[170:191] = 1.0
    context = task.begin(walled)
    task.observe(walled, context, np.zeros(2))
    plan = context.extra["explorer"]
    assert not len(plan.grid.cells) and np.allclose(plan.path, [(0.0, 0.0), (3.0, 0.0)])


def test_the_scan_history_stacks_the_last_scans_newest_first_and_resets():
    """lidar.history 3: the first scan fills the stack; each step shifts it by one; a new
    episode's context starts empty; the goal vector stays at the end."""
    config = EnvConfig().replace(**{"lidar.history": 3})
    task = GoToPoseLidar(config, robot())
    beams = config.lidar.sectors
    assert task.observation_space.shape == (3 * beams + 4,)
    context = task.begin(frame(0.0, ahead_m=2.0))
    obs = [task.observe(frame(0.1 * i, ahead_m=a), context, np.zeros(2))
           for i, a in enumerate((2.0, 1.5, 1.0, 0.5))]
    assert all(task.observation_space.contains(o) for o in obs)
    ahead = [[o[k * beams + beams // 2] for k in range(3)] for o in obs]
    assert ahead == [[2.0, 2.0, 2.0], [1.5, 2.0, 2.0], [1.0, 1.5, 2.0], [0.5, 1.0, 1.5]]
    np.testing.assert_allclose(obs[-1][-4:-2], [2.7, 0.0], atol=1e-6)
    fresh = task.begin(frame(0.0, ahead_m=3.0))
    again = task.observe(frame(0.0, ahead_m=3.0), fresh, np.zeros(2))
    assert [again[k * beams + beams // 2] for k in range(3)] == [3.0, 3.0, 3.0]
