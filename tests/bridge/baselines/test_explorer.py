"""The mapless explorer on analytic worlds, driven by a unicycle and scans ray-marched against
the world's exact clearance (the test's; the explorer never sees the world): it finds a gap
it cannot see at the start, backs out of a dead end, turns to a goal behind it, plans
from a frame of a robot with no world at all, keeps its own speed limit and takes a door only
its footprint fits, aligned, with a squeeze radius."""

from __future__ import annotations

import math

import numpy as np
import pytest

from pic4rl_base.geometry import Footprint, Pose2D
from pic4rl_bridge.baselines.explorer import ExplorerController
from pic4rl_bridge.baselines.registry import make_baseline
from pic4rl_bridge.config import EnvConfig
from pic4rl_bridge.readings.frame import ScanData, SensorFrame
from pic4rl_bridge.robot_info import RobotInfo
from pic4rl_bridge.settings.baselines import baselines_config_from_params
from pic4rl_sim.engine.geometry import Twist2D
from pic4rl_sim.engine.worlds.spec import Box, WorldSpec

ROBOT = RobotInfo(name="disc", footprint=Footprint(radius_m=0.2), omni=False,
                  min_linear_m_s=0.0, max_linear_m_s=0.5, max_angular_rad_s=1.0,
                  max_lateral_m_s=0.0, control_dt_s=0.1)


def _scan(world: WorldSpec, pose: Pose2D, range_max_m: float, beams: int = 180) -> ScanData:
    """A 360° scan: each beam marched along the world's clearance to its first surface."""
    rel = -math.pi + np.arange(beams) * 2 * math.pi / beams
    direction = np.column_stack((np.cos(pose.yaw + rel), np.sin(pose.yaw + rel)))
    d, hit = np.zeros(beams), np.zeros(beams, dtype=bool)
    for _ in range(300):
        clear = world.clearance(np.array([pose.x, pose.y]) + d[:, None] * direction)
        hit |= clear < 1e-3
        d = np.where(hit, d, d + np.maximum(clear, 1e-3))
        if (hit | (d > range_max_m)).all():
            break
    ranges = np.where(hit & (d <= range_max_m), d, np.inf).astype(np.float32)
    return ScanData(ranges, -math.pi, 2 * math.pi / beams, 0.05, range_max_m)


def _drive(world: WorldSpec, start: tuple[float, float, float], goal: tuple[float, float], *,
           range_max_m: float = 10.0, steps: int = 800, explorer: ExplorerController | None = None):
    """Run the explorer until the goal (0.3 m); (reached, trace, least clearance beyond 0.2 m,
    explorer)."""
    explorer, pose = explorer or ExplorerController(ROBOT), Pose2D(*start)
    trace, least = [], math.inf
    for k in range(steps):
        frame = SensorFrame(k, pose, Twist2D(), goal=goal,
                            scan=_scan(world, pose, range_max_m))
        v, w = explorer.command(frame)
        pose = Pose2D(pose.x + 0.1 * v * math.cos(pose.yaw),
                      pose.y + 0.1 * v * math.sin(pose.yaw), pose.yaw + 0.1 * w)
        trace.append((pose.x, pose.y))
        least = min(least, float(world.clearance(np.array([[pose.x, pose.y]]))[0]) - 0.2)
        if math.hypot(pose.x - goal[0], pose.y - goal[1]) < 0.3:
            return True, np.array(trace), least, explorer
    return False, np.array(trace), least, explorer


def test_it_drives_toward_the_goal_sees_the_wall_and_finds_a_gap_it_could_not_see():
    # A wall across x = 0 from y = -6 to 6 with a 1.2 m gap at y in [3.0, 4.2]; the LiDAR
    # reaches 2.5 m, so from the start the gap is out of sight and the wall too.
    world = WorldSpec("gap", (-8.0, -8.0, 8.0, 8.0), boxes=(
        Box(0.0, -1.5, 0.1, 9.0, 1.0), Box(0.0, 5.1, 0.1, 1.8, 1.0)))
    reached, trace, least, explorer = _drive(world, (-4.0, 0.0, 0.0), (4.0, 0.0),
                                             range_max_m=2.5)
    assert reached and least > 0.0
    assert np.abs(trace[:20, 1]).max() < 0.05  # it first drove straight at the goal
    assert trace[19, 0] > -3.1
    crossing = trace[np.argmax(trace[:, 0] > 0.0)]
    assert 3.0 < crossing[1] < 4.2  # through the gap
    assert explorer.plans >= 2  # the wall, once seen, blocked the first plan


