"""Robots as data: footprint, mass, drive, limits and sensors.

Four robots ship built in (``jackal``, ``husky``, ``burger``, ``omni``); a user's robot is a
YAML file with the same keys, its sensors as top-level keys (``lidar:``, ``depth:``, ...:
``sensors.SENSOR_KINDS``' names; ``load_robot("my_robot.yaml")``). Optional sensors may be
missing: ``None`` means the robot carries no such sensor.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from dataclasses import dataclass, field
from enum import Enum
from pathlib import Path
from types import MappingProxyType
from typing import Any, TypeVar

from pic4rl_base.errors import ConfigError, require, unknown_key
from pic4rl_base.geometry import Footprint
from pic4rl_base.schema import NON_NEGATIVE, POSITIVE, read_yaml

from .sensors import KINDS_BY_NAME, SENSOR_TABLE, DepthCameraSpec, ImuSpec, LidarSpec, OdometrySpec


class Drive(str, Enum):
    """How a robot moves: ``diff`` follows (v, ω); ``omni`` also strafes (vx, vy, ω)."""

    DIFF = "diff"
    OMNI = "omni"


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
    #: Its sensors by ``SENSOR_TABLE`` name, all kinds in the table's order (a kind not given
    #: gets its stock spec, or ``None`` when optional and not ``carried``).
    sensors: Mapping[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        require(bool(self.name), "robot.name", self.name, "a non-empty name")
        for key in self.sensors:
            if key not in KINDS_BY_NAME:
                raise unknown_key(key, KINDS_BY_NAME, where="robot sensors")
        stock = {k.name: k.spec() if k.carried else None for k in SENSOR_TABLE}
        sensors = {name: self.sensors.get(name, spec) for name, spec in stock.items()}
        for kind in SENSOR_TABLE:
            spec = sensors[kind.name]
            ok = isinstance(spec, kind.spec) or (spec is None and kind.optional)
            require(ok, f"robot.{kind.name}", spec,
                    f"{kind.spec.__name__}{' or None' if kind.optional else ''}")
        object.__setattr__(self, "sensors", MappingProxyType(sensors))
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

    def __hash__(self) -> int:  # ``sensors`` is a mapping: equal robots share these
        return hash((self.name, self.drive, self.footprint))

    def with_sensors(self, **changes: Any) -> RobotSpec:
        """A copy with sensors (``SENSOR_TABLE``' names) replaced."""
        return dataclasses.replace(self, sensors={**self.sensors, **changes})

    # The stock kinds, typed; a kind added to SENSOR_TABLE is read as ``sensors[name]``.
    @property
    def lidar(self) -> LidarSpec | None:
        return self.sensors["lidar"]

    @property
    def depth(self) -> DepthCameraSpec | None:
        return self.sensors["depth"]

    @property
    def imu(self) -> ImuSpec:
        return self.sensors["imu"]

    @property
    def odometry(self) -> OdometrySpec:
        return self.sensors["odometry"]


JACKAL = RobotSpec(
    name="jackal", drive=Drive.DIFF, footprint=Footprint(length_m=0.508, width_m=0.430),
    height_m=0.25, mass_kg=17.0, wheel_base_m=0.376, wheel_radius_m=0.098,
    max_linear_m_s=2.0, max_angular_rad_s=4.0,
    max_linear_accel_m_s2=3.0, max_angular_accel_rad_s2=6.0,
    sensors={"lidar": LidarSpec(mount_xyz_m=(0.12, 0.0, 0.3)), "depth": None},
)
HUSKY = RobotSpec(
    name="husky", drive=Drive.DIFF, footprint=Footprint(length_m=0.99, width_m=0.67),
    height_m=0.39, mass_kg=50.0, wheel_base_m=0.555, wheel_radius_m=0.165,
    max_linear_m_s=1.0, max_angular_rad_s=2.0,
    max_linear_accel_m_s2=3.0, max_angular_accel_rad_s2=6.0,
    sensors={"lidar": LidarSpec(mount_xyz_m=(0.3, 0.0, 0.5), range_max_m=20.0), "depth": None},
)
BURGER = RobotSpec(
    name="burger", drive=Drive.DIFF, footprint=Footprint(radius_m=0.105),
    height_m=0.192, mass_kg=1.0, wheel_base_m=0.160, wheel_radius_m=0.033,
    max_linear_m_s=0.22, max_angular_rad_s=2.84,
    max_linear_accel_m_s2=2.5, max_angular_accel_rad_s2=3.2,
    sensors={"lidar": LidarSpec(range_min_m=0.12, range_max_m=3.5,
                                mount_xyz_m=(-0.032, 0.0, 0.172)), "depth": None},
)
OMNI = RobotSpec(
    name="omni", drive=Drive.OMNI, footprint=Footprint(radius_m=0.25),
    height_m=0.3, mass_kg=20.0, wheel_base_m=0.4, wheel_radius_m=0.05,
    max_linear_m_s=1.0, max_lateral_m_s=1.0, max_angular_rad_s=2.0,
    max_linear_accel_m_s2=2.0, max_angular_accel_rad_s2=4.0,
    sensors={"lidar": LidarSpec(mount_xyz_m=(0.0, 0.0, 0.35)), "depth": None},
)
ROBOT_TABLE: dict[str, RobotSpec] = {r.name: r for r in (JACKAL, HUSKY, BURGER, OMNI)}

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


#: A robot file's keys: ``RobotSpec``'s, with each sensor kind's in place of ``sensors``.
_FILE_KEYS = frozenset({f.name for f in dataclasses.fields(RobotSpec)} - {"sensors"}
                       | set(KINDS_BY_NAME))


def _as_file(robot: RobotSpec) -> dict[str, Any]:
    """``robot``'s keys as a robot file writes them (sensors at the top level, parts as
    mappings)."""
    values = {f.name: getattr(robot, f.name) for f in dataclasses.fields(robot)
              if f.name != "sensors"}
    values.update(robot.sensors)
    return {k: dataclasses.asdict(v) if dataclasses.is_dataclass(v) else v
            for k, v in values.items()}


def robot_from_mapping(data: Mapping[str, Any], *, where: str = "robot") -> RobotSpec:
    """A robot from a robot file's keys; sensors as nested mappings or null."""
    data = dict(data)
    base = ROBOT_TABLE.get(str(data.pop("base", "")))  # start from a built-in robot if named
    values: dict[str, Any] = _as_file(base) if base else {}
    nested = {"footprint": Footprint, **{k.name: k.spec for k in SENSOR_TABLE}}
    for key, value in data.items():  # nested mappings refine the base robot's sensors
        old = values.get(key)
        merge = isinstance(old, dict) and isinstance(value, Mapping)
        values[key] = {**old, **value} if merge else value  # type: ignore[dict-item]
    for key in values:
        if key not in _FILE_KEYS:
            raise unknown_key(key, _FILE_KEYS, where=where)
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
    values["sensors"] = {name: values.pop(name) for name in KINDS_BY_NAME if name in values}
    return _build(RobotSpec, values, where)


def load_robot(name_or_path: str | Path) -> RobotSpec:
    """A built-in robot by name, or a robot YAML file (keys of ``RobotSpec``)."""
    text = str(name_or_path)
    if text in ROBOT_TABLE:
        return ROBOT_TABLE[text]
    path = Path(text)
    if path.suffix not in (".yaml", ".yml"):
        raise unknown_key(text, ROBOT_TABLE, where="robot")
    data = read_yaml(path, "robot file")
    if not isinstance(data, Mapping):
        raise ConfigError(f"robot: {str(path)!r} must hold a mapping of robot keys")
    return robot_from_mapping(data, where=str(path))
