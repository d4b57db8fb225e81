"""A rolling occupancy grid of the robot's own scans: what a mapless robot can remember.

Each scan's returns (``ScanData.points``: the beams' angles and the LiDAR's
mount, REP 117's ±inf) are placed with the frame's pose (the pose topic's: wheel odometry by
default) and mark world-fixed cells of ``resolution_m`` as occupied. Nothing else is marked:
unknown space counts as free, the optimistic convention of nav2's rolling costmap with
``track_unknown_space: false`` and of D* Lite in unknown terrain. Marking is idempotent (the
same frame twice gives the same grid), so the grid is a function of the frames seen, whichever
transport made them. Cells are only marked unless a reader opts into ``clear_scan``, nav2's
obstacle layer's raytrace clearing: a scan's beams free the occupied cells they pass through
short of their returns, so people and moving obstacles leave no trails. It grows as the robot sees farther; past ``max_extent_m`` across it rolls,
forgetting the cells farthest from the robot. ``reset`` clears it (one grid per episode).

Two readers: the mapless ``explorer`` baseline (``pic4rl_bridge.baselines.explorer``) plans on it,
and goToPose's memory observation is its egocentric crop (``crop``: heading up, the robot at the
centre, as nav2's rolling local costmap is centred on the robot).
"""

from __future__ import annotations

import math

import numpy as np
from pic4rl_base.geometry import Pose2D, wrap_angle

from ..robot_info import RobotInfo
from ..readings.frame import ScanData, SensorFrame
from .collision import depth_scan

#: Cell size (m) of the grids the explorer and the memory observation keep.
GRID_RESOLUTION_M = 0.05
_GROW_MARGIN_CELLS = 64  # grown by at least this much on a side, so that it rarely regrows
#: ``clear_scan`` frees only cells whose centres lie this many cells short of the beam's return:
#: the surface it hit, seen again a cell nearer or farther (noise, another viewpoint), stays.
_CLEAR_SHORT_CELLS = 2.0


def to_world(points: np.ndarray, pose: Pose2D) -> np.ndarray:
    """Points (n, 2) of the base frame at ``pose`` in the pose's frame (m)."""
    c, s = math.cos(pose.yaw), math.sin(pose.yaw)
    x, y = points[:, 0], points[:, 1]
    return np.column_stack((pose.x + c * x - s * y, pose.y + s * x + c * y))


def sensed_scans(frame: SensorFrame, robot: RobotInfo, sensors: tuple[str, ...] = (),
                 depth_rows: int = 0) -> list[ScanData]:
    """What the grid marks from ``frame``: the scans of ``sensors`` (``lidar``: the scan;
    ``depth``: the depth image's pseudo-scan, ``depth_scan`` of its ``depth_rows`` middle rows,
    0: all), each that the frame holds, so an agent's memory and plan hold what it observes
    (``[lidar, depth]``: both, a fused grid). With no ``sensors`` (a real robot's frames): the
    scan, else the depth image's pseudo-scan."""
    scans: list[ScanData] = []
    lidar = "lidar" in sensors or not sensors
    if frame.scan is not None and lidar:
        scans.append(frame.scan)
    if frame.depth is not None and ("depth" in sensors or not scans):
        scans.append(depth_scan(frame.depth, robot.depth_mount or Pose2D(0.0, 0.0, 0.0),
                                robot.depth_hfov_rad, depth_rows, height_m=robot.depth_height_m,
                                pitch_rad=robot.depth_pitch_rad))
    return scans


