"""A robot's sensors in one table, ``SENSOR_TABLE``: each kind's spec (the robot's data and the
sim's ``<kind>.*`` parameters) and how the engine builds and reads it. The IMU and wheel
odometry live here beside their specs; the ray-casting LiDAR and depth camera in
``ray_sensors``; the paper's future-work sensors in ``sensor_kinds``, one module each.

Each read takes the ``np.random.Generator`` of its own sensor, so noise does not depend on the
order in which sensors are read; a sensor without noise never draws from it. Frames follow
REP 103: base +x forward, +y left, +z up, origin on the floor.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, NamedTuple

import numpy as np

from pic4rl_base.geometry import Pose2D, wrap_angle, yaw_to_quaternion
from pic4rl_base.plugins import load_group
from pic4rl_base.schema import FRACTION, Range, check, param

from .geometry import Twist2D
from .ray_sensors import DepthCamera, DepthCameraSpec, Lidar, LidarSpec
from .sensor_kinds import sonar, stereo, uwb

STANDARD_GRAVITY_M_S2 = 9.80665
# ROS reads a zero covariance as "unknown"; an exact (noise-free) quantity gets this instead.
EXACT_VARIANCE = 1e-9


_SCALE_ERROR = Range(-1.0, 1.0, lo_open=True, hi_open=True)


@dataclass(frozen=True)
class ImuSpec:
    """An IMU at the base: yaw rate and planar acceleration, with white noise."""

    gyro_noise_std_rad_s: float = param(0.0, doc="standard deviation of the gyro's white noise",
                                        unit="rad/s", range=Range(0.0, 10.0))
    accel_noise_std_m_s2: float = param(0.0, doc="standard deviation of the accelerometer's "
                                        "white noise", unit="m/s^2", range=Range(0.0, 100.0))

    def __post_init__(self) -> None:
        check(self, "imu.")


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

    def frames(self) -> list[tuple[str, tuple[float, float, float],
                                   tuple[float, float, float, float]]]:
        """Its frame on the base for ``tf_static``: the base's origin (it reads its motion)."""
        return [(self.frame_id, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0, 1.0))]

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


@dataclass(frozen=True)
class OdometrySpec:
    """Wheel odometry: the true displacement each control period, scaled and perturbed.

    ``*_scale_error`` is a systematic drift (0.02 = the odometry sees 2 % more motion than
    happened); ``*_noise_std`` a relative white noise on each period's displacement.
    """

    linear_scale_error: float = param(0.0, doc="systematic wheel-odometry error on distance "
                                      "(0.02 = 2 % too far)", range=_SCALE_ERROR)
    angular_scale_error: float = param(0.0, doc="systematic wheel-odometry error on rotation",
                                       range=_SCALE_ERROR)
    linear_noise_std: float = param(0.0, doc="relative noise on each period's odometry "
                                    "displacement", range=FRACTION)
    angular_noise_std: float = param(0.0, doc="relative noise on each period's odometry "
                                     "rotation", range=FRACTION)

    def __post_init__(self) -> None:
        check(self, "odometry.")


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


@dataclass(frozen=True)
class SensorKind:
    """One kind of sensor a robot may carry. ``name`` is its key in ``RobotSpec.sensors`` and
    a robot file, its parameters' prefix (``lidar.beams``) and its random stream; ``spec`` its
    spec class; ``build`` and ``read`` its engine side. ``optional`` sensors may be missing
    (``None``; ``carried`` says whether a robot that does not name it has one) and get an
    ``<name>.enabled`` parameter naming the sensor (``label``) and what it publishes."""

    name: str
    spec: type
    #: (model, spec, the robot's body id, which rays skip) → the sensor.
    build: Callable[[Any, Any, int], Any]
    #: (sensor, engine, the sensor's random stream) → a reading; ``None``: the engine
    #: advances it at each step (wheel odometry).
    read: Callable[[Any, Any, np.random.Generator], Any] | None = None
    optional: bool = False
    carried: bool = True
    label: str = ""
    publishes: str = ""
    #: (engine, the step's stamp) → its step messages for the sim node (``held``: interface →
    #: message, ``fill(engine)``), for a user's sensor; pic4rl's own are in
    #: ``pic4rl_sim.node.messages.SENSOR_MESSAGES``.
    messages: Callable[[Any, Any], Any] | None = None


def _read_rays(sensor: Lidar | DepthCamera, engine: Any, rng: np.random.Generator) -> np.ndarray:
    return sensor.read(engine.data, engine.robot_pose(), rng)


def _read_imu(imu: Imu, engine: Any, rng: np.random.Generator) -> ImuReading:
    d, ids = engine.data, engine.ids
    return imu.read(float(d.qpos[ids.qpos_yaw]), float(d.qvel[ids.dof_yaw]),
                    (float(d.qacc[ids.dof_x]), float(d.qacc[ids.dof_y])), rng)


#: Every kind of sensor, in ``RobotSpec.sensors``' order: the sim's parameters, a robot
#: file's keys, the engine's sensors and their random streams derive from it (a kind added
#: at the end leaves the others' noise as it was).
SENSOR_TABLE = (
    SensorKind("lidar", LidarSpec,
               lambda model, spec, body: Lidar(model, spec, exclude_body=body), _read_rays,
               optional=True, label="LiDAR", publishes="scan"),
    SensorKind("depth", DepthCameraSpec,
               lambda model, spec, body: DepthCamera(model, spec, exclude_body=body), _read_rays,
               optional=True, carried=False, label="depth camera", publishes="camera/depth/*"),
    SensorKind("imu", ImuSpec, lambda model, spec, body: Imu(spec), _read_imu),
    SensorKind("odometry", OdometrySpec, lambda model, spec, body: WheelOdometry(spec)),
    SensorKind(sonar.NAME, sonar.SonarSpec, sonar.build, sonar.read, optional=True,
               carried=False, label="sonar ring", publishes="sonar/*"),
    SensorKind(uwb.NAME, uwb.UwbSpec, uwb.build, uwb.read, optional=True, carried=False,
               label="UWB tag", publishes="uwb/*"),
    SensorKind(stereo.NAME, stereo.StereoCameraSpec, stereo.build, stereo.read, optional=True,
               carried=False, label="stereo depth camera", publishes="stereo/*"),
)
#: pic4rl's own kinds, before any user's.
OWN_KINDS = tuple(kind.name for kind in SENSOR_TABLE)
#: A user's sensors, after pic4rl's: each a ``SensorKind`` that its package names in this
#: entry-point group under the kind's name (its topic in ``pic4rl.interfaces``, its reading
#: in ``pic4rl.readings``).
SENSOR_GROUP = "pic4rl.sensors"
SENSOR_TABLE += tuple(load_group(SENSOR_GROUP, SensorKind,
                                 taken={kind.name for kind in SENSOR_TABLE}).values())
#: The kinds by name.
KINDS_BY_NAME = {kind.name: kind for kind in SENSOR_TABLE}
