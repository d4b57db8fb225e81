"""UWB ranging: a tag on the robot ranging to anchors fixed in the world (for localisation)
and, with ``goal_tag``, to a tag at the episode's goal (relative goal sensing). Each range is
one ``sensor_msgs/Range`` on ``uwb/<anchor>`` (anchors ``a0``…``a3``, the goal's tag
``goal``), read by the bridge as ``uwb_<anchor>``; the anchors' positions are published
latched on ``uwb/anchors`` at each episode. With ``anchors_on_robot`` the anchors ride on the
robot instead and each ranges to the goal's tag (``uwb/a<i>``), as a person-following robot's
anchors range to the person's tag: the range and bearing of the goal from ranges alone.

Model, a two-way-ranging radio (Decawave DWM1000 class): the true 3-D distance between the
tag's antenna and the anchor's, plus white noise ``noise_std_m``; when the line of sight is
blocked (a ray cast from tag to anchor by ``mj_multiRay`` hits anything first, walls, boxes
and people alike, the robot itself skipped) a positive bias drawn from an exponential
distribution of mean ``nlos_bias_m`` (the first path arrives late through or around the
obstacle; anchors on the robot, blocked at one instant, share one draw); each range is lost with probability ``dropout_prob`` and beyond ``range_max_m``
(``+inf``, REP 117). MuJoCo and numpy are imported where they are used: the sim's interface
table imports this module and loads neither."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from pic4rl_base.errors import require
from pic4rl_base.schema import FRACTION, Range, check, param

from . import Instant

if TYPE_CHECKING:
    import numpy as np

NAME = "uwb"
#: The most anchors fixed in the world: one topic each in the sim's interface table.
MAX_ANCHORS = 4
#: The goal's tag's name, beside the anchors' ``a<i>``.
GOAL_TAG = "goal"
#: Every name a range may have, in a reading's order.
TARGETS = (*(f"a{i}" for i in range(MAX_ANCHORS)), GOAL_TAG)


@dataclass(frozen=True)
class UwbSpec:
    """A UWB tag on the robot, the world's anchors and the goal's tag it ranges to."""

    anchors_xy_m: tuple[float, ...] = param(
        (), doc="UWB anchors fixed in the world, [x0, y0, x1, y1, ...] (at most 4, named a0, "
        "a1, ...); empty: none", unit="m")
    anchor_height_m: float = param(2.0, doc="height of the UWB anchors", unit="m",
                                   range=Range(0.0, 100.0))
    anchors_on_robot: bool = param(False, doc="the anchors of uwb.anchors_xy_m are mounted on "
                                   "the robot ([x, y] in its base frame) and range to the goal's "
                                   "tag (relative goal sensing); false: fixed in the world, "
                                   "ranging to the robot's tag")
    goal_tag: bool = param(True, doc="whether a UWB tag at the episode's goal is ranged "
                           "(uwb/goal)")
    goal_tag_height_m: float = param(1.0, doc="height of the goal's UWB tag", unit="m",
                                     range=Range(0.0, 100.0))
    noise_std_m: float = param(0.1, doc="standard deviation of the white noise on a UWB "
                               "range", unit="m", range=Range(0.0, 10.0))
    nlos_bias_m: float = param(0.3, doc="mean of the positive error (exponential) on a UWB "
                               "range whose line of sight is blocked", unit="m",
                               range=Range(0.0, 100.0))
    dropout_prob: float = param(0.0, doc="probability that a UWB range is lost (reads +inf)",
                                range=FRACTION)
    range_max_m: float = param(50.0, doc="UWB maximum range; farther reads +inf", unit="m",
                               range=Range(0.0, 1000.0, lo_open=True))
    mount_xyz_m: tuple[float, float, float] = (0.0, 0.0, 0.4)

    def __post_init__(self) -> None:
        check(self, f"{NAME}.")
        xy = self.anchors_xy_m
        require(len(xy) % 2 == 0 and len(xy) <= 2 * MAX_ANCHORS
                and all(math.isfinite(v) for v in xy), f"{NAME}.anchors_xy_m", list(xy),
                f"[x0, y0, ...]: pairs of finite numbers, at most {MAX_ANCHORS} anchors")
        require(bool(xy) or self.goal_tag, f"{NAME}.goal_tag", self.goal_tag,
                "true when uwb.anchors_xy_m is empty (a UWB tag ranges to something)")
        require(bool(xy) or not self.anchors_on_robot, f"{NAME}.anchors_on_robot",
                self.anchors_on_robot, "false when uwb.anchors_xy_m is empty (no anchors)")

    @property
    def anchors(self) -> tuple[tuple[float, float, float], ...]:
        """The anchors, (x, y, z) m, in name order: in the world, or in the robot's base
        frame with ``anchors_on_robot``."""
        xy = self.anchors_xy_m
        return tuple((xy[i], xy[i + 1], self.anchor_height_m) for i in range(0, len(xy), 2))

    @property
    def targets(self) -> tuple[str, ...]:
        """The names of the ranges a reading holds, in its order."""
        return TARGETS[:len(self.anchors)] + ((GOAL_TAG,) if self.goal_tag else ())


class UwbTag:
    """The tag on the engine's robot: its ranges to every target in one ``mj_multiRay`` call
    (one ray per target, cut at the farthest), the robot's own body skipped; the messages
    and readings of an instant share one draw (``Instant``)."""

    frame_id = "uwb_tag"

    def __init__(self, model: Any, spec: UwbSpec, *, exclude_body: int) -> None:
        import mujoco  # here, not above: see the module docstring
        import numpy as np

        self.spec = spec
        self._model, self._multi_ray, self._exclude = model, mujoco.mj_multiRay, exclude_body
        self._anchors = np.array(spec.anchors, dtype=float).reshape(-1, 3)
        n = len(spec.targets)
        self._geomid = np.empty(n, dtype=np.int32)
        self._dist = np.empty(n)
        self._instant = Instant()

    def frames(self) -> list[tuple[str, tuple[float, float, float],
                                   tuple[float, float, float, float]]]:
        """The tag's frame on the base for ``tf_static``: at the mount, unturned."""
        return [(self.frame_id, self.spec.mount_xyz_m, (0.0, 0.0, 0.0, 1.0))]

    def read(self, data: Any, pose: Any, goal: tuple[float, float],
             rng: np.random.Generator) -> np.ndarray:
        """The ranges (float32 m, ``spec.targets``' order) from the robot at ``pose`` (a
        ``Pose2D``) with the episode's ``goal`` (x, y)."""
        import numpy as np

        key = (pose.x, pose.y, pose.yaw, float(data.time), float(goal[0]), float(goal[1]))
        kept = self._instant.get(rng, key)
        if kept is not None:
            return kept  # type: ignore[return-value]
        spec = self.spec
        c, s = math.cos(pose.yaw), math.sin(pose.yaw)
        mx, my, mz = spec.mount_xyz_m
        tag = np.array([pose.x + c * mx - s * my, pose.y + s * mx + c * my, mz])
        goal_tag = np.array([goal[0], goal[1], spec.goal_tag_height_m])
        points = self._anchors
        if spec.anchors_on_robot:  # each anchor on the robot ranges to the goal's tag
            points = np.column_stack((pose.x + c * points[:, 0] - s * points[:, 1],
                                      pose.y + s * points[:, 0] + c * points[:, 1], points[:, 2]))
        if spec.goal_tag:
            points = np.vstack((points, goal_tag))
        # the rays leave the one point every range shares: the robot's tag, or the goal's tag
        # when the robot's anchors range to it (then the robot's tag is a target too)
        origin = goal_tag if spec.anchors_on_robot else tag
        if spec.anchors_on_robot and spec.goal_tag:
            points[-1] = tag
        offsets = points - origin
        true = np.linalg.norm(offsets, axis=1)
        dirs = offsets / np.maximum(true, 1e-12)[:, None]
        self._multi_ray(self._model, data, origin, dirs.reshape(-1), None, 1, self._exclude,
                        self._geomid, self._dist, None, len(true), float(true.max()))
        blocked = (self._geomid >= 0) & (self._dist < true)
        ranges = true.copy()
        if spec.noise_std_m > 0:
            ranges += spec.noise_std_m * rng.standard_normal(len(true))
        if spec.nlos_bias_m > 0 and blocked.any():
            # anchors on one robot see the tag through the same obstacle: one late path, one
            # draw for all of them; anchors across a room, one each
            draws = 1 if spec.anchors_on_robot else int(blocked.sum())
            ranges[blocked] += rng.exponential(spec.nlos_bias_m, draws)
        np.maximum(ranges, 0.0, out=ranges)
        if spec.dropout_prob > 0:
            ranges[rng.random(len(true)) < spec.dropout_prob] = np.inf
        ranges[ranges > spec.range_max_m] = np.inf
        return self._instant.keep(rng, key, ranges.astype(np.float32))  # type: ignore[return-value]


