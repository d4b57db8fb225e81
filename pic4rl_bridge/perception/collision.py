"""How close the nearest obstacle is to the robot's footprint, from what the robot senses.

The paper's collision test: any scan point closer to the footprint than
``collision_tolerance_m``. It runs every step on every beam, so it is plain vectorized numpy:
beams to points in the base frame (``ScanData.points``), then the exact signed distance to the
footprint, a circle or a box (``Footprint.signed_distance``).
Robots without a LiDAR fall back on the depth image (each column's nearest pixel). Any range
sensor whose reading decodes to a ``ScanData`` (a sonar's fan, a point cloud's slice) senses
obstacles the same way, in the sensor table's order, with no change here.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from pic4rl_metrics.geometry import sensor_to_base
from pic4rl_sim.engine.geometry import Pose2D

from ..config import EnvConfig
from ..robot_info import RobotInfo
from ..transports.frame import ScanData, SensorFrame
from ..transports.sensor_table import SENSORS


def depth_points(depth: np.ndarray, mount: Pose2D, hfov_rad: float) -> np.ndarray:
    """The nearest pixel of each column of a depth image (H × W, m along the optical axis) as
    a point (n, 2) in the base frame, for a level pinhole camera of horizontal field of view
    ``hfov_rad`` mounted at ``mount``. ``+inf``/NaN pixels are ignored; ``-inf`` (closer than
    the camera's minimum) counts as depth 0, so a blinded camera reads as touching."""
    image = np.asarray(depth, dtype=np.float64)
    image = np.where(np.isneginf(image), 0.0, image)
    nearest = np.where(np.isfinite(image), image, np.inf).min(axis=0)
    width = image.shape[1]
    focal_px = 0.5 * width / math.tan(0.5 * hfov_rad)
    right = (np.arange(width) + 0.5 - 0.5 * width) / focal_px  # tan of the bearing, right +
    keep = np.isfinite(nearest)
    d = nearest[keep]
    return np.column_stack(sensor_to_base(d, -d * right[keep], mount))


def depth_scan(depth: np.ndarray, mount: Pose2D, hfov_rad: float,
               rows: int = 0) -> ScanData:
    """A pseudo-scan from a depth image (H × W, m along the optical axis) of a level pinhole
    camera of horizontal field of view ``hfov_rad`` mounted at ``mount``, as
    ``depthimage_to_laserscan`` makes one: ``W`` beams evenly spaced across the field of view
    (counter-clockwise, the scan's convention), each the nearest pixel of the column its ray
    crosses (of the ``rows`` middle rows; 0: all) over the cosine of its bearing, so a wall
    square to the camera reads as its true range. ``+inf``/NaN pixels give ``+inf`` (no
    return), ``-inf`` (closer than the camera's minimum) ``-inf``."""
    image = np.asarray(depth, dtype=np.float64)
    height, width = image.shape
    if 0 < rows < height:
        top = (height - rows) // 2
        image = image[top:top + rows]
    image = np.where(np.isneginf(image), 0.0, image)
    nearest = np.where(np.isnan(image), np.inf, image).min(axis=0)
    step = hfov_rad / width
    angles = -0.5 * hfov_rad + (np.arange(width) + 0.5) * step
    focal_px = 0.5 * width / math.tan(0.5 * hfov_rad)
    column = np.clip(np.floor(0.5 * width - focal_px * np.tan(angles)), 0, width - 1)
    z = nearest[column.astype(np.intp)]
    ranges = np.where(z <= 0.0, -np.inf, z / np.cos(angles)).astype(np.float32)
    return ScanData(ranges, float(angles[0]), float(step), 0.0, math.inf, mount)


def sensed_points(frame: SensorFrame, robot: RobotInfo) -> np.ndarray:
    """The obstacle points (n, 2, base frame, m) the robot senses: those of the first reading,
    in the sensor table's order, that is a scan (the LiDAR's, or any range sensor's decoded
    to ``ScanData``) or the depth image; none without one."""
    for sensor in SENSORS:
        reading = frame.readings.get(sensor.name)
        if isinstance(reading, ScanData):
            return reading.points()
        if sensor.name == "depth" and reading is not None:
            mount = robot.depth_mount or Pose2D(0.0, 0.0, 0.0)
            return depth_points(reading, mount, robot.depth_hfov_rad)
    return np.empty((0, 2))


def obstacle_distance(frame: SensorFrame, robot: RobotInfo) -> float:
    """Distance (m) from the footprint to the nearest obstacle sensed: from the scan, else from
    the depth image, else ``inf``. Negative when a return lies inside the footprint."""
    points = sensed_points(frame, robot)
    if len(points) == 0:
        return math.inf
    return float(robot.footprint.signed_distance(points).min())


class Safety(NamedTuple):
    """One step's collision check: nearest obstacle (m), whether the footprint plus
    ``collision_tolerance_m`` is violated, whether one is within ``warning_tolerance_m``,
    the streak of violating steps and whether it reached ``collision_steps``."""

    min_obstacle_m: float
    collision: bool
    warning: bool
    streak: int
    ended: bool


def assess(frame: SensorFrame, robot: RobotInfo, config: EnvConfig, streak: int) -> Safety:
    """The collision check every task shares; ``streak`` counts the violating steps before."""
    distance = obstacle_distance(frame, robot)
    collision = distance < config.collision_tolerance_m
    streak = streak + 1 if collision else 0
    return Safety(distance, collision, distance < config.warning_tolerance_m, streak,
                  streak >= config.collision_steps)
