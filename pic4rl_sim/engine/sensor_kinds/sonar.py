"""A sonar ring: ``count`` ultrasonic cones spread evenly over ``fov_deg`` around the base, each
published as one ``sensor_msgs/Range`` on ``sonar/cone<i>`` and read by the bridge as
``sonar_<i>``.

Model: a cone of full angle ``cone_deg`` reads the nearest surface any of its rays hits (a
sonar's first echo), cast by ``mj_multiRay`` on a grid of directions inside the cone; white
noise on a hit; the floor (a plane) returns no echo (a smooth floor reflects the pulse
away); nothing within ``range_max_m`` reads ``+inf``, closer than ``range_min_m``
``-inf`` (REP 117, as the LiDAR). Defaults after a Pioneer-class ring of Polaroid 6500
transducers (8 per array; 0.15 m minimum range, about 1 % accuracy); the 5 m maximum and the
30° cone are this module's choice (docs/sim.md says why). MuJoCo and numpy are imported where
they are used, not with the module: the sim's interface table imports it and loads neither."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from pic4rl_base.errors import require
from pic4rl_base.schema import FRACTION, Range, check, param

from . import Instant

if TYPE_CHECKING:
    import numpy as np

NAME = "sonar"
#: The ring's most cones: one topic each in the sim's interface table.
MAX_CONES = 8
_RAYS_ACROSS = 7  # a cone's rays: a 7 × 7 grid of directions, those inside the cone


@dataclass(frozen=True)
class SonarSpec:
    """A ring of ``count`` sonar cones, the first on the base's +x axis."""

    count: int = param(8, doc="number of sonar cones in the ring", range=Range(1, MAX_CONES))
    fov_deg: float = param(360.0, doc="arc the cones' axes spread over, centred on +x (360: "
                           "a full ring)", unit="deg", range=Range(0.0, 360.0))
    cone_deg: float = param(30.0, doc="a sonar cone's full angle", unit="deg",
                            range=Range(0.0, 120.0, lo_open=True))
    range_min_m: float = param(0.15, doc="sonar minimum range; closer echoes read -inf",
                               unit="m", range=Range(0.0, 100.0))
    range_max_m: float = param(5.0, doc="sonar maximum range; no echo within it reads +inf",
                               unit="m", range=Range(0.0, 100.0, lo_open=True))
    noise_std_m: float = param(0.01, doc="standard deviation of the white noise on a sonar "
                               "range", unit="m", range=Range(0.0, 10.0))
    dropout_prob: float = param(0.0, doc="probability that a cone misses its echo (reads +inf)",
                                range=FRACTION)
    mount_xyz_m: tuple[float, float, float] = (0.0, 0.0, 0.2)

    def __post_init__(self) -> None:
        check(self, f"{NAME}.")
        require(self.range_min_m < self.range_max_m, f"{NAME}.range_max_m", self.range_max_m,
                f"more than range_min_m={self.range_min_m}")

    def cone_yaws_rad(self) -> np.ndarray:
        """Each cone's axis in the base frame (rad): evenly over ``fov_deg``, a full ring not
        repeating its first."""
        import numpy as np

        fov = math.radians(self.fov_deg)
        step = fov / self.count if self.fov_deg >= 360.0 else fov / max(self.count - 1, 1)
        start = 0.0 if self.fov_deg >= 360.0 or self.count == 1 else -0.5 * fov
        return start + step * np.arange(self.count)


def _cone_directions(half_angle: float) -> np.ndarray:
    """Unit directions inside a cone about +x (k × 3): its axis and a grid of tangents."""
    import numpy as np

    t = math.tan(half_angle) * np.linspace(-1.0, 1.0, _RAYS_ACROSS)
    ty, tz = np.meshgrid(t, t)
    inside = ty**2 + tz**2 <= math.tan(half_angle) ** 2 + 1e-12
    dirs = np.column_stack((np.ones(inside.sum()), ty[inside], tz[inside]))
    return dirs / np.linalg.norm(dirs, axis=1, keepdims=True)


