"""Sensors against analytic answers: rooms, cylinders, walls and floors built inline."""

from __future__ import annotations

import math

import mujoco
import numpy as np
import pytest

from pic4rl_base.geometry import Pose2D, wrap_angle, yaw_to_quaternion
from pic4rl_sim.engine.robot_specs import DepthCameraSpec, ImuSpec, LidarSpec, OdometrySpec
from pic4rl_sim.engine.sensors import (EXACT_VARIANCE, STANDARD_GRAVITY_M_S2, DepthCamera, Imu,
                                       Lidar, WheelOdometry)

ROOM = """
<geom type="box" pos="2.1 0 1" size="0.1 2.2 1"/>
<geom type="box" pos="-2.1 0 1" size="0.1 2.2 1"/>
<geom type="box" pos="0 2.1 1" size="2.2 0.1 1"/>
<geom type="box" pos="0 -2.1 1" size="2.2 0.1 1"/>
"""


def world(geoms: str = "",
          robot: Pose2D = Pose2D(0.0, 0.0, 0.0)) -> tuple[mujoco.MjModel, mujoco.MjData, int]:
    """A floor, ``geoms``, and a robot whose box encloses every sensor mount used here."""
    xml = f"""<mujoco><compiler angle="radian"/><worldbody>
      <geom name="floor" type="plane" size="0 0 1"/>{geoms}
      <body name="robot" pos="{robot.x} {robot.y} 0" euler="0 0 {robot.yaw}">
        <geom type="box" size="0.3 0.3 0.3" pos="0 0 0.3"/>
      </body></worldbody></mujoco>"""
    model = mujoco.MjModel.from_xml_string(xml)
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    return model, data, model.body("robot").id


def room_ranges(x0: float, y0: float, angles: np.ndarray, half_m: float = 2.0) -> np.ndarray:
    """Distance from (x0, y0) along each angle to the walls of a square room at ±half_m."""
    c, s = np.cos(angles), np.sin(angles)
    with np.errstate(divide="ignore"):
        tx = np.where(c > 0, (half_m - x0) / c, np.where(c < 0, (-half_m - x0) / c, np.inf))
        ty = np.where(s > 0, (half_m - y0) / s, np.where(s < 0, (-half_m - y0) / s, np.inf))
    return np.minimum(tx, ty)


def rng(seed: int = 0) -> np.random.Generator:
    return np.random.default_rng(seed)


# --- LiDAR ---------------------------------------------------------------------------------

@pytest.mark.parametrize("pose", [Pose2D(0, 0, 0), Pose2D(0.4, -0.3, 0.7), Pose2D(-1, 1.2, -2.9)])
@pytest.mark.parametrize("mount_yaw", [0.0, math.pi / 2, -1.0])
def test_lidar_in_square_room_matches_ray_wall_distance(pose: Pose2D, mount_yaw: float) -> None:
    model, data, robot = world(ROOM, pose)
    spec = LidarSpec(beams=360, range_max_m=10.0, mount_xyz_m=(0.1, 0.05, 0.3),
                     mount_yaw_rad=mount_yaw)
    ranges = Lidar(model, spec, exclude_body=robot).read(data, pose, rng())
    c, s = math.cos(pose.yaw), math.sin(pose.yaw)
    x0, y0 = pose.x + c * 0.1 - s * 0.05, pose.y + s * 0.1 + c * 0.05
    angles = pose.yaw + mount_yaw + spec.angle_min_rad + np.arange(360) * spec.angle_increment_rad
    assert ranges.dtype == np.float32 and ranges.shape == (360,)
    np.testing.assert_allclose(ranges, room_ranges(x0, y0, angles), rtol=0, atol=1e-6)


def test_lidar_sees_cylinder_ahead_with_chord_distances() -> None:
    d_m, r_m = 3.0, 0.5
    model, data, robot = world(f'<geom type="cylinder" pos="{d_m} 0 0.5" size="{r_m} 0.5"/>')
    spec = LidarSpec(beams=360, range_max_m=10.0, mount_xyz_m=(0.0, 0.0, 0.3))
    lidar = Lidar(model, spec, exclude_body=robot)
    ranges = lidar.read(data, Pose2D(0, 0, 0), rng())
    angles = spec.angle_min_rad + np.arange(360) * spec.angle_increment_rad
    forward = int(np.argmin(np.abs(angles)))
    assert ranges[forward] == pytest.approx(d_m - r_m, abs=1e-6)
    perp = d_m * np.abs(np.sin(angles))
    sees = (perp < r_m) & (np.cos(angles) > 0)
    chord = d_m * np.cos(angles) - np.sqrt(np.maximum(r_m**2 - perp**2, 0.0))
    assert sees.sum() == 19  # ±9 beams of 1° within asin(0.5/3) = 9.6°
    np.testing.assert_allclose(ranges[sees], chord[sees], atol=1e-6)
    assert np.all(np.isposinf(ranges[~sees]))


