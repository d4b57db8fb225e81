"""The ``dynbarn`` world and its moving obstacles in the engine: the same variant and episode
seed give the same motion, speeds stay in their range and obstacles in the field, headings
turn smoothly but at the field's edges, the LiDAR sees a moving obstacle where its trajectory
has taken it, touching one is a collision, and the world carries BARN's start, goal and a
reference path for the BARN score."""

from __future__ import annotations

import numpy as np
import pytest

from pic4rl_base.errors import ConfigError
from pic4rl_base.geometry import Pose2D
from pic4rl_sim.engine.core import Engine
from pic4rl_sim.engine.geometry import Twist2D
from pic4rl_sim.engine.robot_specs import JACKAL
from pic4rl_sim.engine.worlds.barn import start_and_goal
from pic4rl_sim.engine.worlds.dynbarn import FIELD, TEST_SCENES
from pic4rl_sim.engine.worlds.generators import make_world
from pic4rl_sim.engine.worlds.spec import MovingObstacles, WorldSpec

STILL = Twist2D(0.0, 0.0, 0.0)


def _tracks(variant: int, seed: int, steps: int, **params) -> np.ndarray:
    """Where the moving obstacles' bodies are (steps × n × 2) over ``steps`` control steps."""
    engine = Engine(JACKAL, make_world("dynbarn", seed=variant, **params), seed=seed)
    tracks = []
    for _ in range(steps):
        engine.step(STILL)
        tracks.append(engine.data.mocap_pos[list(engine.ids.mover_mocap), :2].copy())
    return np.array(tracks)


def test_the_same_variant_and_seed_give_the_same_motion_and_others_differ():
    a, b = _tracks(7, 1, 40), _tracks(7, 1, 40)
    np.testing.assert_array_equal(a, b)
    other_seed, other_variant = _tracks(7, 2, 40), _tracks(8, 1, 40)
    assert np.abs(a[0] - other_seed[0]).max() < 0.2  # the same starts, drawn from the variant
    assert np.abs(a[-1] - other_seed[-1]).max() > 0.3  # then the episode's own motion
    assert np.abs(a[0] - other_variant[0]).max() > 0.5


@pytest.mark.parametrize(("low", "high", "turn"), [(0.1, 1.5, 0.5), (1.2, 1.5, 5.0)])
def test_speeds_stay_in_their_range_and_obstacles_in_the_field(low, high, turn):
    world = make_world("dynbarn", seed=3, moving_count=20, speed_min_m_s=low,
                       speed_max_m_s=high, turn_time_s=turn)
    engine = Engine(JACKAL, world, seed=4)
    mocap, r = list(engine.ids.mover_mocap), world.moving.radius_m
    last = engine.data.mocap_pos[mocap, :2].copy()
    speeds, steps = [], []
    for _ in range(600):  # a minute
        engine.step(STILL)
        now = engine.data.mocap_pos[mocap, :2].copy()
        speeds.append(engine.movers.speed.copy())
        steps.append(np.hypot(*(now - last).T) / engine.config.control_dt_s)
        assert (now >= np.array(FIELD[:2]) + r - 1e-9).all()
        assert (now <= np.array(FIELD[2:]) - r + 1e-9).all()
        last = now
    speeds, steps = np.array(speeds), np.array(steps)
    assert speeds.min() >= low and speeds.max() <= high
    assert steps.max() <= high + 1e-9  # a bounce only shortens a step
    assert np.median(steps) > low  # they do move
    assert speeds.std(axis=0).min() > 0.0  # each one's speed varies


def test_trajectories_turn_smoothly_away_from_the_edges():
    """With ``turn_time_s`` 5 the turn rate's deviation is 0.2 rad/s: a heading moves a few
    hundredths of a radian per 0.1 s step, never a corner, but where it bounces."""
    tracks = _tracks(2, 3, 300, moving_count=20, speed_min_m_s=0.5, turn_time_s=5.0)
    step = np.diff(tracks, axis=0)  # (steps - 1) x n x 2
    heading = np.arctan2(step[..., 1], step[..., 0])
    turn = np.abs(np.angle(np.exp(1j * np.diff(heading, axis=0))))
    margin = 0.15 + 0.2  # the radius and a step at the top speed and more
    lo, hi = np.array(FIELD[:2]) + margin, np.array(FIELD[2:]) - margin
    inside = ((tracks[1:-1] > lo) & (tracks[1:-1] < hi)).all(axis=-1)
    assert inside.mean() > 0.5 and turn[inside].max() < 0.15
    assert turn[~inside].max() > 0.5  # they do bounce


def _lane(start_x: float, heading: float, speed: float) -> WorldSpec:
    """An open arena with one obstacle held to the line y = 0 between x = -4 and 4 m."""
    r = 0.15
    moving = MovingObstacles((-4.0, -r - 1e-4, 4.0, r + 1e-4), ((start_x, 0.0),), (heading,),
                             (speed,), (speed, speed), turn_time_s=20.0, radius_m=r)
    return WorldSpec("lane", (-5.0, -5.0, 5.0, 5.0), moving=moving)


def test_the_lidar_sees_a_moving_obstacle_where_its_trajectory_took_it():
    engine = Engine(JACKAL, _lane(1.5, 0.0, 1.0), seed=0)
    engine.reset(start=Pose2D(0.0, 0.0, 0.0))
    lidar = JACKAL.lidar
    assert lidar is not None
    angles = lidar.angle_min_rad + np.arange(lidar.beams) * lidar.angle_increment_rad
    ahead = int(np.argmin(np.abs(angles + lidar.mount_yaw_rad)))
    first = engine.scan()[ahead]
    assert first == pytest.approx(1.5 - 0.15 - lidar.mount_xyz_m[0], abs=1e-3)
    for _ in range(10):  # one second at 1 m/s, away from the robot
        engine.step(STILL)
    x = float(engine.movers.pos[0, 0])
    assert x == pytest.approx(2.5, abs=0.01)
    assert engine.scan()[ahead] == pytest.approx(x - 0.15 - lidar.mount_xyz_m[0], abs=1e-3)


def test_touching_a_moving_obstacle_is_a_collision():
    engine = Engine(JACKAL, _lane(3.5, np.pi, 1.0), seed=0)
    engine.reset(start=Pose2D(0.0, 0.0, 0.0))
    early = [engine.step(STILL).collided for _ in range(15)]  # it is 2 m off at 1.5 s
    late = [engine.step(STILL).collided for _ in range(20)]
    assert not any(early)
    assert any(late)


def test_the_world_has_barns_start_goal_and_a_reference_path():
    world = make_world("dynbarn", seed=TEST_SCENES[1])
    start, goal = start_and_goal()
    assert world.spawn_poses == (start,) and world.goal_points == (goal,)
    assert world.params["reference_path_length_m"] >= 10.0  # the goal is 10 m ahead
    assert len(world.moving.starts) == 6
    assert len(TEST_SCENES) == 60 and len(set(TEST_SCENES)) == 60


@pytest.mark.bad_input
def test_a_speed_range_upside_down_is_refused():
    with pytest.raises(ConfigError, match="world.dynbarn.speed_min_m_s"):
        make_world("dynbarn", seed=0, speed_min_m_s=1.0, speed_max_m_s=0.5)
    with pytest.raises(ConfigError, match="world.dynbarn.speed_max_m_s"):
        make_world("dynbarn", seed=0, speed_max_m_s=2.0)
