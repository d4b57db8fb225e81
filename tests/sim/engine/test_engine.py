"""The engine against analytic motion: arcs, strafing, ramps, walls, determinism, divergence."""

from __future__ import annotations

import math

import numpy as np
import pytest

from pic4rl_base.errors import ConfigError
from pic4rl_sim.engine.core import Engine, EngineConfig, limit_command
from pic4rl_base.geometry import Pose2D
from pic4rl_sim.engine.geometry import Twist2D
from pic4rl_sim.engine.robot_specs import BURGER, HUSKY, JACKAL, OMNI, LidarSpec
from pic4rl_sim.engine.worlds.spec import Box, Cylinder, PersonSpec, WorldSpec
from pic4rl_sim.errors import WorldError


def open_field(*boxes: Box, cylinders: tuple[Cylinder, ...] = (), person: PersonSpec | None = None
               ) -> WorldSpec:
    return WorldSpec("field", (-20.0, -20.0, 20.0, 20.0), boxes=boxes, cylinders=cylinders,
                     person=person)


def drive(engine: Engine, command: Twist2D, seconds: float) -> None:
    for _ in range(round(seconds / engine.config.control_dt_s)):
        engine.step(command)


def relative(a: Pose2D, b: Pose2D) -> tuple[float, float, float]:
    """``b`` in the frame of ``a``."""
    dx, dy = b.x - a.x, b.y - a.y
    c, s = math.cos(a.yaw), math.sin(a.yaw)
    return c * dx + s * dy, -s * dx + c * dy, math.remainder(b.yaw - a.yaw, math.tau)


@pytest.mark.parametrize("robot", [JACKAL, HUSKY, BURGER], ids=lambda r: r.name)
def test_differential_drive_follows_the_analytic_arc(robot):
    engine = Engine(robot, open_field(), seed=1)
    engine.reset(start=Pose2D(0, 0, 0.3), goal=(5, 5))
    v, w, seconds = 0.8 * robot.max_linear_m_s, 0.5, 4.0
    drive(engine, Twist2D(v, 0, w), 1.0)  # past the acceleration ramp
    p0 = engine.robot_pose()
    drive(engine, Twist2D(v, 0, w), seconds)
    dx, dy, dyaw = relative(p0, engine.robot_pose())
    radius = v / w
    # Tolerance: the servos lag by their time constant and the wheels slip sideways by
    # v·w·tau, a few millimetres over the arc.
    assert dyaw == pytest.approx(w * seconds, abs=0.01)
    assert dx == pytest.approx(radius * math.sin(w * seconds), abs=0.02)
    assert dy == pytest.approx(radius * (1 - math.cos(w * seconds)), abs=0.02)
    twist = engine.robot_twist()
    assert twist.vx == pytest.approx(v, rel=1e-3)
    assert twist.wz == pytest.approx(w, rel=1e-3)
    assert abs(twist.vy) < 0.01


def test_a_commanded_step_gives_a_ramp_at_the_acceleration_limit():
    engine = Engine(JACKAL, open_field(), seed=1)
    engine.reset(start=Pose2D(0, 0, 0), goal=(5, 5))
    speeds = []
    for _ in range(8):
        engine.step(Twist2D(JACKAL.max_linear_m_s, 0, 0))
        speeds.append(engine.robot_twist().vx)
    accel = JACKAL.max_linear_accel_m_s2
    dt = engine.config.control_dt_s
    ramp = [min(accel * dt * (k + 1), JACKAL.max_linear_m_s) for k in range(8)]
    assert speeds[0] < 0.2 * JACKAL.max_linear_m_s  # no teleporting to the commanded speed
    assert speeds == pytest.approx(ramp, abs=0.03)
    # Distance of a trapezoidal profile: v·T − v²/(2a) once the ramp is over.
    x = engine.robot_pose().x
    v, t = JACKAL.max_linear_m_s, 8 * dt
    assert x == pytest.approx(v * t - v * v / (2 * accel), abs=0.03)


def test_omni_strafes_sideways_without_turning():
    engine = Engine(OMNI, open_field(), seed=1)
    engine.reset(start=Pose2D(1, 1, math.pi / 2), goal=(5, 5))
    drive(engine, Twist2D(0, 0.5, 0), 3.0)
    dx, dy, dyaw = relative(Pose2D(1, 1, math.pi / 2), engine.robot_pose())
    ramp = 0.5 * 0.5 / (2 * OMNI.max_linear_accel_m_s2)
    assert dy == pytest.approx(0.5 * 3.0 - ramp, abs=0.02)
    assert abs(dx) < 1e-3 and abs(dyaw) < 1e-3
    drive(engine, Twist2D(0.3, -0.3, 0), 2.0)
    twist = engine.robot_twist()
    assert (twist.vx, twist.vy) == pytest.approx((0.3, -0.3), abs=1e-3)


def test_differential_drive_cannot_strafe():
    engine = Engine(JACKAL, open_field(), seed=1)
    engine.reset(start=Pose2D(0, 0, 0), goal=(5, 5))
    drive(engine, Twist2D(0, 1.0, 0), 2.0)
    pose = engine.robot_pose()
    assert abs(pose.y) < 1e-3 and abs(pose.x) < 1e-3


