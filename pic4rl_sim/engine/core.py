"""The simulation engine: one robot in one world, stepped one control period at a time.

No ROS here: the node, the bridge's in-process transport and the tests drive the same
``Engine``. Same robot, world, seed and commands give identical states and sensor data:
every random draw comes from per-purpose streams seeded from the episode seed.
"""

from __future__ import annotations

import logging
import math
from typing import Any, NamedTuple

import mujoco
import numpy as np

from pic4rl_base.errors import require
from pic4rl_base.geometry import Pose2D, wrap_angle
from pic4rl_base.goal import Goal

from ..errors import WorldError
from .crowd.crowd import Crowd
from .crowd.movers import Movers
from .engine_config import EngineConfig
from .geometry import Twist2D
from .model import build_model
from .paths import plan_path
from .robot_specs import Drive, RobotSpec
from .sampling import check_free, sample_start_goal
from .sensor_kinds import NAMES as KIND_NAMES
from .sensors import (KINDS_BY_NAME, OWN_KINDS, SENSOR_TABLE, DepthCamera, Imu, ImuReading, Lidar,
                      WheelOdometry)
from .worlds.spec import WorldSpec

log = logging.getLogger(__name__)

_DIVERGED_SPEED = 1e3  # m/s or rad/s: no robot gets near, a blown-up solver does
_BAD_STATE_WARNINGS = [int(mujoco.mjtWarning.mjWARN_BADQACC), int(mujoco.mjtWarning.mjWARN_BADQPOS),
                       int(mujoco.mjtWarning.mjWARN_BADQVEL)]
# Independent random streams per purpose: reading one sensor never shifts another's noise.
# The order is the order streams were added in (pic4rl's first sensors, the crowd, then
# ``sensor_kinds``'), and a user's sensors come last, so installing one leaves every
# stream of pic4rl's as it was.
_STREAMS = ("sampling", *(name for name in OWN_KINDS if name not in KIND_NAMES), "crowd",
            *KIND_NAMES, *(kind.name for kind in SENSOR_TABLE if kind.name not in OWN_KINDS))
_SAMPLING_ROUNDS = 200  # pairs drawn to find a partner for a given start or goal


class StepResult(NamedTuple):
    """What happened in one control period."""

    collided: bool  # the robot touches an obstacle at the period's end, or a mover during it
    diverged: bool  # the physics blew up; the episode was reset to its start
    reason: str = ""  # what diverged, when (empty otherwise)


class CommandCheck(NamedTuple):
    """A command made safe, and what was wrong with the one given (``None`` if nothing)."""

    command: Twist2D
    problem: str | None


def limit_command(command: Twist2D, robot: RobotSpec) -> CommandCheck:
    """Clamp ``command`` to the robot's limits; a non-finite command becomes a stop."""
    values = (command.vx, command.vy, command.wz)
    if not all(math.isfinite(v) for v in values):
        return CommandCheck(Twist2D(), f"non-finite command {tuple(values)!r} replaced by a stop")
    lateral = robot.max_lateral_m_s if robot.drive is Drive.OMNI else 0.0
    limits = (robot.max_linear_m_s, lateral, robot.max_angular_rad_s)
    clamped = Twist2D(*(min(max(v, -lim), lim) for v, lim in zip(values, limits)))
    if clamped == Twist2D(*values):
        return CommandCheck(clamped, None)
    return CommandCheck(clamped, f"command {tuple(values)!r} clamped to the limits {clamped!r}")