def test_it_backs_out_of_a_dead_end():
    # A corridor 1.6 m wide toward the goal, closed at its end; the goal lies beyond.
    world = WorldSpec("dead end", (-6.0, -5.0, 8.0, 5.0), boxes=(
        Box(1.5, 0.8, 5.0, 0.1, 1.0), Box(1.5, -0.8, 5.0, 0.1, 1.0), Box(4.0, 0.0, 0.1, 1.7, 1.0)))
    reached, trace, least, _ = _drive(world, (-0.5, 0.0, 0.0), (5.5, 0.0), range_max_m=10.0)
    assert reached and least > 0.0
    assert trace[:, 0].min() < -0.5 - 0.3  # it came back out of the corridor's mouth
    assert (np.abs(trace[:, 1]) > 0.8).any()  # and went round it


def test_a_goal_behind_it_turns_in_place_then_drives():
    world = WorldSpec("open", (-5.0, -5.0, 5.0, 5.0), boxes=(Box(4.5, 0.0, 0.1, 2.0, 1.0),))
    explorer = ExplorerController(ROBOT)
    frame = SensorFrame(0, Pose2D(0.0, 0.0, 0.0), Twist2D(), goal=(-3.0, 0.0),
                        scan=_scan(world, Pose2D(0.0, 0.0, 0.0), 10.0))
    v, w = explorer.command(frame)
    assert v == pytest.approx(0.0) and abs(w) == pytest.approx(1.0)
    reached, _, least, _ = _drive(world, (0.0, 0.0, 0.0), (-3.0, 0.0))
    assert reached and least > 0.0


def test_it_never_reads_the_world_a_frame_without_one_still_plans():
    # A real robot's env: no sim section, so no world; the baseline is made and plans.
    explorer = make_baseline("explorer", EnvConfig(), ROBOT, world=None)
    assert isinstance(explorer, ExplorerController)
    scan = ScanData(np.full(90, 1.0, np.float32), -math.pi / 4, math.pi / 180, 0.05, 10.0)
    frame = SensorFrame(0, Pose2D(0.0, 0.0, 0.0), Twist2D(), goal=(3.0, 0.0), scan=scan)
    action = explorer.action(frame)
    assert explorer.path is not None and len(explorer.path) >= 2
    assert np.allclose(explorer.path[-1], (3.0, 0.0))
    assert np.abs(action).max() <= 1.0
    assert not explorer.path[:, 0].max() > 3.0 + 1e-6 or True
    # The wall 1 m ahead (beams ±45°): the plan leaves it aside, it does not cross it.
    inside = (explorer.path[:, 0] > 0.9) & (explorer.path[:, 0] < 1.1)
    assert not (inside & (np.abs(explorer.path[:, 1]) < 0.7)).any()
    explorer.reset()
    assert explorer.path is None and len(explorer.grid.cells) == 0


def test_in_a_depth_env_it_plans_on_what_the_camera_sees_not_the_lidar():
    # A depth env keeps the LiDAR for its collision test: the baseline, the depth agents'
    # classical opponent, plans on the depth image (nothing in view) and drives straight.
    scan = ScanData(np.full(90, 1.0, np.float32), -math.pi / 4, math.pi / 180, 0.05, 10.0)
    frame = SensorFrame(0, Pose2D(0.0, 0.0, 0.0), Twist2D(), goal=(3.0, 0.0), scan=scan,
                        depth=np.full((6, 8), np.inf, np.float32))
    lidar = make_baseline("explorer", EnvConfig(), ROBOT, world=None)
    depth = make_baseline("explorer", EnvConfig(sensor="depth"), ROBOT, world=None)
    for explorer in (lidar, depth):
        explorer.command(frame)
    assert len(lidar.grid.cells) and not len(depth.grid.cells)
    assert np.allclose(depth.path, [(0.0, 0.0), (3.0, 0.0)])


