"""How close the nearest obstacle is to the robot's footprint, from what the robot senses.

The paper's collision test: any scan point closer to the footprint than
``collision_tolerance_m``; in simulation also the engine's contact (``assess``). It runs
every step on every beam, so it is plain vectorized numpy:
beams to points in the base frame (``ScanData.points``), then the exact signed distance to the
footprint, a circle or a box (``Footprint.signed_distance``).
Which sensor's points count is the observed sensors' table's (``OBSERVED_TABLE``, each
entry's part's ``points``, ``pic4rl_bridge.perception.sensor_parts``): the first that gives
points for the frame, so robots without a LiDAR fall back on the depth image (each column's
nearest pixel that is not the floor), then on a sonar ring's echoes or a stereo image; a
sensor added to the table adds its points with no change here.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from pic4rl_base.geometry import Pose2D, sensor_to_base
from pic4rl_metrics.contract import CollisionRule

from ..config import EnvConfig
from ..readings.frame import ScanData, SensorFrame
from ..robot_info import RobotInfo
from ..settings.observations import OBSERVED_TABLE

#: Pixels whose point lies this high above the floor or lower are the floor, not an obstacle
#: (``pointcloud_to_laserscan``'s ``min_height``): a camera sees the floor in its lower rows,
#: and a pseudo-scan of every row's nearest pixel would ring the robot with it.
FLOOR_M = 0.05


def _nearest_per_column(depth: np.ndarray, hfov_rad: float, rows: int,
                        height_m: float | None, pitch_rad: float) -> np.ndarray:
    """Each column's nearest obstacle pixel's forward distance (m, level; ``inf``: none,
    ``0``: a ``-inf`` pixel, closer than the camera's minimum) of the ``rows`` middle rows
    (0: all), the floor's pixels dropped (``height_m``: the camera's height above the floor,
    ``pitch_rad`` its downward pitch; ``None``: no floor is known, every pixel counts)."""
    image = np.asarray(depth, dtype=np.float64)
    height, width = image.shape
    focal_px = 0.5 * width / math.tan(0.5 * hfov_rad)
    down = (np.arange(height) + 0.5 - 0.5 * height) / focal_px  # image rows: down +
    cp, sp = math.cos(pitch_rad), math.sin(pitch_rad)
    image = np.where(np.isneginf(image), 0.0, np.where(np.isnan(image), np.inf, image))
    forward = image * (cp - sp * down)[:, None]
    if height_m is not None:
        with np.errstate(invalid="ignore"):  # inf x 0 on a row level with the floor's horizon
            up = height_m - image * (sp + cp * down)[:, None]
        forward = np.where(np.isfinite(image) & (image > 0.0) & (up <= FLOOR_M), np.inf,
                           forward)
    if 0 < rows < height:
        top = (height - rows) // 2
        forward = forward[top:top + rows]
    return forward.min(axis=0)


def depth_points(depth: np.ndarray, mount: Pose2D, hfov_rad: float, *,
                 height_m: float | None = None, pitch_rad: float = 0.0) -> np.ndarray:
    """The nearest obstacle pixel of each column of a depth image (H × W, m along the optical
    axis) as a point (n, 2) in the base frame, for a pinhole camera of horizontal field of view
    ``hfov_rad`` mounted at ``mount`` (``height_m`` above the floor, pitched down ``pitch_rad``:
    the floor's pixels are not obstacles; ``None``: every pixel is). ``+inf``/NaN pixels are
    ignored; ``-inf`` (closer than the camera's minimum) counts as depth 0, so a blinded camera
    reads as touching."""
    nearest = _nearest_per_column(depth, hfov_rad, 0, height_m, pitch_rad)
    width = nearest.shape[0]
    focal_px = 0.5 * width / math.tan(0.5 * hfov_rad)
    right = (np.arange(width) + 0.5 - 0.5 * width) / focal_px  # tan of the bearing, right +
    keep = np.isfinite(nearest)
    d = nearest[keep]
    return np.column_stack(sensor_to_base(d, -d * right[keep], mount))


def depth_scan(depth: np.ndarray, mount: Pose2D, hfov_rad: float, rows: int = 0, *,
               height_m: float | None = None, pitch_rad: float = 0.0) -> ScanData:
    """A pseudo-scan from a depth image (H × W, m along the optical axis) of a pinhole camera
    of horizontal field of view ``hfov_rad`` mounted at ``mount``, as
    ``depthimage_to_laserscan`` makes one: ``W`` beams evenly spaced across the field of view
    (counter-clockwise, the scan's convention), each the nearest obstacle pixel of the column
    its ray crosses (of the ``rows`` middle rows; 0: all) over the cosine of its bearing, so a
    wall square to the camera reads as its true range. With ``height_m`` (the camera's height
    above the floor, pitched down ``pitch_rad``) the floor's pixels are dropped, as
    ``pointcloud_to_laserscan``'s ``min_height`` does (``FLOOR_M``). ``+inf``/NaN pixels give
    ``+inf`` (no return), ``-inf`` (closer than the camera's minimum) ``-inf``."""
    nearest = _nearest_per_column(depth, hfov_rad, rows, height_m, pitch_rad)
    width = nearest.shape[0]
    step = hfov_rad / width
    angles = -0.5 * hfov_rad + (np.arange(width) + 0.5) * step
    focal_px = 0.5 * width / math.tan(0.5 * hfov_rad)
    column = np.clip(np.floor(0.5 * width - focal_px * np.tan(angles)), 0, width - 1)
    z = nearest[column.astype(np.intp)]
    ranges = np.where(z <= 0.0, -np.inf, z / np.cos(angles)).astype(np.float32)
    return ScanData(ranges, float(angles[0]), float(step), 0.0, math.inf, mount)


def sensed_points(frame: SensorFrame, robot: RobotInfo) -> np.ndarray:
    """The obstacle points (n, 2, base frame, m) the robot senses: those of the first sensor
    of ``OBSERVED_TABLE`` whose part gives points for the frame (its readings there: the
    LiDAR's scan, else the depth image, else the sonar ring, else the stereo image, else a
    user's sensor's); none without one."""
    for entry in OBSERVED_TABLE.values():
        points = entry.part.points(frame, robot)
        if points is not None:
            return points
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
    ``collision_tolerance_m`` is violated or the robot touches something, whether an obstacle
    is within ``warning_tolerance_m``, the streak of violating steps, whether the episode ends
    as a collision, and by which rule (``None`` when it goes on)."""

    min_obstacle_m: float
    collision: bool
    warning: bool
    streak: int
    ended: bool
    rule: CollisionRule | None = None


def assess(frame: SensorFrame, robot: RobotInfo, config: EnvConfig, streak: int) -> Safety:
    """The collision check every task shares; ``streak`` counts the violating steps before.

    The sensed rule (the paper's): a sensed point closer than ``collision_tolerance_m`` for
    ``collision_steps`` steps. In simulation (``frame.contact`` known) a contact ends the
    episode too, sensed or not: a box below the LiDAR's plane stops the robot without a
    sensed point. Both at one step: ``SENSED``."""
    distance = obstacle_distance(frame, robot)
    near = distance < config.collision_tolerance_m
    streak = streak + 1 if near else 0
    rule = (CollisionRule.SENSED if streak >= config.collision_steps
            else CollisionRule.CONTACT if frame.contact else None)
    return Safety(distance, near or bool(frame.contact), distance < config.warning_tolerance_m,
                  streak, rule is not None, rule)
