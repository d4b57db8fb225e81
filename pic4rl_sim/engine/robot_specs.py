"""Robots as data: footprint, mass, drive, limits and sensor mounts.

Four robots ship built in (``jackal``, ``husky``, ``burger``, ``omni``); a user's robot is a
YAML file with the same keys (``load_robot("my_robot.yaml")``). Sensors are optional parts of
a robot: ``None`` means the robot carries no such sensor.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from enum import Enum
from pathlib import Path
from typing import Any, TypeVar


from ..errors import ConfigError, require, unknown_key
from ..schema import FRACTION, NON_NEGATIVE, POSITIVE, Range, check, param, read_yaml
from .geometry import Footprint

_SCALE_ERROR = Range(-1.0, 1.0, lo_open=True, hi_open=True)


class Drive(str, Enum):
    """How a robot moves: ``diff`` follows (v, ω); ``omni`` also strafes (vx, vy, ω)."""

    DIFF = "diff"
    OMNI = "omni"


@dataclass(frozen=True)
class LidarSpec:
    """A planar LiDAR: ``beams`` rays over ``fov_deg`` centred on the mount's +x axis."""

    beams: int = param(360, doc="number of LiDAR beams", range=Range(1, 10_000))
    fov_deg: float = param(360.0, doc="LiDAR field of view, centred on the mount's forward axis",
                           unit="deg", range=Range(0.0, 360.0, lo_open=True))
    range_min_m: float = param(0.1, doc="LiDAR minimum range; closer returns read -inf",
                               unit="m", range=Range(0.0, 1000.0))
    range_max_m: float = param(10.0, doc="LiDAR maximum range; farther returns read +inf",
                               unit="m", range=Range(0.0, 1000.0, lo_open=True))
    noise_std_m: float = param(0.0, doc="standard deviation of the Gaussian noise on each range",
                               unit="m", range=Range(0.0, 10.0))
    dropout_prob: float = param(0.0, doc="probability that a beam is dropped (reads +inf)",
                                range=FRACTION)
    mount_xyz_m: tuple[float, float, float] = (0.0, 0.0, 0.3)
    mount_yaw_rad: float = 0.0

    def __post_init__(self) -> None:
        check(self, "lidar.")
        require(self.range_min_m < self.range_max_m, "lidar.range_max_m", self.range_max_m,
                f"more than range_min_m={self.range_min_m}")

    @property
    def angle_min_rad(self) -> float:
        return -0.5 * math.radians(self.fov_deg)

    @property
    def angle_increment_rad(self) -> float:
        """Angle between beams; a full circle does not repeat its first beam (rad)."""
        fov = math.radians(self.fov_deg)
        if self.fov_deg >= 360.0:
            return fov / self.beams
        return fov / max(self.beams - 1, 1)


@dataclass(frozen=True)
class DepthCameraSpec:
    """A pinhole depth camera; pixels hold depth along the optical axis (m, 32FC1)."""

    width: int = param(80, doc="depth image width", unit="px", range=Range(1, 4096))
    height: int = param(60, doc="depth image height", unit="px", range=Range(1, 4096))
    hfov_deg: float = param(87.0, doc="depth camera horizontal field of view", unit="deg",
                            range=Range(0.0, 180.0, lo_open=True, hi_open=True))
    min_depth_m: float = param(0.1, doc="depth camera minimum depth; closer pixels read -inf",
                               unit="m", range=Range(0.0, 1000.0))
    max_depth_m: float = param(10.0, doc="depth camera maximum depth; farther pixels read +inf",
                               unit="m", range=Range(0.0, 1000.0, lo_open=True))
    noise_std_m: float = param(0.0, doc="standard deviation of the Gaussian noise on each pixel",
                               unit="m", range=Range(0.0, 10.0))
    mount_xyz_m: tuple[float, float, float] = (0.2, 0.0, 0.4)
    mount_pitch_rad: float = 0.0

    def __post_init__(self) -> None:
        check(self, "depth.")
        require(self.min_depth_m < self.max_depth_m, "depth.max_depth_m", self.max_depth_m,
                f"more than min_depth_m={self.min_depth_m}")

    @property
    def focal_px(self) -> float:
        """Focal length in pixels (square pixels)."""
        return 0.5 * self.width / math.tan(0.5 * math.radians(self.hfov_deg))


