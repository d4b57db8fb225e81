"""Simulated sensors: LiDAR and depth camera by ray casting, IMU and wheel odometry.

Each ``read``/``update`` takes the ``np.random.Generator`` of its own sensor, so noise does
not depend on the order in which sensors are read; a sensor without noise never draws from
it. Ranges follow REP 117: ``+inf`` = nothing within range, ``-inf`` = closer than the
minimum. Frames follow REP 103: base +x forward, +y left, +z up, origin on the floor.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any, NamedTuple

import mujoco
import numpy as np

from .geometry import Pose2D, Twist2D, wrap_angle, yaw_to_quaternion
from .robot_specs import DepthCameraSpec, ImuSpec, LidarSpec, OdometrySpec

STANDARD_GRAVITY_M_S2 = 9.80665
# ROS reads a zero covariance as "unknown"; an exact (noise-free) quantity gets this instead.
EXACT_VARIANCE = 1e-9


def _to_rep117(values: np.ndarray, hit: np.ndarray, lo: float, hi: float, noise_std: float,
               rng: np.random.Generator) -> np.ndarray:
    """Float32 ranges from true ``values``: noise on hits, then ±inf outside ``[lo, hi]``."""
    out = np.where(hit, values, np.inf)
    if noise_std > 0:
        too_close = out < lo  # judged on the truth: noise cannot bring such a return back
        out += rng.normal(0.0, noise_std, out.shape)  # inf stays inf
        out[too_close] = -np.inf
    out[out > hi] = np.inf
    out[out < lo] = -np.inf
    return out.astype(np.float32)


def _mount_point(pose: Pose2D, c: float, s: float, xyz_m: tuple[float, float, float],
                 out: np.ndarray) -> None:
    """World position of a base-frame mount point, written into ``out``."""
    mx, my, mz = xyz_m
    out[0] = pose.x + c * mx - s * my
    out[1] = pose.y + s * mx + c * my
    out[2] = mz


class Lidar:
    """A planar LiDAR: all beams in one ``mj_multiRay`` call, skipping the robot's own body."""

    frame_id = "laser"

    def __init__(self, model: mujoco.MjModel, spec: LidarSpec, *, exclude_body: int) -> None:
        self.spec = spec
        self._model = model
        self._exclude_body = exclude_body
        n = spec.beams
        angles = spec.angle_min_rad + np.arange(n) * spec.angle_increment_rad + spec.mount_yaw_rad
        self._dirs_xy = np.column_stack((np.cos(angles), np.sin(angles)))  # base frame
        self._pnt = np.zeros(3)
        self._vec = np.zeros((n, 3))  # z stays 0: horizontal beams
        self._vec_flat = self._vec.reshape(-1)
        self._vec_xy = self._vec[:, :2]
        self._rot = np.empty((2, 2))
        self._geomid = np.empty(n, dtype=np.int32)
        self._dist = np.empty(n)

    @property
    def angle_min_rad(self) -> float:
        return self.spec.angle_min_rad

    @property
    def angle_max_rad(self) -> float:
        """Angle of the last beam (rad), as ``LaserScan.angle_max`` wants it."""
        return self.spec.angle_min_rad + (self.spec.beams - 1) * self.spec.angle_increment_rad

    @property
    def angle_increment_rad(self) -> float:
        return self.spec.angle_increment_rad

    @property
    def range_min_m(self) -> float:
        return self.spec.range_min_m

    @property
    def range_max_m(self) -> float:
        return self.spec.range_max_m

    def read(self, data: mujoco.MjData, pose: Pose2D, rng: np.random.Generator) -> np.ndarray:
        """One scan (float32 m, one per beam) for the robot at ``pose``; geoms as of ``data``."""
        spec = self.spec
        c, s = math.cos(pose.yaw), math.sin(pose.yaw)
        _mount_point(pose, c, s, spec.mount_xyz_m, self._pnt)
        rot = self._rot  # row-vector rotation: [x y] @ rot = R(yaw) [x y]^T
        rot[0, 0], rot[0, 1], rot[1, 0], rot[1, 1] = c, s, -s, c
        np.matmul(self._dirs_xy, rot, out=self._vec_xy)
        mujoco.mj_multiRay(self._model, data, self._pnt, self._vec_flat, None, 1,
                           self._exclude_body, self._geomid, self._dist, None, spec.beams,
                           spec.range_max_m)
        ranges = _to_rep117(self._dist, self._geomid >= 0, spec.range_min_m, spec.range_max_m,
                            spec.noise_std_m, rng)
        if spec.dropout_prob > 0:
            ranges[rng.random(spec.beams) < spec.dropout_prob] = np.inf
        return ranges