def test_lidar_never_sees_its_own_robot() -> None:
    model, data, robot = world()  # the robot's box encloses the mount
    ranges = Lidar(model, LidarSpec(mount_xyz_m=(0.1, 0.0, 0.3)), exclude_body=robot).read(
        data, Pose2D(0, 0, 0), rng())
    assert np.all(np.isposinf(ranges))


def test_lidar_beyond_range_max_is_inf_and_too_close_is_minus_inf() -> None:
    geoms = ('<geom type="cylinder" pos="12 0 0.5" size="0.5 0.5"/>'
             '<geom type="box" pos="0 0.45 0.5" size="0.2 0.05 0.5"/>')
    model, data, robot = world(geoms)
    spec = LidarSpec(beams=360, range_min_m=0.5, range_max_m=10.0, mount_xyz_m=(0, 0, 0.3))
    ranges = Lidar(model, spec, exclude_body=robot).read(data, Pose2D(0, 0, 0), rng())
    angles = spec.angle_min_rad + np.arange(360) * spec.angle_increment_rad
    assert np.isposinf(ranges[np.argmin(np.abs(angles))])  # cylinder at 11.5 m
    assert np.isneginf(ranges[np.argmin(np.abs(angles - math.pi / 2))])  # box at 0.4 m
    assert np.isneginf(ranges).sum() > 10 and np.isfinite(ranges).sum() == 0


def test_lidar_mount_yaw_rotates_the_scan() -> None:
    model, data, robot = world(ROOM)
    pose = Pose2D(0.5, -0.2, 0.3)
    plain = Lidar(model, LidarSpec(beams=360, mount_xyz_m=(0.1, 0, 0.3)), exclude_body=robot)
    turned = Lidar(model, LidarSpec(beams=360, mount_xyz_m=(0.1, 0, 0.3),
                                    mount_yaw_rad=math.pi / 2), exclude_body=robot)
    r0, r90 = plain.read(data, pose, rng()), turned.read(data, pose, rng())
    np.testing.assert_allclose(r90, np.roll(r0, -90), atol=1e-5)


def test_lidar_pose_yaw_rotates_the_scan() -> None:
    model, data, robot = world(ROOM)
    lidar = Lidar(model, LidarSpec(beams=360, mount_xyz_m=(0, 0, 0.3)), exclude_body=robot)
    r0 = lidar.read(data, Pose2D(0.7, 0.3, 0.0), rng())
    r45 = lidar.read(data, Pose2D(0.7, 0.3, math.radians(45)), rng())
    np.testing.assert_allclose(r45, np.roll(r0, -45), atol=1e-5)
    assert r0[180] == pytest.approx(2.0 - 0.7, abs=1e-6)  # beam 180 looks straight ahead


def test_lidar_partial_fov_reports_laser_scan_angles() -> None:
    model, data, robot = world(ROOM)
    spec = LidarSpec(beams=181, fov_deg=180.0, range_min_m=0.05, mount_xyz_m=(0, 0, 0.3))
    lidar = Lidar(model, spec, exclude_body=robot)
    assert lidar.angle_min_rad == pytest.approx(-math.pi / 2)
    assert lidar.angle_max_rad == pytest.approx(math.pi / 2)
    assert lidar.angle_increment_rad == pytest.approx(math.pi / 180)
    assert (lidar.range_min_m, lidar.range_max_m, lidar.frame_id) == (0.05, 10.0, "laser")
    ranges = lidar.read(data, Pose2D(0.5, 0.5, 0.0), rng())
    assert ranges[0] == pytest.approx(2.5, abs=1e-6) and ranges[-1] == pytest.approx(1.5, abs=1e-6)


