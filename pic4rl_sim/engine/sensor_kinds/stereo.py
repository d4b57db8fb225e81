"""A stereo depth camera: two pinhole cameras ``baseline_m`` apart, depth from the disparity
between them. Published as a depth ``sensor_msgs/Image`` (32FC1, m) on
``stereo/depth/image_raw``, read by the bridge as ``stereo_depth``, and a
``stereo_msgs/DisparityImage`` on ``stereo/disparity``.

Model: the left camera's depth ``z`` per pixel by ray casting (``ray_sensors.DepthCamera``);
the disparity a sensor of ``sensor_width_px`` columns sees, ``d = f·B/z`` (``f`` its focal
length in pixels), with white noise of ``subpixel_px`` (the matcher's RMS sub-pixel error) and
quantised to ``disparity_step_px``; depth back from it, ``f·B/d``, so that its error grows as
``z²·subpixel/(f·B)``. Invalid: a disparity above the matcher's search range
``max_disparity_px`` (too close: ``-inf``), a depth beyond ``max_depth_m`` (``+inf``, REP 117),
and, ``NaN`` (REP 117: no valid measurement), a point the right camera does not see, hidden
behind a nearer surface (a second ray cast from the right camera: the bands left of occluding
edges in the image) or outside its image (the left image's left band). Defaults: Intel RealSense D435
(datasheet: 50 mm baseline, 87° × 58° depth field of view, 848 × 480 depth at its best,
126-disparity search range; Intel's depth-tuning white paper: depth RMS error =
z²·subpixel/(f·B) with subpixel 0.08), published decimated to 80 × 48. MuJoCo and numpy are
imported where they are used: the sim's interface table imports this module."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, NamedTuple

from pic4rl_base.errors import require
from pic4rl_base.schema import Range, check, param

from . import OPTICAL_XYZW, Instant

if TYPE_CHECKING:
    import numpy as np

NAME = "stereo"
#: A disparity pixel the matcher found no match for (``DisparityImage``: below its minimum).
INVALID_DISPARITY = -1.0


@dataclass(frozen=True)
class StereoCameraSpec:
    """A stereo depth camera at the mount, looking along the base's +x."""

    width: int = param(80, doc="stereo depth image width", unit="px", range=Range(1, 4096))
    height: int = param(48, doc="stereo depth image height", unit="px", range=Range(1, 4096))
    hfov_deg: float = param(87.0, doc="stereo camera horizontal field of view", unit="deg",
                            range=Range(0.0, 180.0, lo_open=True, hi_open=True))
    baseline_m: float = param(0.05, doc="distance between the two cameras", unit="m",
                              range=Range(0.0, 10.0, lo_open=True))
    sensor_width_px: int = param(848, doc="columns of the images the disparity is matched in "
                                 "(the depth image is decimated from them)", unit="px",
                                 range=Range(1, 10_000))
    subpixel_px: float = param(0.08, doc="RMS error of a matched disparity, in sensor pixels",
                               unit="px", range=Range(0.0, 10.0))
    disparity_step_px: float = param(0.03125, doc="quantum of a reported disparity, in sensor "
                                     "pixels", unit="px", range=Range(0.0, 1.0, lo_open=True))
    max_disparity_px: float = param(126.0, doc="the matcher's disparity search range; larger "
                                    "disparities (too close) read -inf", unit="px",
                                    range=Range(1.0, 10_000.0))
    max_depth_m: float = param(10.0, doc="stereo maximum depth; farther pixels read +inf",
                               unit="m", range=Range(0.0, 1000.0, lo_open=True))
    mount_xyz_m: tuple[float, float, float] = (0.2, 0.0, 0.4)

    def __post_init__(self) -> None:
        check(self, f"{NAME}.")
        require(self.sensor_width_px >= self.width, f"{NAME}.sensor_width_px",
                self.sensor_width_px, f"at least width={self.width}")

    @property
    def sensor_focal_px(self) -> float:
        """Focal length in sensor pixels: the ``f`` of ``d = f·B/z``."""
        return 0.5 * self.sensor_width_px / math.tan(0.5 * math.radians(self.hfov_deg))

    @property
    def scale(self) -> float:
        """Image pixels per sensor pixel."""
        return self.width / self.sensor_width_px

    @property
    def min_depth_m(self) -> float:
        """The nearest depth the search range matches."""
        return self.sensor_focal_px * self.baseline_m / self.max_disparity_px