class DepthCamera:
    """A pinhole depth camera: one ray per pixel centre, depth along the optical axis."""

    frame_id = "camera_depth_optical_frame"

    def __init__(self, model: mujoco.MjModel, spec: DepthCameraSpec, *,
                 exclude_body: int) -> None:
        self.spec = spec
        self._model = model
        self._exclude_body = exclude_body
        self.width, self.height = spec.width, spec.height
        f = spec.focal_px
        self._intrinsics = (f, f, 0.5 * spec.width, 0.5 * spec.height)
        u = (np.arange(spec.width) + 0.5 - 0.5 * spec.width) / f  # optical x: right
        v = (np.arange(spec.height) + 0.5 - 0.5 * spec.height) / f  # optical y: down
        xo, yo = np.meshgrid(u, v)  # (height, width), row-major like the image
        # Optical (right, down, forward) -> camera link (forward, left, up), then pitch down.
        fwd, left, up = np.ones_like(xo).ravel(), -xo.ravel(), -yo.ravel()
        cp, sp = math.cos(spec.mount_pitch_rad), math.sin(spec.mount_pitch_rad)
        dirs = np.column_stack((cp * fwd + sp * up, left, -sp * fwd + cp * up))
        norm = np.linalg.norm(dirs, axis=1)
        self._dirs_xy = dirs[:, :2] / norm[:, None]
        self._depth_per_m = 1.0 / norm  # cos of the angle between ray and optical axis
        self._n = spec.width * spec.height
        self._cutoff_m = spec.max_depth_m * float(norm.max())
        self._pnt = np.zeros(3)
        self._vec = np.empty((self._n, 3))
        self._vec[:, 2] = dirs[:, 2] / norm  # yaw does not change the vertical part
        self._vec_flat = self._vec.reshape(-1)
        self._vec_xy = self._vec[:, :2]
        self._rot = np.empty((2, 2))
        self._geomid = np.empty(self._n, dtype=np.int32)
        self._dist = np.empty(self._n)

    @property
    def intrinsics(self) -> tuple[float, float, float, float]:
        """``(fx, fy, cx, cy)`` in pixels."""
        return self._intrinsics

    @property
    def k_matrix(self) -> tuple[float, ...]:
        """``CameraInfo.k``: the 3×3 intrinsic matrix, row-major."""
        fx, fy, cx, cy = self._intrinsics
        return (fx, 0.0, cx, 0.0, fy, cy, 0.0, 0.0, 1.0)

    @property
    def p_matrix(self) -> tuple[float, ...]:
        """``CameraInfo.p``: the 3×4 projection matrix of a monocular camera, row-major."""
        fx, fy, cx, cy = self._intrinsics
        return (fx, 0.0, cx, 0.0, 0.0, fy, cy, 0.0, 0.0, 0.0, 1.0, 0.0)

    def read(self, data: mujoco.MjData, pose: Pose2D, rng: np.random.Generator) -> np.ndarray:
        """A depth image (float32 m, shape ``(height, width)``) for the robot at ``pose``."""
        spec = self.spec
        c, s = math.cos(pose.yaw), math.sin(pose.yaw)
        _mount_point(pose, c, s, spec.mount_xyz_m, self._pnt)
        rot = self._rot
        rot[0, 0], rot[0, 1], rot[1, 0], rot[1, 1] = c, s, -s, c
        np.matmul(self._dirs_xy, rot, out=self._vec_xy)
        mujoco.mj_multiRay(self._model, data, self._pnt, self._vec_flat, None, 1,
                           self._exclude_body, self._geomid, self._dist, None, self._n,
                           self._cutoff_m)
        depth = self._dist * self._depth_per_m
        image = _to_rep117(depth, self._geomid >= 0, spec.min_depth_m, spec.max_depth_m,
                           spec.noise_std_m, rng)
        return image.reshape(spec.height, spec.width)


class ImuReading(NamedTuple):
    """One IMU sample in ``imu_link`` (REP 145: at rest the accelerometer reads +g up)."""

    orientation_xyzw: tuple[float, float, float, float]
    angular_velocity_xyz: tuple[float, float, float]  # rad/s
    linear_acceleration_xyz: tuple[float, float, float]  # m/s²


def _diagonal(variances: tuple[float, float, float]) -> tuple[float, ...]:
    a, b, c = variances
    return (a, 0.0, 0.0, 0.0, b, 0.0, 0.0, 0.0, c)


class Imu:
    """A planar IMU at the base: true heading, noisy yaw rate and specific force.

    Noise is white: on the gyro's z axis (x and y are exactly 0 for a planar base) and on all
    three accelerometer axes. Covariances say ``EXACT_VARIANCE`` for exact quantities.
    """

    frame_id = "imu_link"

    def __init__(self, spec: ImuSpec) -> None:
        self.spec = spec
        gyro_var = max(spec.gyro_noise_std_rad_s**2, EXACT_VARIANCE)
        accel_var = max(spec.accel_noise_std_m_s2**2, EXACT_VARIANCE)
        self.orientation_covariance = _diagonal((EXACT_VARIANCE,) * 3)
        self.angular_velocity_covariance = _diagonal((EXACT_VARIANCE, EXACT_VARIANCE, gyro_var))
        self.linear_acceleration_covariance = _diagonal((accel_var,) * 3)

    def read(self, yaw: float, yaw_rate_rad_s: float, accel_world_xy: tuple[float, float],
             rng: np.random.Generator) -> ImuReading:
        """A sample for heading ``yaw`` (rad), yaw rate and world planar acceleration (m/s²)."""
        c, s = math.cos(yaw), math.sin(yaw)
        ax_w, ay_w = accel_world_xy
        accel = [c * ax_w + s * ay_w, -s * ax_w + c * ay_w, STANDARD_GRAVITY_M_S2]
        wz = float(yaw_rate_rad_s)
        if self.spec.gyro_noise_std_rad_s > 0:
            wz += self.spec.gyro_noise_std_rad_s * float(rng.standard_normal())
        if self.spec.accel_noise_std_m_s2 > 0:
            noise = self.spec.accel_noise_std_m_s2 * rng.standard_normal(3)
            accel = [a + float(n) for a, n in zip(accel, noise)]
        return ImuReading(yaw_to_quaternion(yaw), (0.0, 0.0, wz),
                          (float(accel[0]), float(accel[1]), float(accel[2])))