def test_a_wall_stops_the_robot_by_contact():
    wall = Box(3.0, 0.0, 0.2, 4.0, 1.0)  # face at x = 2.9
    engine = Engine(JACKAL, open_field(wall), seed=1)
    engine.reset(start=Pose2D(0, 0, 0), goal=(-5, 5))
    assert not engine.in_collision()
    results = [engine.step(Twist2D(1.0, 0, 0)) for _ in range(60)]
    assert results[0].collided is False
    assert results[-1].collided is True and not results[-1].diverged
    front = engine.robot_pose().x + JACKAL.footprint.length_m / 2
    assert front == pytest.approx(2.9, abs=0.02)  # pressed against the face, not through it
    assert abs(engine.robot_twist().vx) < 0.05
    drive(engine, Twist2D(-0.5, 0, 0), 1.0)  # backing off frees it
    assert not engine.in_collision()


def test_the_person_walks_each_leg_at_its_own_speed():
    """A 4 m square walked at 1, 2, 1 and 0.5 m/s: 4 + 2 + 4 + 8 = 18 s a lap."""
    walk = PersonSpec(((0, 0), (4, 0), (4, 4), (0, 4)), leg_speeds_m_s=(1.0, 2.0, 1.0, 0.5))
    for t, xy, velocity in [(1.0, (1, 0), (1, 0)), (5.0, (4, 2), (0, 2)),
                            (8.0, (2, 4), (-1, 0)), (14.0, (0, 2), (0, -0.5)),
                            (19.0, (1, 0), (1, 0))]:
        pose, v = walk.pose_at(t)
        assert (pose.x, pose.y) == pytest.approx(xy) and v == pytest.approx(velocity)
    with pytest.raises(ConfigError, match=r"person\.leg_speeds_m_s"):
        PersonSpec(((0, 0), (4, 0)), leg_speeds_m_s=(1.0,))


def test_the_walking_person_moves_and_bumps_into_a_standing_robot():
    person = PersonSpec(((2.0, -3.0), (2.0, 3.0)), speed_m_s=1.0)
    engine = Engine(OMNI, open_field(person=person), seed=1)
    engine.reset(start=Pose2D(2.0, 0.0, 0.0), goal=(-5, 5))
    first, _ = engine.person_pose()
    assert not engine.step(Twist2D()).collided
    later, velocity = engine.person_pose()
    assert (later.y - first.y) == pytest.approx(0.1, abs=1e-9)
    assert velocity == pytest.approx((0.0, 1.0))
    # The person reaches the robot (0.25 m + 0.25 m radii) after 2.5 s of walking.
    hits = [engine.step(Twist2D()).collided for _ in range(30)]
    assert not any(hits[:20]) and any(hits[20:])
    assert engine.robot_pose().y > 0.05  # pushed along, not walked through


def test_same_seed_same_commands_same_states_and_sensors():
    robot = JACKAL.with_sensors(lidar=LidarSpec(beams=90, noise_std_m=0.02, dropout_prob=0.05))
    world = open_field(Box(3, 0, 0.2, 4, 1), cylinders=(Cylinder(-2, 1, 0.3, 1),))
    commands = np.random.default_rng(7).uniform(-1, 1, size=(30, 3))
    runs = []
    for _ in range(2):
        engine = Engine(robot, world, seed=11)
        trace = []
        for vx, vy, wz in commands:
            engine.step(Twist2D(vx, vy, wz))
            trace.append((engine.robot_pose(), engine.scan().copy(), engine.imu_reading(),
                          engine.wheel_odometry()))
        runs.append((engine.start, engine.goal, trace))
    (start_a, goal_a, a), (start_b, goal_b, b) = runs
    assert (start_a, goal_a) == (start_b, goal_b)
    for (pose_a, scan_a, imu_a, odom_a), (pose_b, scan_b, imu_b, odom_b) in zip(a, b):
        assert pose_a == pose_b and imu_a == imu_b and odom_a == odom_b
        np.testing.assert_array_equal(scan_a, scan_b)
    other = Engine(robot, world, seed=12)
    assert (other.start, other.goal) != (start_a, goal_a)


def test_reset_restarts_the_episode():
    engine = Engine(JACKAL, open_field(), seed=3)
    start, goal = engine.start, engine.goal
    drive(engine, Twist2D(1.0, 0, 0.5), 2.0)
    engine.reset()
    assert engine.robot_pose() == pytest.approx(start) and engine.goal == goal
    assert engine.episode_time_s == 0 and engine.robot_twist() == (0, 0, 0)
    engine.reset(seed=4)
    assert (engine.start, engine.goal) != (start, goal)


def test_a_diverged_state_resets_the_episode(caplog):
    engine = Engine(JACKAL, open_field(), seed=3)
    drive(engine, Twist2D(1.0, 0, 0), 1.0)
    engine.data.qvel[engine.ids.dof_x] = 1e9
    result = engine.step(Twist2D(1.0, 0, 0))
    assert result.diverged
    assert engine.robot_pose() == pytest.approx(engine.start)
    assert "diverged" in caplog.text
    engine.data.qpos[engine.ids.qpos_x] = math.nan
    assert engine.step(Twist2D()).diverged
    assert all(math.isfinite(v) for v in engine.robot_pose())
    assert not engine.step(Twist2D(0.5, 0, 0)).diverged