class StereoReading(NamedTuple):
    """One instant: depth (m) and disparity (image pixels), float32, height × width."""

    depth: np.ndarray
    disparity: np.ndarray


class StereoCamera:
    """The camera pair on the engine's robot: the left camera's rays, then the right camera's
    rays to the points the left one sees; one draw per instant (``Instant``)."""

    frame_id = "stereo_left_optical_frame"

    def __init__(self, model: Any, spec: StereoCameraSpec, *, exclude_body: int) -> None:
        import mujoco  # here, not above: see the module docstring
        import numpy as np

        from ..ray_sensors import DepthCamera, DepthCameraSpec

        self.spec = spec
        self._left = DepthCamera(model, DepthCameraSpec(
            width=spec.width, height=spec.height, hfov_deg=spec.hfov_deg, min_depth_m=0.0,
            max_depth_m=2.0 * spec.max_depth_m, mount_xyz_m=spec.mount_xyz_m),
            exclude_body=exclude_body)
        self._model, self._multi_ray, self._exclude = model, mujoco.mj_multiRay, exclude_body
        f, _, cx, cy = self._left.intrinsics
        self.focal_px = f
        u = np.arange(spec.width) + 0.5
        xo, yo = np.meshgrid((u - cx) / f, (np.arange(spec.height) + 0.5 - cy) / f)
        self._rays = np.stack((np.ones_like(xo), -xo, -yo), axis=-1).reshape(-1, 3)  # base
        self._u = np.broadcast_to(u, (spec.height, spec.width))
        n = spec.width * spec.height
        self._geomid = np.empty(n, dtype=np.int32)
        self._dist = np.empty(n)
        self._instant = Instant()

    def frames(self) -> list[tuple[str, tuple[float, float, float],
                                   tuple[float, float, float, float]]]:
        """The left camera's optical frame on the base for ``tf_static``."""
        return [(self.frame_id, self.spec.mount_xyz_m, OPTICAL_XYZW)]

    def _hidden_from_right(self, data: Any, pose: Any, z: np.ndarray) -> np.ndarray:
        """Whether the right camera's view of each pixel's point is blocked by a nearer
        surface (pixels without a point: ``False``)."""
        import numpy as np

        spec = self.spec
        c, s = math.cos(pose.yaw), math.sin(pose.yaw)
        mx, my, mz = spec.mount_xyz_m
        rx, ry = mx, my - spec.baseline_m  # the right camera: the baseline to the right
        right = np.array([pose.x + c * rx - s * ry, pose.y + s * rx + c * ry, mz])
        # a pixel's point in the base frame, from the left camera, then in the world
        seen = np.isfinite(z.reshape(-1))
        pts = self._rays * np.where(seen, z.reshape(-1), 0.0)[:, None] + np.array([mx, my, mz])
        world = np.column_stack((pose.x + c * pts[:, 0] - s * pts[:, 1],
                                 pose.y + s * pts[:, 0] + c * pts[:, 1], pts[:, 2]))
        offsets = np.where(seen[:, None], world - right, [1.0, 0.0, 0.0])
        reach = np.linalg.norm(offsets, axis=1)
        self._multi_ray(self._model, data, right, (offsets / reach[:, None]).reshape(-1), None,
                        1, self._exclude, self._geomid, self._dist, None, len(reach),
                        float(reach.max()))
        blocked = (self._geomid >= 0) & (self._dist < reach - 1e-3 * (1.0 + reach))
        return (blocked & seen).reshape(z.shape)

    def read(self, data: Any, pose: Any, rng: np.random.Generator) -> StereoReading:
        """Depth and disparity images for the robot at ``pose`` (a ``Pose2D``)."""
        import numpy as np

        key = (pose.x, pose.y, pose.yaw, float(data.time))
        kept = self._instant.get(rng, key)
        if kept is not None:
            return kept  # type: ignore[return-value]
        spec = self.spec
        z = self._left.read(data, pose, rng).astype(np.float64)  # exact: the spec has no noise
        fb = spec.sensor_focal_px * spec.baseline_m
        with np.errstate(divide="ignore"):
            d = fb / z  # sensor pixels; 0 where nothing was hit
        if spec.subpixel_px > 0:
            d = d + spec.subpixel_px * rng.standard_normal(d.shape)
        d = spec.disparity_step_px * np.round(d / spec.disparity_step_px)
        with np.errstate(divide="ignore"):
            depth = np.where(d > 0, fb / np.where(d > 0, d, 1.0), np.inf)
        depth[depth > spec.max_depth_m] = np.inf
        depth[fb / z > spec.max_disparity_px] = -np.inf
        outside = self._u < d * spec.scale  # the right camera's image ends there
        depth[np.isfinite(depth) & (outside | self._hidden_from_right(data, pose, z))] = np.nan
        disparity = np.where(np.isfinite(depth), d * spec.scale, INVALID_DISPARITY)
        reading = StereoReading(depth.astype(np.float32), disparity.astype(np.float32))
        return self._instant.keep(rng, key, reading)  # type: ignore[return-value]