class WheelOdometry:
    """Dead reckoning from the true motion of each control period, with drift and noise.

    A period's displacement is expressed in the frame at its midpoint heading (a
    differential-drive robot on an arc moves straight along it), distorted by the spec's
    scale errors and relative noise, then composed onto the odometry pose the same way.
    """

    frame_id = "odom"
    child_frame_id = "base_link"

    def __init__(self, spec: OdometrySpec) -> None:
        self.spec = spec
        self._pose = Pose2D(0.0, 0.0, 0.0)

    @property
    def pose(self) -> Pose2D:
        """The odometry's current estimate of the base pose in ``odom``."""
        return self._pose

    def reset(self, pose: Pose2D) -> None:
        """Start dead reckoning at ``pose`` (the odom frame is initialised at the start)."""
        self._pose = Pose2D(pose.x, pose.y, wrap_angle(pose.yaw))

    def update(self, true_prev: Pose2D, true_now: Pose2D, dt_s: float,
               rng: np.random.Generator) -> tuple[Pose2D, Twist2D]:
        """Advance by the true motion ``true_prev`` → ``true_now`` over ``dt_s`` (s > 0).

        Returns the odometry pose and the measured body-frame twist (m/s, rad/s).
        """
        spec = self.spec
        dtheta = wrap_angle(true_now.yaw - true_prev.yaw)
        mid = true_prev.yaw + 0.5 * dtheta
        c, s = math.cos(mid), math.sin(mid)
        wx, wy = true_now.x - true_prev.x, true_now.y - true_prev.y
        lin = 1.0 + spec.linear_scale_error
        dx, dy = lin * (c * wx + s * wy), lin * (-s * wx + c * wy)
        dtheta *= 1.0 + spec.angular_scale_error
        if spec.linear_noise_std > 0:
            ex, ey = rng.normal(0.0, spec.linear_noise_std, 2)
            dx, dy = dx * (1.0 + float(ex)), dy * (1.0 + float(ey))
        if spec.angular_noise_std > 0:
            dtheta *= 1.0 + float(rng.normal(0.0, spec.angular_noise_std))
        odom = self._pose
        mid = odom.yaw + 0.5 * dtheta
        c, s = math.cos(mid), math.sin(mid)
        self._pose = Pose2D(odom.x + c * dx - s * dy, odom.y + s * dx + c * dy,
                            wrap_angle(odom.yaw + dtheta))
        return self._pose, Twist2D(dx / dt_s, dy / dt_s, dtheta / dt_s)


class EngineSensor(NamedTuple):
    """How the engine builds and reads one kind of ``robot_specs.SENSOR_KINDS``."""

    #: (model, spec, the robot's body id, which rays skip) → the sensor.
    build: Callable[[mujoco.MjModel, Any, int], Any]
    #: (sensor, engine, the sensor's random stream) → a reading; ``None``: the engine
    #: advances it at each step (wheel odometry).
    read: Callable[[Any, Any, np.random.Generator], Any] | None = None


def _read_rays(sensor: Lidar | DepthCamera, engine: Any, rng: np.random.Generator) -> np.ndarray:
    return sensor.read(engine.data, engine.robot_pose(), rng)


def _read_imu(imu: Imu, engine: Any, rng: np.random.Generator) -> ImuReading:
    d, ids = engine.data, engine.ids
    return imu.read(float(d.qpos[ids.qpos_yaw]), float(d.qvel[ids.dof_yaw]),
                    (float(d.qacc[ids.dof_x]), float(d.qacc[ids.dof_y])), rng)


#: Each sensor kind's engine side, by ``SENSOR_KINDS`` name.
ENGINE_SENSORS = {
    "lidar": EngineSensor(lambda model, spec, body: Lidar(model, spec, exclude_body=body),
                          _read_rays),
    "depth": EngineSensor(lambda model, spec, body: DepthCamera(model, spec, exclude_body=body),
                          _read_rays),
    "imu": EngineSensor(lambda model, spec, body: Imu(spec), _read_imu),
    "odometry": EngineSensor(lambda model, spec, body: WheelOdometry(spec)),
}