@dataclass(frozen=True)
class ImuSpec:
    """An IMU at the base: yaw rate and planar acceleration, with white noise."""

    gyro_noise_std_rad_s: float = param(0.0, doc="standard deviation of the gyro's white noise",
                                        unit="rad/s", range=Range(0.0, 10.0))
    accel_noise_std_m_s2: float = param(0.0, doc="standard deviation of the accelerometer's "
                                        "white noise", unit="m/s^2", range=Range(0.0, 100.0))

    def __post_init__(self) -> None:
        check(self, "imu.")


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


@dataclass(frozen=True)
class SensorKind:
    """One kind of sensor a robot may carry: ``name`` is its ``RobotSpec`` field, its
    parameters' prefix (``lidar.beams``) and its random stream; ``spec`` its spec class;
    ``optional`` sensors may be missing (``None``) and get an ``<name>.enabled`` parameter
    that names the sensor (``label``) and what it publishes (``publishes``)."""

    name: str
    spec: type
    optional: bool = False
    label: str = ""
    publishes: str = ""


#: Every kind of sensor, in ``RobotSpec``'s order: the sim's parameters, a robot file's keys
#: and the engine's sensors derive from it.
SENSOR_KINDS = (
    SensorKind("lidar", LidarSpec, optional=True, label="LiDAR", publishes="scan"),
    SensorKind("depth", DepthCameraSpec, optional=True, label="depth camera",
               publishes="camera/depth/*"),
    SensorKind("imu", ImuSpec),
    SensorKind("odometry", OdometrySpec),
)


@dataclass(frozen=True)
class RobotSpec:
    """A mobile base: body, drive, limits (SI units) and sensors."""

    name: str
    drive: Drive
    footprint: Footprint
    height_m: float
    mass_kg: float
    wheel_base_m: float  # distance between left and right wheels
    wheel_radius_m: float
    max_linear_m_s: float
    max_angular_rad_s: float
    max_linear_accel_m_s2: float
    max_angular_accel_rad_s2: float
    max_lateral_m_s: float = 0.0  # omni only
    lidar: LidarSpec | None = field(default_factory=LidarSpec)
    depth: DepthCameraSpec | None = None
    imu: ImuSpec = field(default_factory=ImuSpec)
    odometry: OdometrySpec = field(default_factory=OdometrySpec)

    def __post_init__(self) -> None:
        require(bool(self.name), "robot.name", self.name, "a non-empty name")
        for key in ("height_m", "mass_kg", "wheel_base_m", "wheel_radius_m", "max_linear_m_s",
                    "max_angular_rad_s", "max_linear_accel_m_s2", "max_angular_accel_rad_s2"):
            value = getattr(self, key)
            require(value in POSITIVE, f"robot.{key}", value, POSITIVE.expected())
        lateral = POSITIVE if self.drive is Drive.OMNI else NON_NEGATIVE
        require(self.max_lateral_m_s in lateral, "robot.max_lateral_m_s", self.max_lateral_m_s,
                lateral.expected())
        if self.drive is not Drive.OMNI:
            require(self.max_lateral_m_s == 0, "robot.max_lateral_m_s", self.max_lateral_m_s,
                    "0 for a differential-drive robot")

    def with_sensors(self, **changes: Any) -> RobotSpec:
        """A copy with sensors (``SENSOR_KINDS``' names) replaced."""
        return dataclasses.replace(self, **changes)