def test_lidar_noise_is_unbiased_with_the_configured_std_and_seeded() -> None:
    model, data, robot = world(ROOM)
    pose = Pose2D(0.2, 0.1, 0.4)
    exact = Lidar(model, LidarSpec(mount_xyz_m=(0, 0, 0.3)), exclude_body=robot)
    noisy = Lidar(model, LidarSpec(mount_xyz_m=(0, 0, 0.3), noise_std_m=0.05),
                  exclude_body=robot)
    truth = exact.read(data, pose, rng())
    gen = rng(7)
    errors = np.stack([noisy.read(data, pose, gen) - truth for _ in range(50)]).astype(float)
    assert abs(errors.mean()) < 4 * 0.05 / math.sqrt(errors.size)
    assert errors.std() == pytest.approx(0.05, rel=0.05)
    np.testing.assert_array_equal(noisy.read(data, pose, rng(3)), noisy.read(data, pose, rng(3)))


def test_lidar_without_noise_leaves_the_rng_alone() -> None:
    model, data, robot = world(ROOM)
    gen = rng(5)
    before = gen.bit_generator.state
    Lidar(model, LidarSpec(), exclude_body=robot).read(data, Pose2D(0, 0, 0), gen)
    assert gen.bit_generator.state == before


def test_lidar_dropout_turns_beams_into_no_return() -> None:
    model, data, robot = world(ROOM)
    lidar = Lidar(model, LidarSpec(dropout_prob=0.3), exclude_body=robot)
    gen = rng(11)
    scans = np.stack([lidar.read(data, Pose2D(0, 0, 0), gen) for _ in range(20)])
    assert np.isposinf(scans).mean() == pytest.approx(0.3, abs=0.03)
    assert np.all(np.isfinite(scans) | np.isposinf(scans))


# --- Depth camera ---------------------------------------------------------------------------

WALL_AHEAD = '<geom type="box" pos="4.1 0 5" size="0.1 20 5"/>'  # inner face at x = 4


def floor_depth(spec: DepthCameraSpec, height_m: float) -> np.ndarray:
    """Depth along the optical axis of the floor, per image row (inf above the horizon)."""
    f, cy = spec.focal_px, 0.5 * spec.height
    y_o = (np.arange(spec.height) + 0.5 - cy) / f
    down = math.sin(spec.mount_pitch_rad) + y_o * math.cos(spec.mount_pitch_rad)
    with np.errstate(divide="ignore"):
        return np.where(down > 0, height_m / down, np.inf)


@pytest.mark.parametrize("pose", [Pose2D(0, 0, 0), Pose2D(1.0, 0.5, 0.0)])
def test_depth_on_a_perpendicular_wall_is_constant_and_floor_is_analytic(pose: Pose2D) -> None:
    model, data, robot = world(WALL_AHEAD, pose)
    spec = DepthCameraSpec(mount_xyz_m=(0.2, 0.0, 0.25), max_depth_m=10.0)
    image = DepthCamera(model, spec, exclude_body=robot).read(data, pose, rng())
    assert image.shape == (60, 80) and image.dtype == np.float32
    wall = 4.0 - pose.x - 0.2
    expected = np.minimum(wall, floor_depth(spec, 0.25))[:, None].repeat(80, axis=1)
    np.testing.assert_allclose(image, expected, rtol=1e-6)
    assert (expected < wall).any() and (expected == wall).any()  # both floor and wall seen


def test_depth_follows_robot_yaw() -> None:
    pose = Pose2D(0.0, 0.0, math.pi / 2)
    model, data, robot = world('<geom type="box" pos="0 4.1 5" size="20 0.1 5"/>', pose)
    spec = DepthCameraSpec(mount_xyz_m=(0.2, 0.0, 0.25))
    image = DepthCamera(model, spec, exclude_body=robot).read(data, pose, rng())
    np.testing.assert_allclose(image[:30], 3.8, rtol=1e-6)  # upper half: all wall


def test_depth_beyond_max_is_inf() -> None:
    model, data, robot = world(WALL_AHEAD)
    spec = DepthCameraSpec(mount_xyz_m=(0.2, 0.0, 0.25), max_depth_m=3.0)
    image = DepthCamera(model, spec, exclude_body=robot).read(data, Pose2D(0, 0, 0), rng())
    floor = floor_depth(spec, 0.25)[:, None].repeat(80, axis=1)
    near = floor <= 3.0
    np.testing.assert_allclose(image[near], floor[near], rtol=1e-6)
    assert np.all(np.isposinf(image[~near])) and (~near).sum() > 80 * 30


