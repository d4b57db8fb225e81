"""Decoded sensor data: what a task sees at one control step, whichever transport made it.

Both transports build the same ``SensorFrame`` from the same values: the ROS transport decodes
messages, the in-process transport reads the engine and passes poses through the same
quaternion round trip and ranges through the same float32 buffers, so that the same seed and
actions give bit-identical observations and rewards through both.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from types import MappingProxyType
from typing import Any

import numpy as np

from pic4rl_base.geometry import Pose2D, scan_points, yaw_from_quaternion, yaw_to_quaternion
from pic4rl_base.goal import Goal
from pic4rl_sim.engine.geometry import Twist2D


def as_published(pose: Pose2D) -> Pose2D:
    """``pose`` as a subscriber decodes it from a message: yaw through its quaternion."""
    return Pose2D(pose.x, pose.y, yaw_from_quaternion(*yaw_to_quaternion(pose.yaw)))


@dataclass(frozen=True)
class ScanData:
    """A planar scan (``sensor_msgs/LaserScan`` decoded): ranges (m, float32, REP 117 ±inf)
    at angles ``angle_min_rad + i * angle_increment_rad`` in the scan's frame, mounted at
    ``mount`` in the robot's base frame."""

    ranges: np.ndarray
    angle_min_rad: float
    angle_increment_rad: float
    range_min_m: float
    range_max_m: float
    mount: Pose2D = Pose2D(0.0, 0.0, 0.0)

    def angles(self) -> np.ndarray:
        """Beam angles (rad) in the scan's frame."""
        return self.angle_min_rad + self.angle_increment_rad * np.arange(len(self.ranges))

    def base_angles(self) -> np.ndarray:
        """Beam directions (rad, not wrapped) in the robot's base frame: ``angles()`` turned by
        the mount's yaw. ``points`` places the returns along the same directions, from the
        mount's position."""
        return self.angles() + self.mount.yaw

    def points(self) -> np.ndarray:
        """The returns as points (n, 2) in the base frame (m; ``geometry.scan_points``).

        ``+inf`` (nothing in range) and NaN beams are dropped; ``-inf`` (REP 117: closer than
        ``range_min_m``) counts as a return at ``range_min_m``.
        """
        ranges = np.asarray(self.ranges, dtype=np.float64)
        ranges = np.where(np.isneginf(ranges), self.range_min_m, ranges)
        keep = np.isfinite(ranges)
        return np.column_stack(scan_points(ranges[keep], self.angles()[keep], self.mount))


@dataclass(frozen=True, init=False)
class SensorFrame:
    """Everything a task may read at one step: pose, twist and goal, and each sensor's reading
    by its ``pic4rl_bridge.readings.sensor_table.SENSORS`` name (given as keywords too,
    ``scan=...``); a sensor the robot lacks, or the task did not ask for, is absent (its accessor:
    ``None``).

    ``pose`` and ``twist`` come from the configured pose topic (wheel odometry by default, in
    the frame the goal is given in); ``goal`` is the current goal in that frame; ``depth`` is
    height × width metres (float32, ±inf out of range); ``person`` is the person's pose;
    ``plan`` is the latest global plan (k × 2, m, in the goal's frame). ``contact`` says
    whether the robot touched anything during the step, sensed or not, as only a simulator
    knows it (the engine's ``StepResult.collided``); ``None``: not known (a real robot, a
    reset's frame).
    """

    stamp_ns: int
    pose: Pose2D
    twist: Twist2D
    goal: Goal | None
    readings: Mapping[str, Any]
    contact: bool | None

    def __init__(self, stamp_ns: int, pose: Pose2D, twist: Twist2D,
                 goal: Goal | None = None,
                 readings: Mapping[str, Any] | None = None, contact: bool | None = None,
                 **sensors: Any) -> None:
        """``sensors`` by name add to (or replace) ``readings``; a ``None`` one is absent
        (``dataclasses.replace(frame, scan=None)`` drops the scan)."""
        for name, value in (("stamp_ns", stamp_ns), ("pose", pose), ("twist", twist),
                            ("goal", goal), ("contact", contact)):
            object.__setattr__(self, name, value)
        merged = {**(readings or {}), **sensors} if sensors else readings or {}
        object.__setattr__(self, "readings", MappingProxyType(
            {name: value for name, value in merged.items() if value is not None}))

    # The stock sensors, typed; another is read as ``readings.get(name)``.
    @property
    def scan(self) -> ScanData | None:
        return self.readings.get("scan")

    @property
    def depth(self) -> np.ndarray | None:
        return self.readings.get("depth")

    @property
    def person(self) -> Pose2D | None:
        return self.readings.get("person")

    @property
    def plan(self) -> np.ndarray | None:
        return self.readings.get("plan")