class Engine:
    """A robot in a world with its sensors. ``reset`` starts an episode, ``step`` runs one
    control period of ``config.substeps`` physics steps."""

    def __init__(self, robot: RobotSpec, world: WorldSpec, config: EngineConfig | None = None,
                 *, seed: int = 0) -> None:
        self.robot = robot
        self.world = world
        self.config = config or EngineConfig()
        self.model, self.ids = build_model(robot, world, physics_dt_s=self.config.physics_dt_s,
                                           crowd=self.config.crowd)
        #: The walking people (``config.crowd``), ``None`` without any.
        self.crowd = Crowd(self.config.crowd, world) if self.config.crowd.count else None
        #: The world's moving obstacles (``world.moving``: ``dynbarn``), ``None`` without any.
        self.movers = None if world.moving is None else Movers(world.moving, self.ids.mover_mocap)
        self.data = mujoco.MjData(self.model)
        body = self.ids.robot_body
        #: The robot's sensors by ``SENSOR_TABLE`` name (an optional one it lacks: absent).
        self.sensors: dict[str, Any] = {
            kind.name: kind.build(self.model, spec, body)
            for kind in SENSOR_TABLE if (spec := robot.sensors[kind.name]) is not None}
        self.lidar: Lidar | None = self.sensors.get("lidar")
        self.depth: DepthCamera | None = self.sensors.get("depth")
        self.imu: Imu = self.sensors["imu"]
        self.odometry: WheelOdometry = self.sensors["odometry"]
        self._odom: tuple[Pose2D, Twist2D] = (Pose2D(0, 0, 0), Twist2D())
        self._rng: dict[str, np.random.Generator] = {}
        self.seed = seed
        self.start = Pose2D(0.0, 0.0, 0.0)
        self.goal = Goal(0.0, 0.0)
        self.steps = 0
        self._plan: np.ndarray | None = None
        self.reset(seed=seed)

    # -- episodes ----------------------------------------------------------------------------

    def reset(self, *, seed: int | None = None, start: Pose2D | None = None,
              goal: Goal | None = None) -> None:
        """Start an episode: fresh random streams from ``seed`` (default: the last one), the
        robot at rest at ``start`` and the given ``goal``. Either is sampled with clearance
        when not given, at least ``min_goal_distance_m`` from the other; a given one is
        checked to be free. On an error the current episode is left untouched."""
        seed = self.seed if seed is None else int(seed)
        streams = np.random.SeedSequence(seed).spawn(len(_STREAMS))
        rng = {name: np.random.default_rng(s) for name, s in zip(_STREAMS, streams)}
        footprint = self.robot.footprint.bounding_radius_m
        if start is not None:
            check_free(self.world, (start.x, start.y), clearance_m=footprint, what="start_pose")
        if goal is not None:
            check_free(self.world, goal, clearance_m=0.0, what="goal")
        start, goal = self._sample_missing(start, goal, rng["sampling"])
        self.seed, self._rng = seed, rng
        self.start = Pose2D(float(start.x), float(start.y), wrap_angle(float(start.yaw)))
        self.goal = Goal.of(goal)
        self._plan = None
        self._restart()

    def plan(self) -> np.ndarray:
        """The episode's global plan (k × 2, m, world frame) from its start to its goal
        (``paths.plan_path`` with the footprint's circumscribed radius): computed on first
        use, then kept for the episode; empty when no path exists."""
        if self._plan is None:
            self._plan = plan_path(self.world, self.start[:2], self.goal,
                                   robot_radius_m=self.robot.footprint.bounding_radius_m)
        return self._plan

    def _sample_missing(self, start: Pose2D | None, goal: Goal | None,
                        rng: np.random.Generator) -> tuple[Pose2D, tuple[float, float]]:
        """``start`` and ``goal``, sampling whichever is ``None`` (far enough from the other)."""
        if start is not None and goal is not None:
            return start, goal
        clearance = self.robot.footprint.bounding_radius_m + self.config.clearance_m
        min_distance = self.config.min_goal_distance_m
        for _ in range(_SAMPLING_ROUNDS):
            s, g = sample_start_goal(self.world, rng, clearance_m=clearance,
                                     min_distance_m=min_distance)
            s = start if start is not None else s
            g = goal if goal is not None else g
            if math.hypot(g[0] - s.x, g[1] - s.y) >= min_distance:
                return s, g
        given = f"start {tuple(start)}" if start is not None else f"goal {goal}"
        msg = (f"world {self.world.name!r}: no free point {min_distance} m or more from the "
               f"{given} after {_SAMPLING_ROUNDS} rounds of sampling")
        raise WorldError(msg)

    def _restart(self) -> None:
        """Put the robot at rest at ``self.start`` with time 0 (also after a divergence)."""
        d, ids = self.data, self.ids
        mujoco.mj_resetData(self.model, d)
        d.qpos[[ids.qpos_x, ids.qpos_y, ids.qpos_yaw]] = self.start
        self._move_person()
        if self.crowd is not None:
            self.crowd.reset(self._rng["crowd"], self.start[:2],
                             self.robot.footprint.bounding_radius_m)
            d.mocap_pos[list(self.ids.crowd_mocap), :2] = self.crowd.pos
            self._turn_crowd()
        if self.movers is not None:
            self.movers.place(d, self.world.seed, self.seed)
        mujoco.mj_forward(self.model, d)
        self.odometry.reset(self.start)
        self._odom = (self.start, Twist2D())
        self.steps = 0

    # -- stepping ------------------------------------------------------------------------------

    def step(self, command: Twist2D) -> StepResult:
        """Track ``command`` (body frame, clamped to the limits) for one control period."""
        cmd = limit_command(command, self.robot).command
        m, d, ids = self.model, self.data, self.ids
        d.ctrl[ids.act_vx], d.ctrl[ids.act_vy], d.ctrl[ids.act_wz] = cmd
        before = self.robot_pose()
        warnings = d.warning.number[_BAD_STATE_WARNINGS].copy()
        walks = [w for w in (self._person_walk(), self._crowd_walk()) if w is not None]
        if self.movers is not None:
            walks.append(self.movers.walk(d, self.config.control_dt_s, self.config.substeps))
        touched = False
        if not walks:  # a static world: contact with it lasts while the servos push
            mujoco.mj_step(m, d, nstep=self.config.substeps)
        else:  # people and obstacles move smoothly; a bump that bounces the robot off counts
            for k in range(1, self.config.substeps + 1):
                for mocap, start, per_substep in walks:
                    d.mocap_pos[mocap] = start + per_substep * k
                mujoco.mj_step(m, d)
                touched = touched or (d.ncon > 0 and self.in_collision())
        if self._diverged(warnings):
            reason = (f"physics diverged at t={self.episode_time_s:.3f} s of the episode "
                      f"(seed {self.seed})")
            log.error("%s; episode reset to its start", reason)
            self._restart()
            return StepResult(collided=False, diverged=True, reason=reason)
        self.steps += 1
        self._odom = self.odometry.update(before, self.robot_pose(), self.config.control_dt_s,
                                          self._rng["odometry"])
        return StepResult(collided=touched or self.in_collision(), diverged=False)

    def _person_walk(self) -> tuple[Any, np.ndarray, np.ndarray] | None:
        """The person's mocap index, its position now and its change per substep over this
        control period; its heading is set for the period's end."""
        if self.world.person is None:
            return None
        t = self.episode_time_s
        now, _ = self.world.person.pose_at(t)
        end, _ = self.world.person.pose_at(t + self.config.control_dt_s)
        self.data.mocap_quat[self.ids.person_mocap] = (math.cos(end.yaw / 2), 0, 0,
                                                       math.sin(end.yaw / 2))
        start = np.array([now.x, now.y, 0.0])
        return (self.ids.person_mocap, start,
                (np.array([end.x, end.y, 0.0]) - start) / self.config.substeps)

    def _crowd_walk(self) -> tuple[Any, np.ndarray, np.ndarray] | None:
        """The crowd walked one control period ahead (the robot as it is now): the mocap
        indices, the positions now and their change per substep (straight lines within the
        period); headings are set for the period's end."""
        if self.crowd is None:
            return None
        mocap = list(self.ids.crowd_mocap)
        start = self.data.mocap_pos[mocap].copy()
        pose, v = self.robot_pose(), self.data.qvel
        self.crowd.advance(self.config.control_dt_s, (pose.x, pose.y),
                           (float(v[self.ids.dof_x]), float(v[self.ids.dof_y])),
                           self.robot.footprint.bounding_radius_m)
        self._turn_crowd()
        end = np.column_stack((self.crowd.pos, np.zeros(len(mocap))))
        return mocap, start, (end - start) / self.config.substeps

    def _turn_crowd(self) -> None:
        assert self.crowd is not None
        half = 0.5 * self.crowd.yaw
        self.data.mocap_quat[list(self.ids.crowd_mocap)] = np.column_stack(
            (np.cos(half), np.zeros_like(half), np.zeros_like(half), np.sin(half)))

    def _diverged(self, warnings_before: np.ndarray) -> bool:
        d = self.data
        if (d.warning.number[_BAD_STATE_WARNINGS] > warnings_before).any():
            return True  # MuJoCo reset the state itself: the episode is lost anyway
        speed = float(np.abs(d.qvel).max(initial=0.0))
        return not (speed < _DIVERGED_SPEED and math.isfinite(float(d.qpos.sum())))  # NaN fails

    def _move_person(self, t_s: float = 0.0) -> None:
        if self.ids.person_mocap < 0 or self.world.person is None:
            return
        pose, _ = self.world.person.pose_at(t_s)
        self.data.mocap_pos[self.ids.person_mocap] = (pose.x, pose.y, 0.0)
        self.data.mocap_quat[self.ids.person_mocap] = (math.cos(pose.yaw / 2), 0, 0,
                                                       math.sin(pose.yaw / 2))

    # -- readers -------------------------------------------------------------------------------

    @property
    def episode_time_s(self) -> float:
        """Simulated time since the episode's start (s)."""
        return float(self.data.time)

    def robot_pose(self) -> Pose2D:
        """Exact pose of the base in the world."""
        q, ids = self.data.qpos, self.ids
        yaw = wrap_angle(float(q[ids.qpos_yaw]))
        return Pose2D(float(q[ids.qpos_x]), float(q[ids.qpos_y]), yaw)

    def robot_twist(self) -> Twist2D:
        """Exact velocity of the base in its own frame."""
        v, ids = self.data.qvel, self.ids
        yaw = float(self.data.qpos[ids.qpos_yaw])
        c, s = math.cos(yaw), math.sin(yaw)
        vx, vy = float(v[ids.dof_x]), float(v[ids.dof_y])
        return Twist2D(c * vx + s * vy, -s * vx + c * vy, float(v[ids.dof_yaw]))

    def in_collision(self) -> bool:
        """Whether the robot's body touches anything now."""
        d = self.data
        if d.ncon == 0:
            return False
        geoms = d.contact.geom[: d.ncon]
        return bool((self.model.geom_bodyid[geoms] == self.ids.robot_body).any())

    def person_pose(self) -> tuple[Pose2D, tuple[float, float]] | None:
        """The person's pose and world velocity (m/s) now, or ``None`` without a person."""
        if self.world.person is None:
            return None
        return self.world.person.pose_at(self.episode_time_s)

    def people(self) -> tuple[np.ndarray, np.ndarray] | None:
        """The crowd's positions (n × 2, m) and headings (n, rad, along each person's
        velocity) now, in the crowd's order; ``None`` without a crowd."""
        if self.crowd is None:
            return None
        return self.data.mocap_pos[list(self.ids.crowd_mocap), :2].copy(), self.crowd.yaw.copy()

    def read(self, sensor: str) -> Any:
        """The robot's ``sensor`` (a ``SENSOR_TABLE`` name) read now, with its own noise
        stream (its kind's ``read``); error if the robot has none."""
        require(sensor in self.sensors, f"robot.{sensor}", None, f"a {sensor} on the robot")
        read = KINDS_BY_NAME[sensor].read
        return read(self.sensors[sensor], self, self._rng[sensor])  # type: ignore[misc]

    def scan(self) -> np.ndarray:
        """LiDAR ranges now (REP 117: ``inf`` beyond range); error if the robot has none."""
        require(self.lidar is not None, "robot.lidar", None, "a LiDAR on the robot to read a scan")
        return self.read("lidar")

    def depth_image(self) -> np.ndarray:
        """Depth image now (m along the optical axis, float32, height × width)."""
        require(self.depth is not None, "robot.depth", None, "a depth camera on the robot")
        return self.read("depth")

    def imu_reading(self) -> ImuReading:
        """IMU now: orientation, yaw rate, body-frame acceleration including gravity."""
        return self.read("imu")

    def wheel_odometry(self) -> tuple[Pose2D, Twist2D]:
        """Wheel odometry: a pose that starts at the true start and drifts, and the body twist."""
        return self._odom