@pytest.mark.parametrize("bad", [math.nan, math.inf, -math.inf])
def test_non_finite_commands_stop_the_robot(bad):
    checked = limit_command(Twist2D(bad, 0, 0.2), JACKAL)
    assert checked.command == Twist2D() and "non-finite" in checked.problem
    engine = Engine(JACKAL, open_field(), seed=3)
    drive(engine, Twist2D(1.0, 0, 0), 1.0)
    drive(engine, Twist2D(bad, bad, bad), 2.0)
    assert engine.robot_twist().vx == pytest.approx(0, abs=1e-3)


def test_absurd_commands_are_clamped_to_the_limits():
    checked = limit_command(Twist2D(1e9, 3.0, -1e9), JACKAL)
    assert checked.command == Twist2D(JACKAL.max_linear_m_s, 0.0, -JACKAL.max_angular_rad_s)
    assert "clamped" in checked.problem
    assert limit_command(Twist2D(0.5, 0, 0.1), JACKAL).problem is None
    engine = Engine(JACKAL, open_field(), seed=3)
    drive(engine, Twist2D(1e9, 0, 0), 3.0)
    assert engine.robot_twist().vx == pytest.approx(JACKAL.max_linear_m_s, rel=1e-3)


def test_timing_must_be_consistent():
    with pytest.raises(ConfigError, match="control_dt_s.*whole multiple"):
        EngineConfig(physics_dt_s=0.004, control_dt_s=0.01)
    with pytest.raises(ConfigError, match="physics_dt_s"):
        EngineConfig(physics_dt_s=-1)
    assert EngineConfig(physics_dt_s=0.005, control_dt_s=0.1).substeps == 20


def test_a_given_start_gets_a_goal_far_enough_and_a_failed_reset_changes_nothing():
    world = WorldSpec("room", (-5.0, -5.0, 5.0, 5.0))
    engine = Engine(JACKAL, world, EngineConfig(min_goal_distance_m=6.0), seed=2)
    for seed in range(5):
        engine.reset(seed=seed, start=Pose2D(-4, -4, 0))
        assert math.hypot(engine.goal[0] + 4, engine.goal[1] + 4) >= 6.0
    before = (engine.seed, engine.start, engine.goal)
    noise_state = engine._rng["lidar"].bit_generator.state
    with pytest.raises(WorldError, match="goal"):
        engine.reset(seed=99, goal=(50.0, 0.0))  # outside the world
    with pytest.raises(WorldError, match="start"):
        engine.reset(seed=99, start=Pose2D(9.0, 0.0, 0.0))
    assert (engine.seed, engine.start, engine.goal) == before
    assert engine._rng["lidar"].bit_generator.state == noise_state


def test_every_sensor_kind_is_built_and_read_through_the_table():
    """``SENSOR_TABLE`` (sensors) is the robot's sensors' one table: a robot holds one spec per
    kind in its order, gets one engine sensor per spec it carries, and ``read`` of each equals
    its named reader on the same noise stream."""
    from pic4rl_sim.engine.robot_specs import DepthCameraSpec, ImuSpec
    from pic4rl_sim.engine.sensors import SENSOR_TABLE
    from pic4rl_sim.engine.sensor_kinds.sonar import SonarSpec
    from pic4rl_sim.engine.sensor_kinds.stereo import StereoCameraSpec
    from pic4rl_sim.engine.sensor_kinds.uwb import UwbSpec

    assert list(JACKAL.sensors) == [k.name for k in SENSOR_TABLE]
    robot = JACKAL.with_sensors(lidar=LidarSpec(beams=30, noise_std_m=0.02),
                                depth=DepthCameraSpec(width=8, height=6, noise_std_m=0.02),
                                imu=ImuSpec(gyro_noise_std_rad_s=0.1), sonar=SonarSpec(),
                                uwb=UwbSpec(), stereo=StereoCameraSpec(width=8, height=6))
    engine = Engine(robot, open_field(Box(2.0, 0.0, 0.2, 2.0, 1.0)), seed=4)
    assert set(engine.sensors) == {k.name for k in SENSOR_TABLE}
    named = {"lidar": engine.scan, "depth": engine.depth_image, "imu": engine.imu_reading}
    for name, reader in named.items():
        engine.reset(seed=4)
        by_name = reader()
        engine.reset(seed=4)
        again = engine.read(name)
        if name == "imu":  # a reading of three tuples
            assert again == by_name and by_name.angular_velocity_xyz[2] != 0.0  # noisy gyro
        else:
            assert again.dtype == by_name.dtype
            np.testing.assert_array_equal(again, by_name)
    no_depth = Engine(JACKAL, open_field(), seed=0)
    assert "depth" not in no_depth.sensors and no_depth.depth is None
    with pytest.raises(ConfigError, match="robot.depth"):
        no_depth.read("depth")