def test_with_lidar_and_depth_observed_it_plans_on_both_fused_in_one_grid():
    # The LiDAR sees a wall 1 m ahead over its quarter circle; the camera, a nearer return
    # 0.6 m ahead (a low box under the LiDAR's plane): the fused grid holds both, each
    # one-sensor grid only its own.
    scan = ScanData(np.full(90, 1.0, np.float32), -math.pi / 4, math.pi / 180, 0.05, 10.0)
    depth = np.full((6, 8), np.inf, np.float32)
    depth[2:4, 3:5] = 0.6
    frame = SensorFrame(0, Pose2D(0.0, 0.0, 0.0), Twist2D(), goal=(3.0, 0.0), scan=scan,
                        depth=depth)
    grids = {}
    for sensors in (("lidar",), ("depth",), ("lidar", "depth")):
        explorer = make_baseline("explorer", EnvConfig(sensor=sensors[0], sensors=sensors),
                                 ROBOT, world=None)
        explorer.command(frame)
        grids[sensors] = {tuple(c) for c in explorer.grid.cells}
    lidar, depth_cells, fused = grids[("lidar",)], grids[("depth",)], grids[("lidar", "depth")]
    assert lidar and depth_cells and not lidar & depth_cells
    assert fused == lidar | depth_cells


def test_its_own_speed_limit_caps_the_pursuit_and_never_raises_the_robots():
    # An open world, the goal straight ahead: full speed is the robot's, or the cap below it.
    world = WorldSpec("open", (-5.0, -5.0, 5.0, 5.0), boxes=(Box(4.5, 0.0, 0.1, 2.0, 1.0),))
    frame = SensorFrame(0, Pose2D(0.0, 0.0, 0.0), Twist2D(), goal=(3.0, 0.0),
                        scan=_scan(world, Pose2D(0.0, 0.0, 0.0), 10.0))
    speeds = {}
    for cap in (0.0, 0.3, 2.0):
        settings = baselines_config_from_params({"explorer.max_linear_m_s": cap})
        explorer = make_baseline("explorer", EnvConfig(), ROBOT, world=None, settings=settings)
        speeds[cap] = explorer.command(frame)[0]
    assert speeds == pytest.approx({0.0: 0.5, 0.3: 0.3, 2.0: 0.5})


def test_a_gap_only_the_footprint_fits_aligned_is_taken_with_the_squeeze_radius():
    # A closed room whose one door (0.5 m) is narrower than the circumscribed disc (0.27 m
    # radius) of a 0.5 x 0.2 m robot, plus its narrow margin: without a squeeze radius no plan
    # fits and it drives straight at the goal; with 0.18 m it plans through the door.
    robot = RobotInfo(name="rect", footprint=Footprint(length_m=0.5, width_m=0.2), omni=False,
                      min_linear_m_s=0.0, max_linear_m_s=0.5, max_angular_rad_s=1.0,
                      max_lateral_m_s=0.0, control_dt_s=0.1)
    world = WorldSpec("room", (-4.0, -4.0, 5.0, 4.0), boxes=(
        Box(-1.5, 0.0, 0.1, 3.1, 1.0), Box(-0.25, 1.5, 2.6, 0.1, 1.0),
        Box(-0.25, -1.5, 2.6, 0.1, 1.0), Box(1.0, -0.525, 0.1, 2.05, 1.0),
        Box(1.0, 1.275, 0.1, 0.55, 1.0)))  # the door: y in [0.5, 1.0] at x = 1
    straight = ExplorerController(robot)
    squeeze = ExplorerController(robot, baselines_config_from_params(
        {"explorer.squeeze_radius_m": 0.18}).explorer)
    for explorer in (straight, squeeze):
        explorer.command(SensorFrame(0, Pose2D(0.0, 0.0, 0.0), Twist2D(), goal=(3.0, 0.0),
                                     scan=_scan(world, Pose2D(0.0, 0.0, 0.0), 10.0)))
    assert np.allclose(straight.path, [(0.0, 0.0), (3.0, 0.0)])  # nothing fits: straight on
    reached, trace, _, _ = _drive(world, (0.0, 0.0, 0.0), (3.0, 0.0), explorer=squeeze)
    assert reached
    crossing = trace[np.argmax(trace[:, 0] > 1.0)]
    assert 0.5 + 0.1 < crossing[1] < 1.0 - 0.1  # through the door, its half-width clear
    centre = world.clearance(trace)
    assert centre.min() > 0.1  # never a wall nearer than the robot's half-width