def build(model: Any, spec: StereoCameraSpec, body: int) -> StereoCamera:
    """``SENSOR_TABLE``'s build: the pair on the robot's body ``body``."""
    return StereoCamera(model, spec, exclude_body=body)


def read(camera: StereoCamera, engine: Any, rng: np.random.Generator) -> StereoReading:
    """``SENSOR_TABLE``'s read: the pair's images now."""
    return camera.read(engine.data, engine.robot_pose(), rng)


DEPTH_TOPIC = f"{NAME}/depth/image_raw"
DISPARITY_TOPIC = f"{NAME}/disparity"


class StereoMessages:
    """The sim node's step messages: the depth image and the disparity image (pixels written
    in place each step), on ``depth_topic`` and ``disparity_topic``."""

    def __init__(self, engine: Any, stamp: Any, depth_topic: Any, disparity_topic: Any) -> None:
        import array
        import sys

        import numpy as np
        from sensor_msgs.msg import Image
        from std_msgs.msg import Header
        from stereo_msgs.msg import DisparityImage

        cam: StereoCamera = engine.sensors[NAME]
        spec = cam.spec
        header = Header(stamp=stamp, frame_id=cam.frame_id)

        def image() -> Any:
            msg = Image(header=header, height=spec.height, width=spec.width, encoding="32FC1",
                        is_bigendian=int(sys.byteorder == "big"), step=4 * spec.width)
            msg.data = array.array("B", bytes(4 * spec.width * spec.height))
            return msg

        depth, disparity = image(), DisparityImage(
            header=header, image=image(), f=cam.focal_px, t=spec.baseline_m,
            min_disparity=cam.focal_px * spec.baseline_m / spec.max_depth_m,
            max_disparity=spec.max_disparity_px * spec.scale,
            delta_d=spec.disparity_step_px * spec.scale)
        disparity.valid_window.width, disparity.valid_window.height = spec.width, spec.height
        self._pixels = [np.frombuffer(m.data, dtype=np.float32).reshape(spec.height, spec.width)
                        for m in (depth, disparity.image)]
        self.held = {depth_topic: depth, disparity_topic: disparity}

    def fill(self, engine: Any) -> None:
        reading = engine.read(NAME)
        self._pixels[0][...] = reading.depth
        self._pixels[1][...] = reading.disparity


def read_depth(engine: Any, mount: Any) -> np.ndarray | None:
    """``READING_TABLE``'s in-process read of ``stereo_depth``: the instant's depth image
    (``None`` without a stereo camera)."""
    return engine.read(NAME).depth if NAME in engine.sensors else None