def build(model: Any, spec: UwbSpec, body: int) -> UwbTag:
    """``SENSOR_TABLE``'s build: the tag on the robot's body ``body``."""
    return UwbTag(model, spec, exclude_body=body)


def read(tag: UwbTag, engine: Any, rng: np.random.Generator) -> np.ndarray:
    """``SENSOR_TABLE``'s read: the tag's ranges now."""
    return tag.read(engine.data, engine.robot_pose(), (engine.goal[0], engine.goal[1]), rng)


def topic_name(target: str) -> str:
    """The topic of the range to ``target`` (an anchor's name or ``GOAL_TAG``)."""
    return f"{NAME}/{target}"


#: The anchors' positions' topic (latched, once an episode).
ANCHORS_TOPIC = f"{NAME}/anchors"


class RangeMessages:
    """The sim node's step messages: one ``Range`` per target, on ``topics`` (target name →
    its interface), refilled each step. ``Range`` has no UWB radiation type: it says
    ``INFRARED`` (a radio's), with an omnidirectional field of view."""

    def __init__(self, engine: Any, stamp: Any, topics: dict[str, Any]) -> None:
        from sensor_msgs.msg import Range as RangeMsg
        from std_msgs.msg import Header

        tag: UwbTag = engine.sensors[NAME]
        header = Header(stamp=stamp, frame_id=tag.frame_id)
        self._msgs = [RangeMsg(header=header, radiation_type=RangeMsg.INFRARED,
                               field_of_view=2 * math.pi, min_range=0.0,
                               max_range=tag.spec.range_max_m) for _ in tag.spec.targets]
        self.held = {topics[t]: msg for t, msg in zip(tag.spec.targets, self._msgs)}

    def fill(self, engine: Any) -> None:
        for msg, value in zip(self._msgs, engine.read(NAME)):
            msg.range = float(value)


