"""The ray-casting sensors: a planar LiDAR and a pinhole depth camera, each its spec (the
robot's data, the ``lidar.*``/``depth.*`` parameters) beside the reader the engine builds from it.

Ranges follow REP 117: ``+inf`` = nothing within range, ``-inf`` = closer than the minimum.
MuJoCo is imported when a reader is built, not with the specs: reading a robot or a params
file needs no MuJoCo.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from pic4rl_base.errors import require
from pic4rl_base.geometry import Pose2D, yaw_to_quaternion
from pic4rl_base.schema import FRACTION, Range, check, param

from .sensor_kinds import optical

if TYPE_CHECKING:
    import mujoco


def _to_rep117(values: np.ndarray, hit: np.ndarray, lo: float, hi: float, noise_std: float,
               rng: np.random.Generator) -> np.ndarray:
    """Float32 ranges from true ``values``: noise on hits, then ±inf outside ``[lo, hi]``."""
    out = np.where(hit, values, np.inf)
    if noise_std > 0:
        too_close = out < lo  # judged on the truth: noise cannot bring such a return back
        out += rng.normal(0.0, noise_std, out.shape)  # inf stays inf
        out[too_close] = -np.inf
    out[out > hi] = np.inf
    out[out < lo] = -np.inf
    return out.astype(np.float32)


def _mount_point(pose: Pose2D, c: float, s: float, xyz_m: tuple[float, float, float],
                 out: np.ndarray) -> None:
    """World position of a base-frame mount point, written into ``out``."""
    mx, my, mz = xyz_m
    out[0] = pose.x + c * mx - s * my
    out[1] = pose.y + s * mx + c * my
    out[2] = mz


@dataclass(frozen=True)
class LidarSpec:
    """A planar LiDAR: ``beams`` rays over ``fov_deg`` centred on the mount's +x axis."""

    beams: int = param(360, doc="number of LiDAR beams", range=Range(1, 10_000))
    fov_deg: float = param(360.0, doc="LiDAR field of view, centred on the mount's forward axis",
                           unit="deg", range=Range(0.0, 360.0, lo_open=True))
    range_min_m: float = param(0.1, doc="LiDAR minimum range; closer returns read -inf",
                               unit="m", range=Range(0.0, 1000.0))
    range_max_m: float = param(10.0, doc="LiDAR maximum range; farther returns read +inf",
                               unit="m", range=Range(0.0, 1000.0, lo_open=True))
    noise_std_m: float = param(0.0, doc="standard deviation of the Gaussian noise on each range",
                               unit="m", range=Range(0.0, 10.0))
    dropout_prob: float = param(0.0, doc="probability that a beam is dropped (reads +inf)",
                                range=FRACTION)
    mount_xyz_m: tuple[float, float, float] = (0.0, 0.0, 0.3)
    mount_yaw_rad: float = 0.0

    def __post_init__(self) -> None:
        check(self, "lidar.")
        require(self.range_min_m < self.range_max_m, "lidar.range_max_m", self.range_max_m,
                f"more than range_min_m={self.range_min_m}")

    @property
    def angle_min_rad(self) -> float:
        return -0.5 * math.radians(self.fov_deg)

    @property
    def angle_increment_rad(self) -> float:
        """Angle between beams; a full circle does not repeat its first beam (rad)."""
        fov = math.radians(self.fov_deg)
        if self.fov_deg >= 360.0:
            return fov / self.beams
        return fov / max(self.beams - 1, 1)


