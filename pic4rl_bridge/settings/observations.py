"""The env's observation sections (``lidar:``, ``depth:``, ``memory:`` of ``nav_env``): how
each sensor's reading is reduced to what a policy is fed, apart from ``pic4rl_bridge.config``
so that every sensor's settings sit together; the encoders that apply them are
``pic4rl_bridge.perception.observations``.
"""

from __future__ import annotations

from dataclasses import dataclass

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