class OccupancyGrid:
    """World-fixed occupied cells (integer indices ``floor(xy / resolution_m)``), kept both
    as a list (``cells``, in the order first seen) and as a mask for the look-up."""

    def __init__(self, resolution_m: float = GRID_RESOLUTION_M, *,
                 max_extent_m: float = 60.0) -> None:
        self.resolution_m = resolution_m
        self.max_cells = max(1, int(max_extent_m / resolution_m))
        self.reset()

    def reset(self) -> None:
        """Forget every cell (a new episode)."""
        self._origin = np.zeros(2, dtype=np.int64)  # world index of the mask's [0, 0]
        self._mask = np.zeros((0, 0), dtype=bool)  # [iy, ix]
        self._cells = np.zeros((0, 2), dtype=np.int64)

    @property
    def cells(self) -> np.ndarray:
        """The occupied cells' world indices (k, 2: ix, iy)."""
        return self._cells

    def centres(self) -> np.ndarray:
        """The occupied cells' centres (k, 2, m)."""
        return (self._cells + 0.5) * self.resolution_m

    def occupied(self, xy: np.ndarray) -> np.ndarray:
        """Whether the cell of each point of ``xy`` (n, 2, m) is occupied."""
        local = np.floor(np.asarray(xy) / self.resolution_m).astype(np.int64) - self._origin
        h, w = self._mask.shape
        inside = (local[:, 0] >= 0) & (local[:, 0] < w) & (local[:, 1] >= 0) & (local[:, 1] < h)
        out = np.zeros(len(local), dtype=bool)
        out[inside] = self._mask[local[inside, 1], local[inside, 0]]
        return out

    def mark_scan(self, scan: ScanData, pose: Pose2D) -> np.ndarray:
        """Mark the returns of ``scan`` taken at ``pose``; the cells new to the grid (k, 2)."""
        return self.mark(to_world(scan.points(), pose), (pose.x, pose.y))

    def mark(self, points: np.ndarray, centre: tuple[float, float]) -> np.ndarray:
        """Mark the cells of ``points`` (n, 2, m, world) seen from ``centre`` (the robot,
        which the grid keeps inside when it rolls); the cells new to the grid (k, 2)."""
        if not len(points):
            return np.zeros((0, 2), dtype=np.int64)
        idx = np.floor(points / self.resolution_m).astype(np.int64)
        self._fit(idx, np.floor(np.asarray(centre) / self.resolution_m).astype(np.int64))
        h, w = self._mask.shape
        local = idx - self._origin
        inside = (local[:, 0] >= 0) & (local[:, 0] < w) & (local[:, 1] >= 0) & (local[:, 1] < h)
        flat = np.unique(local[inside, 1] * w + local[inside, 0])
        flat = flat[~self._mask.ravel()[flat]]
        self._mask.ravel()[flat] = True
        iy, ix = np.divmod(flat, w)
        new = np.column_stack((ix, iy)) + self._origin
        self._cells = np.concatenate((self._cells, new))
        return new

    def clear_scan(self, scan: ScanData, pose: Pose2D) -> np.ndarray:
        """Free the occupied cells that the beams of ``scan`` taken at ``pose`` pass through at
        least ``_CLEAR_SHORT_CELLS`` cells short of their returns (``+inf``: nothing up to
        ``range_max_m``; NaN: nothing freed); the cells freed (k, 2). Each cell is tested
        against its nearest beam: the ray crosses the cell's square."""
        ranges = np.asarray(scan.ranges, dtype=np.float64)
        if not len(self._cells) or not len(ranges):
            return np.zeros((0, 2), dtype=np.int64)
        ranges = np.where(np.isneginf(ranges), scan.range_min_m, ranges)
        ranges = np.nan_to_num(np.where(np.isposinf(ranges), scan.range_max_m, ranges), nan=0.0)
        origin = to_world(np.array([[scan.mount.x, scan.mount.y]]), pose)[0]
        rel = self.centres() - origin
        dist = np.hypot(rel[:, 0], rel[:, 1])
        inc, n = scan.angle_increment_rad, len(ranges)
        first = pose.yaw + scan.mount.yaw + scan.angle_min_rad  # beam 0's world direction
        mid = 0.5 * inc * (n - 1)
        offset = wrap_angle(np.arctan2(rel[:, 1], rel[:, 0]) - first - mid) + mid
        beam = np.rint(offset / inc).astype(np.int64) if inc else np.zeros(len(dist), np.int64)
        if abs(inc) * n >= 2.0 * math.pi - 1e-9:  # a full turn: the seam's cells to beam 0
            beam %= n
        inside = (beam >= 0) & (beam < n)
        beam = np.clip(beam, 0, n - 1)
        direction = first + beam * inc
        # a line crosses a square of half-side h when its distance to the centre is at most
        # h (|cos| + |sin|) of its direction
        across = np.abs(rel[:, 0] * np.sin(direction) - rel[:, 1] * np.cos(direction))
        reach = 0.5 * self.resolution_m * (np.abs(np.cos(direction)) + np.abs(np.sin(direction)))
        free = (inside & (across <= reach)
                & (dist <= ranges[beam] - _CLEAR_SHORT_CELLS * self.resolution_m))
        if not free.any():
            return np.zeros((0, 2), dtype=np.int64)
        cleared = self._cells[free]
        local = cleared - self._origin
        self._mask[local[:, 1], local[:, 0]] = False
        self._cells = self._cells[~free]
        return cleared

    def _fit(self, idx: np.ndarray, centre: np.ndarray) -> None:
        """Grow the mask to hold ``idx`` (with a margin), or roll it round ``centre`` when that
        would pass ``max_cells`` across: the cells outside the new window are forgotten."""
        h, w = self._mask.shape
        lo, hi = self._origin, self._origin + np.array([w, h])
        need_lo, need_hi = np.minimum(idx.min(axis=0), centre), np.maximum(idx.max(axis=0),
                                                                          centre) + 1
        if w and h and (need_lo >= lo).all() and (need_hi <= hi).all():
            return
        if w and h:
            need_lo, need_hi = np.minimum(need_lo, lo), np.maximum(need_hi, hi)
        new_lo = need_lo - _GROW_MARGIN_CELLS
        new_hi = need_hi + _GROW_MARGIN_CELLS
        for axis in (0, 1):  # roll: a window of max_cells centred on the robot
            if new_hi[axis] - new_lo[axis] > self.max_cells:
                new_lo[axis] = centre[axis] - self.max_cells // 2
                new_hi[axis] = new_lo[axis] + self.max_cells
        keep = ((self._cells >= new_lo) & (self._cells < new_hi)).all(axis=1)
        self._cells = self._cells[keep]
        size = new_hi - new_lo
        self._mask = np.zeros((int(size[1]), int(size[0])), dtype=bool)
        self._origin = new_lo
        local = self._cells - new_lo
        self._mask[local[:, 1], local[:, 0]] = True

    def crop(self, pose: Pose2D, size: int, resolution_m: float) -> np.ndarray:
        """The egocentric crop (size × size, uint8: 255 occupied, 0 free or unknown) of
        pixels ``resolution_m`` wide round ``pose``, heading up: row 0 is farthest ahead,
        column 0 farthest left, and the robot stands where the four middle pixels meet. A
        pixel is occupied when an occupied cell's centre lies in it."""
        image = np.zeros((size, size), dtype=np.uint8)
        if not len(self._cells):
            return image
        centres = self.centres()
        dx, dy = centres[:, 0] - pose.x, centres[:, 1] - pose.y
        c, s = math.cos(pose.yaw), math.sin(pose.yaw)
        row = np.floor(0.5 * size - (c * dx + s * dy) / resolution_m)
        col = np.floor(0.5 * size - (-s * dx + c * dy) / resolution_m)
        keep = (row >= 0) & (row < size) & (col >= 0) & (col < size)
        image[row[keep].astype(np.intp), col[keep].astype(np.intp)] = 255
        return image
