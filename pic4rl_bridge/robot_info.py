"""The robot as the tasks see it (``RobotInfo``): its spec's footprint, limits and sensor
mounts, with the env's own velocity limits applied."""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

from pic4rl_base.geometry import Footprint, Pose2D
from pic4rl_sim.engine.robot_specs import DepthCameraSpec, Drive, RobotSpec

from .config import EnvConfig

#: What a robot without a depth camera reports as its field of view: the stock camera's.
_STOCK_HFOV_RAD = math.radians(DepthCameraSpec.hfov_deg)


@dataclass(frozen=True)
class RobotInfo:
    """The robot as the tasks see it: footprint, drive, the commanded velocity ranges (the
    env's limits within the robot's), control period, the mount of each sensor it carries in
    the base frame (``mounts``, by sensor kind: ``lidar``, ``depth``), and the robot's
    acceleration limits (m/s², rad/s²; ``inf`` when unknown)."""

    name: str
    footprint: Footprint
    omni: bool
    min_linear_m_s: float
    max_linear_m_s: float
    max_angular_rad_s: float
    max_lateral_m_s: float
    control_dt_s: float
    mounts: Mapping[str, Pose2D] = field(default_factory=dict, hash=False)
    #: The spec of each sensor it carries, by sensor kind (what a sensor's observation and
    #: collision part read: a sonar ring's cones, a camera's field of view).
    specs: Mapping[str, Any] = field(default_factory=dict, hash=False)
    depth_hfov_rad: float = _STOCK_HFOV_RAD
    #: the depth camera's height above the floor (m; ``None``: unknown, so no pixel is taken
    #: for the floor) and downward pitch (rad): where its lower rows see the floor
    depth_height_m: float | None = None
    depth_pitch_rad: float = 0.0
    max_linear_accel_m_s2: float = math.inf  # the robot's (classical planners' window)
    max_angular_accel_rad_s2: float = math.inf

    @classmethod
    def of(cls, spec: RobotSpec, config: EnvConfig, control_dt_s: float) -> RobotInfo:
        """``spec`` under the env's velocity limits (``config``; 0: the robot's own)."""
        c = config
        omni = spec.drive is Drive.OMNI
        mounts = {kind: Pose2D(s.mount_xyz_m[0], s.mount_xyz_m[1],
                               getattr(s, "mount_yaw_rad", 0.0))
                  for kind, s in spec.sensors.items() if hasattr(s, "mount_xyz_m")}
        max_linear = _limit(c.max_linear_m_s, spec.max_linear_m_s)
        return cls(
            name=spec.name, footprint=spec.footprint, omni=omni,
            min_linear_m_s=-max_linear if omni else max(c.min_linear_m_s, -max_linear),
            max_linear_m_s=max_linear,
            max_angular_rad_s=_limit(c.max_angular_rad_s, spec.max_angular_rad_s),
            max_lateral_m_s=_limit(c.max_lateral_m_s, spec.max_lateral_m_s) if omni else 0.0,
            control_dt_s=control_dt_s, mounts=mounts,
            specs={k: s for k, s in spec.sensors.items() if s is not None},
            depth_hfov_rad=math.radians(spec.depth.hfov_deg) if spec.depth else _STOCK_HFOV_RAD,
            depth_height_m=spec.depth.mount_xyz_m[2] if spec.depth else None,
            depth_pitch_rad=spec.depth.mount_pitch_rad if spec.depth else 0.0,
            max_linear_accel_m_s2=spec.max_linear_accel_m_s2,
            max_angular_accel_rad_s2=spec.max_angular_accel_rad_s2)


    @property
    def lidar_mount(self) -> Pose2D | None:
        return self.mounts.get("lidar")

    @property
    def depth_mount(self) -> Pose2D | None:
        return self.mounts.get("depth")


def _limit(wanted: float, robot_limit: float) -> float:
    return robot_limit if wanted <= 0 else min(wanted, robot_limit)