JACKAL = RobotSpec(
    name="jackal", drive=Drive.DIFF, footprint=Footprint(length_m=0.508, width_m=0.430),
    height_m=0.25, mass_kg=17.0, wheel_base_m=0.376, wheel_radius_m=0.098,
    max_linear_m_s=2.0, max_angular_rad_s=4.0,
    max_linear_accel_m_s2=3.0, max_angular_accel_rad_s2=6.0,
    lidar=LidarSpec(mount_xyz_m=(0.12, 0.0, 0.3)),
    depth=None,
)
HUSKY = RobotSpec(
    name="husky", drive=Drive.DIFF, footprint=Footprint(length_m=0.99, width_m=0.67),
    height_m=0.39, mass_kg=50.0, wheel_base_m=0.555, wheel_radius_m=0.165,
    max_linear_m_s=1.0, max_angular_rad_s=2.0,
    max_linear_accel_m_s2=3.0, max_angular_accel_rad_s2=6.0,
    lidar=LidarSpec(mount_xyz_m=(0.3, 0.0, 0.5), range_max_m=20.0),
    depth=None,
)
BURGER = RobotSpec(
    name="burger", drive=Drive.DIFF, footprint=Footprint(radius_m=0.105),
    height_m=0.192, mass_kg=1.0, wheel_base_m=0.160, wheel_radius_m=0.033,
    max_linear_m_s=0.22, max_angular_rad_s=2.84,
    max_linear_accel_m_s2=2.5, max_angular_accel_rad_s2=3.2,
    lidar=LidarSpec(range_min_m=0.12, range_max_m=3.5, mount_xyz_m=(-0.032, 0.0, 0.172)),
    depth=None,
)
OMNI = RobotSpec(
    name="omni", drive=Drive.OMNI, footprint=Footprint(radius_m=0.25),
    height_m=0.3, mass_kg=20.0, wheel_base_m=0.4, wheel_radius_m=0.05,
    max_linear_m_s=1.0, max_lateral_m_s=1.0, max_angular_rad_s=2.0,
    max_linear_accel_m_s2=2.0, max_angular_accel_rad_s2=4.0,
    lidar=LidarSpec(mount_xyz_m=(0.0, 0.0, 0.35)),
    depth=None,
)
BUILT_IN: dict[str, RobotSpec] = {r.name: r for r in (JACKAL, HUSKY, BURGER, OMNI)}

_T = TypeVar("_T")


def _build(cls: type[_T], data: Mapping[str, Any], where: str) -> _T:
    """``cls(**data)`` with unknown keys named; tuples for list values."""
    names = {f.name for f in dataclasses.fields(cls)}  # type: ignore[arg-type]
    for key in data:
        if key not in names:
            raise unknown_key(key, names, where=where)
    values = {k: tuple(v) if isinstance(v, list) else v for k, v in data.items()}
    try:
        return cls(**values)
    except TypeError as err:
        raise ConfigError(f"{where}: {err}") from err


def robot_from_mapping(data: Mapping[str, Any], *, where: str = "robot") -> RobotSpec:
    """A robot from a mapping of ``RobotSpec``'s keys; sensors as nested mappings or null."""
    data = dict(data)
    base = BUILT_IN.get(str(data.pop("base", "")))  # start from a built-in robot if named
    values: dict[str, Any] = dataclasses.asdict(base) if base else {}
    nested = {"footprint": Footprint, **{k.name: k.spec for k in SENSOR_KINDS}}
    for key, value in data.items():  # nested mappings refine the base robot's sensors
        old = values.get(key)
        merge = isinstance(old, dict) and isinstance(value, Mapping)
        values[key] = {**old, **value} if merge else value  # type: ignore[dict-item]
    for key, cls in nested.items():
        value = values.get(key)
        if isinstance(value, Mapping):
            values[key] = _build(cls, value, f"{where}.{key}")
    if "drive" in values:
        try:
            values["drive"] = Drive(values["drive"])
        except ValueError as err:
            choices = ", ".join(d.value for d in Drive)
            msg = f"{where}.drive: {values['drive']!r} is not one of {choices}"
            raise ConfigError(msg) from err
    return _build(RobotSpec, values, where)


def load_robot(name_or_path: str | Path) -> RobotSpec:
    """A built-in robot by name, or a robot YAML file (keys of ``RobotSpec``)."""
    text = str(name_or_path)
    if text in BUILT_IN:
        return BUILT_IN[text]
    path = Path(text)
    if path.suffix not in (".yaml", ".yml"):
        raise unknown_key(text, BUILT_IN, where="robot")
    data = read_yaml(path, "robot file")
    if not isinstance(data, Mapping):
        raise ConfigError(f"robot: {str(path)!r} must hold a mapping of robot keys")
    return robot_from_mapping(data, where=str(path))