class Lidar:
    """A planar LiDAR: all beams in one ``mj_multiRay`` call, skipping the robot's own body."""

    frame_id = "laser"

    def frames(self) -> list[tuple[str, tuple[float, float, float],
                                   tuple[float, float, float, float]]]:
        """Its frame on the base for ``tf_static``: at the mount, turned by its yaw."""
        return [(self.frame_id, self.spec.mount_xyz_m, yaw_to_quaternion(self.spec.mount_yaw_rad))]

    def __init__(self, model: mujoco.MjModel, spec: LidarSpec, *, exclude_body: int) -> None:
        import mujoco  # here, not above: see the module docstring

        self.spec = spec
        self._model = model
        self._multi_ray = mujoco.mj_multiRay
        self._exclude_body = exclude_body
        n = spec.beams
        angles = spec.angle_min_rad + np.arange(n) * spec.angle_increment_rad + spec.mount_yaw_rad
        self._dirs_xy = np.column_stack((np.cos(angles), np.sin(angles)))  # base frame
        self._pnt = np.zeros(3)
        self._vec = np.zeros((n, 3))  # z stays 0: horizontal beams
        self._vec_flat = self._vec.reshape(-1)
        self._vec_xy = self._vec[:, :2]
        self._rot = np.empty((2, 2))
        self._geomid = np.empty(n, dtype=np.int32)
        self._dist = np.empty(n)

    @property
    def angle_min_rad(self) -> float:
        return self.spec.angle_min_rad

    @property
    def angle_max_rad(self) -> float:
        """Angle of the last beam (rad), as ``LaserScan.angle_max`` wants it."""
        return self.spec.angle_min_rad + (self.spec.beams - 1) * self.spec.angle_increment_rad

    @property
    def angle_increment_rad(self) -> float:
        return self.spec.angle_increment_rad

    @property
    def range_min_m(self) -> float:
        return self.spec.range_min_m

    @property
    def range_max_m(self) -> float:
        return self.spec.range_max_m

    def read(self, data: mujoco.MjData, pose: Pose2D, rng: np.random.Generator) -> np.ndarray:
        """One scan (float32 m, one per beam) for the robot at ``pose``; geoms as of ``data``."""
        spec = self.spec
        c, s = math.cos(pose.yaw), math.sin(pose.yaw)
        _mount_point(pose, c, s, spec.mount_xyz_m, self._pnt)
        rot = self._rot  # row-vector rotation: [x y] @ rot = R(yaw) [x y]^T
        rot[0, 0], rot[0, 1], rot[1, 0], rot[1, 1] = c, s, -s, c
        np.matmul(self._dirs_xy, rot, out=self._vec_xy)
        self._multi_ray(self._model, data, self._pnt, self._vec_flat, None, 1,
                           self._exclude_body, self._geomid, self._dist, None, spec.beams,
                           spec.range_max_m)
        ranges = _to_rep117(self._dist, self._geomid >= 0, spec.range_min_m, spec.range_max_m,
                            spec.noise_std_m, rng)
        if spec.dropout_prob > 0:
            ranges[rng.random(spec.beams) < spec.dropout_prob] = np.inf
        return ranges


@dataclass(frozen=True)
class DepthCameraSpec:
    """A pinhole depth camera; pixels hold depth along the optical axis (m, 32FC1)."""

    width: int = param(80, doc="depth image width", unit="px", range=Range(1, 4096))
    height: int = param(60, doc="depth image height", unit="px", range=Range(1, 4096))
    hfov_deg: float = param(87.0, doc="depth camera horizontal field of view", unit="deg",
                            range=Range(0.0, 180.0, lo_open=True, hi_open=True))
    min_depth_m: float = param(0.1, doc="depth camera minimum depth; closer pixels read -inf",
                               unit="m", range=Range(0.0, 1000.0))
    max_depth_m: float = param(10.0, doc="depth camera maximum depth; farther pixels read +inf",
                               unit="m", range=Range(0.0, 1000.0, lo_open=True))
    noise_std_m: float = param(0.0, doc="standard deviation of the Gaussian noise on each pixel",
                               unit="m", range=Range(0.0, 10.0))
    mount_xyz_m: tuple[float, float, float] = (0.2, 0.0, 0.4)
    mount_pitch_rad: float = 0.0

    def __post_init__(self) -> None:
        check(self, "depth.")
        require(self.min_depth_m < self.max_depth_m, "depth.max_depth_m", self.max_depth_m,
                f"more than min_depth_m={self.min_depth_m}")

    @property
    def focal_px(self) -> float:
        """Focal length in pixels (square pixels)."""
        return 0.5 * self.width / math.tan(0.5 * math.radians(self.hfov_deg))