def anchors_message(engine: Any, header: Any) -> Any:
    """The anchors' positions as a ``geometry_msgs/PoseArray`` in ``header``'s (the world)
    frame, or in ``base_link`` with ``anchors_on_robot``, in name order; ``None`` without a
    tag ranging to anchors."""
    from geometry_msgs.msg import Pose, PoseArray
    from std_msgs.msg import Header

    tag = engine.sensors.get(NAME)
    if tag is None or not tag.spec.anchors:
        return None
    if tag.spec.anchors_on_robot:
        header = Header(stamp=header.stamp, frame_id="base_link")
    poses = []
    for x, y, z in tag.spec.anchors:
        pose = Pose()
        pose.position.x, pose.position.y, pose.position.z = float(x), float(y), float(z)
        poses.append(pose)
    return PoseArray(header=header, poses=poses)


def reading_name(target: str) -> str:
    """The bridge's reading (and ``topics.<name>`` key) of the range to ``target``."""
    return f"{NAME}_{target}"


def decode(msg: Any, mount: Any, topic: str) -> float:
    """``READING_TABLE``'s decode: a range (m), as its message holds it."""
    return float(msg.range)


def target_reader(target: str) -> Any:
    """``READING_TABLE``'s in-process read of the range to ``target`` (``None`` when the robot
    has no tag or its tag does not range to it): the instant's reading, a float32 as
    published."""

    def read_target(engine: Any, mount: Any) -> float | None:
        tag = engine.sensors.get(NAME)
        if tag is None or target not in tag.spec.targets:
            return None
        return float(engine.read(NAME)[tag.spec.targets.index(target)])

    return read_target