def test_depth_too_close_is_minus_inf() -> None:
    model, data, robot = world('<geom type="box" pos="0.45 0 1" size="0.05 5 1"/>')
    spec = DepthCameraSpec(mount_xyz_m=(0.2, 0.0, 0.25), min_depth_m=0.5)
    image = DepthCamera(model, spec, exclude_body=robot).read(data, Pose2D(0, 0, 0), rng())
    assert np.all(np.isneginf(image))  # wall at 0.2 m, floor hits nearer still


def test_pitching_down_raises_the_horizon_and_keeps_floor_analytic() -> None:
    model, data, robot = world()
    level = DepthCameraSpec(mount_xyz_m=(0.2, 0.0, 0.25), max_depth_m=1000.0)
    down = DepthCameraSpec(mount_xyz_m=(0.2, 0.0, 0.25), max_depth_m=1000.0,
                           mount_pitch_rad=0.3)
    horizon = []
    for spec in (level, down):
        image = DepthCamera(model, spec, exclude_body=robot).read(data, Pose2D(0, 0, 0), rng())
        expected = floor_depth(spec, 0.25)[:, None].repeat(80, axis=1)
        expected[expected > 1000.0] = np.inf
        np.testing.assert_allclose(image, expected, rtol=1e-5)
        horizon.append(int(np.argmax(np.isfinite(image[:, 0]))))
    assert horizon[0] == 30
    assert horizon[1] == math.ceil(30 - down.focal_px * math.tan(0.3) - 0.5)


def test_depth_camera_info() -> None:
    model, _, robot = world()
    spec = DepthCameraSpec(width=80, height=60, hfov_deg=90.0)
    cam = DepthCamera(model, spec, exclude_body=robot)
    assert cam.intrinsics == pytest.approx((40.0, 40.0, 40.0, 30.0))
    assert cam.k_matrix == pytest.approx((40, 0, 40, 0, 40, 30, 0, 0, 1))
    assert cam.p_matrix == pytest.approx((40, 0, 40, 0, 0, 40, 30, 0, 0, 0, 1, 0))
    assert (cam.width, cam.height, cam.frame_id) == (80, 60, "camera_depth_optical_frame")


def test_depth_noise_is_seeded_and_unbiased() -> None:
    model, data, robot = world(WALL_AHEAD)
    truth = DepthCamera(model, DepthCameraSpec(), exclude_body=robot).read(
        data, Pose2D(0, 0, 0), rng())
    noisy = DepthCamera(model, DepthCameraSpec(noise_std_m=0.02), exclude_body=robot)
    first = noisy.read(data, Pose2D(0, 0, 0), rng(1))
    np.testing.assert_array_equal(first, noisy.read(data, Pose2D(0, 0, 0), rng(1)))
    valid = np.isfinite(truth) & np.isfinite(first)
    errors = (first[valid] - truth[valid]).astype(float)
    assert abs(errors.mean()) < 4 * 0.02 / math.sqrt(errors.size)
    assert errors.std() == pytest.approx(0.02, rel=0.1)


# --- IMU ------------------------------------------------------------------------------------

def test_imu_at_rest_reads_gravity_up_and_the_heading() -> None:
    reading = Imu(ImuSpec()).read(1.2, 0.0, (0.0, 0.0), rng())
    assert reading.linear_acceleration_xyz == (0.0, 0.0, STANDARD_GRAVITY_M_S2)
    assert reading.angular_velocity_xyz == (0.0, 0.0, 0.0)
    assert reading.orientation_xyzw == pytest.approx(yaw_to_quaternion(1.2))


def test_imu_rotates_world_acceleration_into_the_body() -> None:
    reading = Imu(ImuSpec()).read(math.pi / 2, 0.4, (0.0, 1.5), rng())
    assert reading.linear_acceleration_xyz == pytest.approx((1.5, 0.0, STANDARD_GRAVITY_M_S2))
    assert reading.angular_velocity_xyz == (0.0, 0.0, 0.4)


