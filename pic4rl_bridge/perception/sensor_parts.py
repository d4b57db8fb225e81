"""Each observable sensor's part, in one place: what it needs of a frame, how it enters an
observation (its space and its value) and what it adds to the collision check and obstacle
distance (its obstacle points in the base frame), so that goToPose and the collision check
read a table (``pic4rl_bridge.settings.observations.OBSERVED_TABLE``, whose entries name
these) instead of branching on a sensor's name. A user's sensor gives its own ``SensorPart``.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

import gymnasium as gym
import numpy as np

from pic4rl_base.geometry import Pose2D
from pic4rl_sim.engine.sensor_kinds import sonar

from ..config import EnvConfig
from ..errors import ConfigError
from ..readings.frame import ScanData, SensorFrame
from ..robot_info import RobotInfo
from ..settings.observations import OBSERVED_TABLE, ObservedSensor
from .collision import depth_points
from .observations import depth_observation, depth_space, lidar_sectors

_ORIGIN = Pose2D(0.0, 0.0, 0.0)


@dataclass(frozen=True)
class SensorPart:
    """An observed sensor's part. ``readings``: the ``SensorFrame`` readings it needs (a
    task's ``required``); ``space`` and ``value``: its observation (``extra``: the episode's
    context's ``extra``, where a part keeps what it stacks); ``points``: its obstacle points
    (n, 2, base frame, m) of a frame, or ``None`` when the frame lacks its readings or it
    senses no obstacles."""

    readings: Callable[[RobotInfo], frozenset[str]]
    space: Callable[[EnvConfig, RobotInfo], gym.spaces.Box]
    value: Callable[[EnvConfig, RobotInfo, SensorFrame, Mapping[str, Any]], np.ndarray]
    points: Callable[[SensorFrame, RobotInfo], np.ndarray | None]


def observable(config: EnvConfig, robot: RobotInfo) -> tuple[ObservedSensor, ...]:
    """The table's entries of the sensors ``config`` observes; ``ConfigError`` in one line for
    one the robot does not carry."""
    entries = tuple(OBSERVED_TABLE[name] for name in config.observed)
    for entry in entries:
        if entry.kind not in robot.specs:
            raise ConfigError(f"sensors: {entry.name!r} needs the robot's {entry.kind} sensor, "
                              f"which robot {robot.name!r} does not carry; expected the sim's "
                              f"'{entry.kind}.enabled: true' (or a robot file with one)")
    return entries


# -- the LiDAR: its sectors, stacked over lidar.history scans --------------------------------

def _sectors_space(config: EnvConfig, robot: RobotInfo) -> gym.spaces.Box:
    far = 1.0 if config.normalize_observations else config.lidar.clip_m
    return gym.spaces.Box(0.0, far, (config.lidar.sectors * config.lidar.history,), np.float32)


def _sectors(config: EnvConfig, robot: RobotInfo, frame: SensorFrame,
             extra: Mapping[str, Any]) -> np.ndarray:
    """The frame's sectors, normalised if asked, stacked with the episode's last scans' when
    ``lidar.history`` > 1 (``extra["scan_history"]``; the episode's first scan fills it)."""
    if frame.scan is None:
        raise ValueError("goToPose (lidar): the frame has no scan")
    lidar = config.lidar
    sectors = lidar_sectors(frame.scan, lidar)
    if config.normalize_observations:
        sectors /= np.float32(lidar.clip_m)
    if lidar.history > 1:
        stack = extra["scan_history"]
        stack.extendleft([sectors] * (lidar.history if not stack else 1))
        sectors = np.concatenate(stack)
    return sectors


LIDAR = SensorPart(lambda robot: frozenset({"scan"}), _sectors_space, _sectors,
                   lambda frame, robot: None if frame.scan is None else frame.scan.points())


# -- the depth camera and the stereo camera: an image each -----------------------------------

def _image(section: str, reading: str) -> Callable[..., np.ndarray]:
    def value(config: EnvConfig, robot: RobotInfo, frame: SensorFrame,
              extra: Mapping[str, Any]) -> np.ndarray:
        image = frame.readings.get(reading)
        if image is None:
            raise ValueError(f"goToPose ({section}): the frame has no {reading} image")
        c = getattr(config, section)
        return depth_observation(image, c.obs_width, c.obs_height, c.clip_m, c.encoding)
    return value


def _depth_points(frame: SensorFrame, robot: RobotInfo) -> np.ndarray | None:
    if frame.depth is None:
        return None
    return depth_points(frame.depth, robot.depth_mount or _ORIGIN, robot.depth_hfov_rad,
                        height_m=robot.depth_height_m, pitch_rad=robot.depth_pitch_rad)


def _stereo_points(frame: SensorFrame, robot: RobotInfo) -> np.ndarray | None:
    image, spec = frame.readings.get("stereo_depth"), robot.specs.get("stereo")
    if image is None or spec is None:
        return None
    return depth_points(image, robot.mounts.get("stereo", _ORIGIN), np.radians(spec.hfov_deg),
                        height_m=spec.mount_xyz_m[2])


DEPTH = SensorPart(lambda robot: frozenset({"depth"}),
                   lambda config, robot: depth_space(config.depth), _image("depth", "depth"),
                   _depth_points)
STEREO = SensorPart(lambda robot: frozenset({"stereo_depth"}),
                    lambda config, robot: depth_space(config.stereo),
                    _image("stereo", "stereo_depth"), _stereo_points)


# -- the sonar ring: a range a cone ----------------------------------------------------------

def _cones(robot: RobotInfo) -> frozenset[str]:
    spec = robot.specs.get(sonar.NAME)
    return frozenset(sonar.reading_name(i) for i in range(spec.count if spec else 0))


def _sonar_space(config: EnvConfig, robot: RobotInfo) -> gym.spaces.Box:
    far = 1.0 if config.normalize_observations else config.sonar.clip_m
    return gym.spaces.Box(0.0, far, (len(_cones(robot)),), np.float32)


def _ranges(frame: SensorFrame, robot: RobotInfo) -> np.ndarray | None:
    """The cones' ranges in cone order (m, float32), or ``None`` if one is missing."""
    names = sorted(_cones(robot), key=lambda name: int(name.rsplit("_", 1)[1]))
    if not names or any(name not in frame.readings for name in names):
        return None
    return np.array([frame.readings[name] for name in names], dtype=np.float32)


def _sonar_value(config: EnvConfig, robot: RobotInfo, frame: SensorFrame,
                 extra: Mapping[str, Any]) -> np.ndarray:
    """The cones' ranges clipped at ``sonar.clip_m`` (no echo: ``clip_m``, closer than the
    minimum: 0), normalised if asked."""
    ranges = _ranges(frame, robot)
    if ranges is None:
        raise ValueError("goToPose (sonar): the frame lacks a sonar cone's range")
    far = config.sonar.clip_m
    ranges = np.clip(np.nan_to_num(ranges, nan=far, posinf=far, neginf=0.0), 0.0, far)
    return (ranges / far if config.normalize_observations else ranges).astype(np.float32)


def _sonar_points(frame: SensorFrame, robot: RobotInfo) -> np.ndarray | None:
    """Each cone's echo as a point on its axis (``ScanData.points``: no echo dropped, too
    close at the minimum range): a cone's nearest surface may lie off its axis, up to half
    its angle away."""
    ranges, spec = _ranges(frame, robot), robot.specs.get(sonar.NAME)
    if ranges is None or spec is None:
        return None
    yaws = spec.cone_yaws_rad()
    step = float(yaws[1] - yaws[0]) if len(yaws) > 1 else 0.0
    scan = ScanData(ranges, float(yaws[0]), step, spec.range_min_m, spec.range_max_m,
                    robot.mounts.get(sonar.NAME, _ORIGIN))
    return scan.points()


SONAR = SensorPart(_cones, _sonar_space, _sonar_value, _sonar_points)
