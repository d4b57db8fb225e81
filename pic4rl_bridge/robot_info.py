"""The robot as the tasks see it (``RobotInfo``): its spec's footprint, limits and sensor
mounts, with the env's own velocity limits applied."""

from __future__ import annotations

import math
from dataclasses import dataclass

from pic4rl_metrics.geometry import Footprint
from pic4rl_sim.engine.geometry import Pose2D
from pic4rl_sim.engine.robot_specs import DepthCameraSpec, Drive, RobotSpec

from .config import EnvConfig

#: What a robot without a depth camera reports as its field of view: the stock camera's.
_STOCK_HFOV_RAD = math.radians(DepthCameraSpec.hfov_deg)


@dataclass(frozen=True)
class RobotInfo:
    """The robot as the tasks see it: footprint, drive, the commanded velocity ranges (the
    env's limits within the robot's), sensor mounts in the base frame, control period, and
    the robot's acceleration limits (m/s², rad/s²; ``inf`` when unknown)."""

    name: str
    footprint: Footprint
    omni: bool
    min_linear_m_s: float
    max_linear_m_s: float
    max_angular_rad_s: float
    max_lateral_m_s: float
    control_dt_s: float
    lidar_mount: Pose2D | None = None
    depth_mount: Pose2D | None = None
    depth_hfov_rad: float = _STOCK_HFOV_RAD
    max_linear_accel_m_s2: float = math.inf  # the robot's (classical planners' window)
    max_angular_accel_rad_s2: float = math.inf

    @classmethod
    def of(cls, spec: RobotSpec, config: EnvConfig, control_dt_s: float) -> RobotInfo:
        """``spec`` under the env's velocity limits (``config``; 0: the robot's own)."""
        c = config
        omni = spec.drive is Drive.OMNI
        lidar = spec.lidar and Pose2D(spec.lidar.mount_xyz_m[0], spec.lidar.mount_xyz_m[1],
                                      spec.lidar.mount_yaw_rad)
        depth = spec.depth and Pose2D(spec.depth.mount_xyz_m[0], spec.depth.mount_xyz_m[1], 0.0)
        max_linear = _limit(c.max_linear_m_s, spec.max_linear_m_s)
        return cls(
            name=spec.name, footprint=spec.footprint, omni=omni,
            min_linear_m_s=-max_linear if omni else max(c.min_linear_m_s, -max_linear),
            max_linear_m_s=max_linear,
            max_angular_rad_s=_limit(c.max_angular_rad_s, spec.max_angular_rad_s),
            max_lateral_m_s=_limit(c.max_lateral_m_s, spec.max_lateral_m_s) if omni else 0.0,
            control_dt_s=control_dt_s, lidar_mount=lidar or None, depth_mount=depth or None,
            depth_hfov_rad=math.radians(spec.depth.hfov_deg) if spec.depth else _STOCK_HFOV_RAD,
            max_linear_accel_m_s2=spec.max_linear_accel_m_s2,
            max_angular_accel_rad_s2=spec.max_angular_accel_rad_s2)


def _limit(wanted: float, robot_limit: float) -> float:
    return robot_limit if wanted <= 0 else min(wanted, robot_limit)