def test_imu_noise_and_covariances() -> None:
    imu = Imu(ImuSpec(gyro_noise_std_rad_s=0.01, accel_noise_std_m_s2=0.1))
    gen = rng(2)
    samples = [imu.read(0.0, 0.5, (1.0, 0.0), gen) for _ in range(4000)]
    wz = np.array([s.angular_velocity_xyz[2] for s in samples])
    ax = np.array([s.linear_acceleration_xyz[0] for s in samples])
    assert wz.mean() == pytest.approx(0.5, abs=0.001) and wz.std() == pytest.approx(0.01, rel=0.05)
    assert ax.mean() == pytest.approx(1.0, abs=0.01) and ax.std() == pytest.approx(0.1, rel=0.05)
    assert imu.angular_velocity_covariance[8] == pytest.approx(1e-4)
    assert imu.linear_acceleration_covariance[0] == pytest.approx(1e-2)
    assert Imu(ImuSpec()).orientation_covariance[0] == EXACT_VARIANCE
    assert imu.frame_id == "imu_link"


def test_imu_without_noise_leaves_the_rng_alone() -> None:
    gen = rng(5)
    before = gen.bit_generator.state
    Imu(ImuSpec()).read(0.3, 0.1, (0.2, 0.1), gen)
    assert gen.bit_generator.state == before


# --- Wheel odometry -------------------------------------------------------------------------

def random_walk(n: int, seed: int) -> list[Pose2D]:
    gen = rng(seed)
    poses = [Pose2D(1.0, -2.0, 3.0)]
    for _ in range(n):
        p = poses[-1]
        step = gen.normal(0.0, 0.05, 2)
        poses.append(Pose2D(p.x + step[0], p.y + step[1], p.yaw + gen.normal(0.0, 0.3)))
    return poses


def test_odometry_without_errors_follows_the_truth_exactly() -> None:
    odom = WheelOdometry(OdometrySpec())
    poses = random_walk(500, seed=4)
    odom.reset(poses[0])
    gen = rng(0)
    before = gen.bit_generator.state
    for prev, now in zip(poses, poses[1:]):
        est, _ = odom.update(prev, now, 0.05, gen)
        assert est.x == pytest.approx(now.x, abs=1e-12)
        assert est.y == pytest.approx(now.y, abs=1e-12)
        assert abs(wrap_angle(est.yaw - now.yaw)) < 1e-12
    assert gen.bit_generator.state == before
    assert (odom.frame_id, odom.child_frame_id) == ("odom", "base_link")


def test_odometry_linear_scale_error_overestimates_distance() -> None:
    odom = WheelOdometry(OdometrySpec(linear_scale_error=0.1))
    odom.reset(Pose2D(0.0, 0.0, 0.0))
    for i in range(100):
        est, twist = odom.update(Pose2D(0.1 * i, 0, 0), Pose2D(0.1 * (i + 1), 0, 0), 0.1, rng())
    assert est == pytest.approx((11.0, 0.0, 0.0))
    assert twist == pytest.approx((1.1, 0.0, 0.0))


def test_odometry_angular_scale_error_and_arc_twist() -> None:
    odom = WheelOdometry(OdometrySpec(angular_scale_error=0.1))
    odom.reset(Pose2D(0.0, 0.0, 0.0))
    radius_m, step_rad, dt_s = 2.0, 0.01, 0.05
    arc = [Pose2D(radius_m * math.sin(a), radius_m * (1 - math.cos(a)), a)
           for a in step_rad * np.arange(101)]
    for prev, now in zip(arc, arc[1:]):
        est, twist = odom.update(prev, now, dt_s, rng())
    assert est.yaw == pytest.approx(1.1)
    chord_m = 2 * radius_m * math.sin(step_rad / 2)
    assert twist == pytest.approx((chord_m / dt_s, 0.0, 1.1 * step_rad / dt_s), abs=1e-12)


def test_odometry_noise_is_relative_and_seeded() -> None:
    spec = OdometrySpec(linear_noise_std=0.1, angular_noise_std=0.2)
    twists = []
    for _ in range(2):
        odom, gen = WheelOdometry(spec), rng(9)
        odom.reset(Pose2D(0, 0, 0))
        twists.append(np.array([odom.update(Pose2D(0, 0, 0), Pose2D(0.1, 0, 0.1), 1.0, gen)[1]
                                for _ in range(3000)]))
    np.testing.assert_array_equal(twists[0], twists[1])
    vx, wz = twists[0][:, 0] / (0.1 * math.cos(0.05)), twists[0][:, 2] / 0.1
    assert vx.mean() == pytest.approx(1.0, abs=0.01) and vx.std() == pytest.approx(0.1, rel=0.05)
    assert wz.mean() == pytest.approx(1.0, abs=0.02) and wz.std() == pytest.approx(0.2, rel=0.05)


# --- Cost (printed, not asserted) -----------------------------------------------------------