class DepthCamera:
    """A pinhole depth camera: one ray per pixel centre, depth along the optical axis."""

    frame_id = "camera_depth_optical_frame"

    def frames(self) -> list[tuple[str, tuple[float, float, float],
                                   tuple[float, float, float, float]]]:
        """Its frame on the base for ``tf_static``: at the mount, pitched down, optical."""
        return [(self.frame_id, self.spec.mount_xyz_m, optical(self.spec.mount_pitch_rad))]

    def __init__(self, model: mujoco.MjModel, spec: DepthCameraSpec, *,
                 exclude_body: int) -> None:
        import mujoco  # here, not above: see the module docstring

        self.spec = spec
        self._model = model
        self._multi_ray = mujoco.mj_multiRay
        self._exclude_body = exclude_body
        self.width, self.height = spec.width, spec.height
        f = spec.focal_px
        self._intrinsics = (f, f, 0.5 * spec.width, 0.5 * spec.height)
        u = (np.arange(spec.width) + 0.5 - 0.5 * spec.width) / f  # optical x: right
        v = (np.arange(spec.height) + 0.5 - 0.5 * spec.height) / f  # optical y: down
        xo, yo = np.meshgrid(u, v)  # (height, width), row-major like the image
        # Optical (right, down, forward) -> camera link (forward, left, up), then pitch down.
        fwd, left, up = np.ones_like(xo).ravel(), -xo.ravel(), -yo.ravel()
        cp, sp = math.cos(spec.mount_pitch_rad), math.sin(spec.mount_pitch_rad)
        dirs = np.column_stack((cp * fwd + sp * up, left, -sp * fwd + cp * up))
        norm = np.linalg.norm(dirs, axis=1)
        self._dirs_xy = dirs[:, :2] / norm[:, None]
        self._depth_per_m = 1.0 / norm  # cos of the angle between ray and optical axis
        self._n = spec.width * spec.height
        self._cutoff_m = spec.max_depth_m * float(norm.max())
        self._pnt = np.zeros(3)
        self._vec = np.empty((self._n, 3))
        self._vec[:, 2] = dirs[:, 2] / norm  # yaw does not change the vertical part
        self._vec_flat = self._vec.reshape(-1)
        self._vec_xy = self._vec[:, :2]
        self._rot = np.empty((2, 2))
        self._geomid = np.empty(self._n, dtype=np.int32)
        self._dist = np.empty(self._n)

    @property
    def intrinsics(self) -> tuple[float, float, float, float]:
        """``(fx, fy, cx, cy)`` in pixels."""
        return self._intrinsics

    @property
    def k_matrix(self) -> tuple[float, ...]:
        """``CameraInfo.k``: the 3×3 intrinsic matrix, row-major."""
        fx, fy, cx, cy = self._intrinsics
        return (fx, 0.0, cx, 0.0, fy, cy, 0.0, 0.0, 1.0)

    @property
    def p_matrix(self) -> tuple[float, ...]:
        """``CameraInfo.p``: the 3×4 projection matrix of a monocular camera, row-major."""
        fx, fy, cx, cy = self._intrinsics
        return (fx, 0.0, cx, 0.0, 0.0, fy, cy, 0.0, 0.0, 0.0, 1.0, 0.0)

    def read(self, data: mujoco.MjData, pose: Pose2D, rng: np.random.Generator) -> np.ndarray:
        """A depth image (float32 m, shape ``(height, width)``) for the robot at ``pose``."""
        spec = self.spec
        c, s = math.cos(pose.yaw), math.sin(pose.yaw)
        _mount_point(pose, c, s, spec.mount_xyz_m, self._pnt)
        rot = self._rot
        rot[0, 0], rot[0, 1], rot[1, 0], rot[1, 1] = c, s, -s, c
        np.matmul(self._dirs_xy, rot, out=self._vec_xy)
        self._multi_ray(self._model, data, self._pnt, self._vec_flat, None, 1,
                           self._exclude_body, self._geomid, self._dist, None, self._n,
                           self._cutoff_m)
        depth = self._dist * self._depth_per_m
        image = _to_rep117(depth, self._geomid >= 0, spec.min_depth_m, spec.max_depth_m,
                           spec.noise_std_m, rng)
        return image.reshape(spec.height, spec.width)