class SonarRing:
    """The ring on the engine's robot: every cone's rays in one ``mj_multiRay`` call, the
    robot's own body skipped; its cones' messages and readings of an instant share one draw
    (``Instant``)."""

    frame_prefix = "sonar_"

    def __init__(self, model: Any, spec: SonarSpec, *, exclude_body: int) -> None:
        import mujoco  # here, not above: see the module docstring
        import numpy as np

        self.spec = spec
        self._model, self._multi_ray, self._exclude = model, mujoco.mj_multiRay, exclude_body
        self._echoes = np.asarray(model.geom_type) != mujoco.mjtGeom.mjGEOM_PLANE  # by geom id
        cone = _cone_directions(0.5 * math.radians(spec.cone_deg))
        self._per_cone = len(cone)
        yaws = spec.cone_yaws_rad()
        c, s = np.cos(yaws)[:, None], np.sin(yaws)[:, None]
        self._dirs = np.stack((c * cone[:, 0] - s * cone[:, 1], s * cone[:, 0] + c * cone[:, 1],
                               np.broadcast_to(cone[:, 2], c.shape[:1] + cone[:, 2].shape)),
                              axis=-1).reshape(-1, 3)  # base frame, cone-major
        self._n = len(self._dirs)
        self._vec = np.empty((self._n, 3))
        self._geomid = np.empty(self._n, dtype=np.int32)
        self._dist = np.empty(self._n)
        self._instant = Instant()

    @property
    def rays_per_cone(self) -> int:
        return self._per_cone

    def frames(self) -> list[tuple[str, tuple[float, float, float],
                                   tuple[float, float, float, float]]]:
        """Each cone's frame on the base for ``tf_static``: at the mount, +x along its axis."""
        from pic4rl_base.geometry import yaw_to_quaternion

        return [(f"{self.frame_prefix}{i}", self.spec.mount_xyz_m, yaw_to_quaternion(float(yaw)))
                for i, yaw in enumerate(self.spec.cone_yaws_rad())]

    def read(self, data: Any, pose: Any, rng: np.random.Generator) -> np.ndarray:
        """The cones' ranges (float32 m, REP 117) for the robot at ``pose`` (``Pose2D``)."""
        import numpy as np

        key = (pose.x, pose.y, pose.yaw, float(data.time))
        kept = self._instant.get(rng, key)
        if kept is not None:
            return kept  # type: ignore[return-value]
        spec = self.spec
        c, s = math.cos(pose.yaw), math.sin(pose.yaw)
        mx, my, mz = spec.mount_xyz_m
        pnt = np.array([pose.x + c * mx - s * my, pose.y + s * mx + c * my, mz])
        d = self._dirs
        self._vec[:, 0] = c * d[:, 0] - s * d[:, 1]
        self._vec[:, 1] = s * d[:, 0] + c * d[:, 1]
        self._vec[:, 2] = d[:, 2]
        self._multi_ray(self._model, data, pnt, self._vec.reshape(-1), None, 1, self._exclude,
                        self._geomid, self._dist, None, self._n, spec.range_max_m)
        hit = self._geomid >= 0
        hit[hit] = self._echoes[self._geomid[hit]]
        dist = np.where(hit, self._dist, np.inf).reshape(spec.count, -1)
        ranges = dist.min(axis=1)
        too_close = ranges < spec.range_min_m
        if spec.noise_std_m > 0:
            ranges = ranges + spec.noise_std_m * rng.standard_normal(spec.count)
        if spec.dropout_prob > 0:
            ranges[rng.random(spec.count) < spec.dropout_prob] = np.inf
        ranges[ranges > spec.range_max_m] = np.inf
        ranges[too_close | (ranges < spec.range_min_m)] = -np.inf
        return self._instant.keep(rng, key, ranges.astype(np.float32))  # type: ignore[return-value]


def build(model: Any, spec: SonarSpec, body: int) -> SonarRing:
    """``SENSOR_TABLE``'s build: the ring on the robot's body ``body``."""
    return SonarRing(model, spec, exclude_body=body)


def read(ring: SonarRing, engine: Any, rng: np.random.Generator) -> np.ndarray:
    """``SENSOR_TABLE``'s read: the ring's ranges now."""
    return ring.read(engine.data, engine.robot_pose(), rng)


def topic_name(cone: int) -> str:
    """Cone ``cone``'s topic (``INTERFACE_TABLE`` holds one per cone up to ``MAX_CONES``)."""
    return f"{NAME}/cone{cone}"


class RangeMessages:
    """The sim node's step messages: one ``Range`` per cone, on ``topics`` (the ring's
    interfaces in cone order), refilled each step."""

    def __init__(self, engine: Any, stamp: Any, topics: tuple[Any, ...]) -> None:
        from sensor_msgs.msg import Range as RangeMsg
        from std_msgs.msg import Header

        ring: SonarRing = engine.sensors[NAME]
        spec = ring.spec
        self._msgs = [RangeMsg(header=Header(stamp=stamp, frame_id=f"{ring.frame_prefix}{i}"),
                               radiation_type=RangeMsg.ULTRASOUND,
                               field_of_view=math.radians(spec.cone_deg),
                               min_range=spec.range_min_m, max_range=spec.range_max_m)
                      for i in range(spec.count)]
        self.held = dict(zip(topics, self._msgs))

    def fill(self, engine: Any) -> None:
        for msg, value in zip(self._msgs, engine.read(NAME)):
            msg.range = float(value)


def reading_name(cone: int) -> str:
    """Cone ``cone``'s reading in the bridge's frame (and its ``topics.<name>`` key)."""
    return f"{NAME}_{cone}"


def decode(msg: Any, mount: Any, topic: str) -> float:
    """``READING_TABLE``'s decode: a cone's range (m), as its message holds it."""
    return float(msg.range)


def cone_reader(cone: int) -> Any:
    """``READING_TABLE``'s in-process read of cone ``cone`` (``None`` when the robot has no
    ring or a shorter one): the ring's reading of the instant, as a float32 as published."""

    def read_cone(engine: Any, mount: Any) -> float | None:
        ring = engine.sensors.get(NAME)
        if ring is None or cone >= ring.spec.count:
            return None
        return float(engine.read(NAME)[cone])

    return read_cone
