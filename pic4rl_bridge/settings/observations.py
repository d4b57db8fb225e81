"""The env's observation sections (``lidar:``, ``depth:``, ``sonar:``, ``stereo:``,
``memory:`` of ``nav_env``): how each sensor's reading is reduced to what a policy is fed,
apart from ``pic4rl_bridge.config`` so that every sensor's settings sit together; and the
table of the sensors an env can observe (``OBSERVED_TABLE``: the ``sensors:`` choices, each
naming its sim kind and its part, ``pic4rl_bridge.perception.sensor_parts``, which encodes
its observation and gives its obstacle points). A user's sensor joins through the
``pic4rl.observations`` entry-point group.
"""

from __future__ import annotations

import importlib
from dataclasses import dataclass
from functools import cached_property
from typing import Any

from pic4rl_base.plugins import load_group
from pic4rl_base.schema import NON_NEGATIVE, POSITIVE, ParamEnum, Range, param


class DepthEncoding(ParamEnum):
    UINT8 = "uint8"
    FLOAT32 = "float32"


@dataclass(frozen=True)
class LidarObsConfig:
    """The LiDAR observation: ``sectors`` of equal width over ``fov_deg`` centred on the
    robot's forward axis, each the minimum range of the sim's rays (its ``lidar.beams``)
    pointing into it, clipped at ``clip_m`` (the sensor's own range is the sim's
    ``lidar.range_max_m``)."""

    sectors: int = param(36, doc="sectors of the observation, each the minimum range of the "
                         "scan's rays in it", range=POSITIVE)
    clip_m: float = param(10.0, doc="the observation's ranges clipped here", unit="m",
                          range=POSITIVE)
    fov_deg: float = param(360.0, doc="the sectors' span, centred on the robot's forward axis "
                           "(sector 0 starts at -fov_deg / 2)", unit="deg",
                           range=Range(0.0, 360.0, lo_open=True))
    history: int = param(1, doc="goToPose: the last N scans' sectors, newest first (a frame "
                         "stack; 1: the current scan only)", range=POSITIVE)


@dataclass(frozen=True)
class DepthObsConfig:
    """The depth observation: the camera's image (the sim's ``depth.width`` × ``depth.height``)
    resized to ``obs_width`` × ``obs_height``, clipped at ``clip_m``; ``uint8`` scales
    [0, clip_m] to [0, 255] so SB3's CNN treats it as an image."""

    obs_width: int = param(80, doc="the observation's width (the image resized)", unit="px",
                           range=POSITIVE)
    obs_height: int = param(60, doc="the observation's height (the image resized)", unit="px",
                            range=POSITIVE)
    clip_m: float = param(5.0, doc="the observation's depths clipped here", unit="m",
                          range=POSITIVE)
    encoding: DepthEncoding = param(DepthEncoding.UINT8, doc="uint8 (an image for SB3's CNN) or "
                                    "float32 (metres)")


@dataclass(frozen=True)
class MemoryObsConfig:
    """goToPose's memory: an egocentric crop of an occupancy grid of the robot's own scans
    (``pic4rl_bridge.perception.occupancy``), beside the usual observation in a Dict."""

    enabled: bool = param(False, doc="goToPose: add the memory crop to the observation (a Dict: "
                          "memory, and lidar or depth and goal)")
    size_px: int = param(64, doc="the crop's width and height", unit="px", range=POSITIVE)
    resolution_m: float = param(0.15, doc="the crop's pixel size", unit="m", range=POSITIVE)
    depth_rows: int = param(0, doc="depth robots: the pseudo-scan's middle rows of the depth "
                            "image (0: all; the floor's pixels never)", range=NON_NEGATIVE)


@dataclass(frozen=True)
class SonarObsConfig:
    """The sonar observation: the ring's ranges (one per cone, ``sonar.count`` of the sim),
    clipped at ``clip_m``."""

    clip_m: float = param(5.0, doc="the observation's sonar ranges clipped here", unit="m",
                          range=POSITIVE)


@dataclass(frozen=True)
class StereoObsConfig(DepthObsConfig):
    """The stereo observation: the stereo camera's depth image (the sim's ``stereo.width`` ×
    ``stereo.height``) encoded as the depth camera's is; NaN (no match) reads as ``clip_m``."""

    obs_height: int = param(48, doc="the observation's height (the image resized)", unit="px",
                            range=POSITIVE)
    clip_m: float = param(10.0, doc="the observation's depths clipped here", unit="m",
                          range=POSITIVE)


@dataclass(frozen=True)
class ObservedSensor:
    """A sensor an env can observe (a ``sensors:`` entry): ``name`` is that entry, its key in
    a Dict observation and its settings' section (``lidar.*``; none for a user's); ``kind``
    the robot's sensor kind (the sim's ``SENSOR_TABLE`` name) that makes it, refused when the
    robot does not carry it; ``part`` names, as ``module:attribute``, its ``SensorPart`` (or a
    function of no arguments that makes one): what it needs of a frame, its observation's
    space and value, its obstacle points. ``flat_alone``: observed alone, it and the goal
    make one vector (the paper's LiDAR layout), not a Dict."""

    name: str
    kind: str
    part_path: str
    flat_alone: bool = False

    @cached_property
    def part(self) -> Any:
        """The ``SensorPart``, imported on first use (the tables above it load first)."""
        module, _, attr = self.part_path.partition(":")
        found = getattr(importlib.import_module(module), attr)
        return found() if callable(found) else found


_PARTS = "pic4rl_bridge.perception.sensor_parts"
#: The sensors an env can observe, in the order the collision check asks them for obstacle
#: points (the first that gives some wins: the LiDAR before the depth camera).
OBSERVED_TABLE: dict[str, ObservedSensor] = {s.name: s for s in (
    ObservedSensor("lidar", "lidar", f"{_PARTS}:LIDAR", flat_alone=True),
    ObservedSensor("depth", "depth", f"{_PARTS}:DEPTH"),
    ObservedSensor("sonar", "sonar", f"{_PARTS}:SONAR"),
    ObservedSensor("stereo", "stereo", f"{_PARTS}:STEREO"),
)}
#: A user's observed sensors, after pic4rl's: each an ``ObservedSensor`` that its package names
#: in this entry-point group under the sensor's name.
OBSERVED_GROUP = "pic4rl.observations"
OBSERVED_TABLE.update(load_group(OBSERVED_GROUP, ObservedSensor, taken=OBSERVED_TABLE))
