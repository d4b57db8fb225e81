"""The Dynamic Window Approach (Fox, Burgard, Thrun 1997): the ``dwa`` baseline, the local
planner that nav2 and the BARN challenge compare learned planners with, and the velocity
layer of the person follower's hybrids (``follow``). Pure numpy over the env's decoded frame.
"""

from __future__ import annotations

import math

import numpy as np

from pic4rl_base.geometry import wrap_angle

from ..control.actions import normalized_action
from ..errors import ConfigError
from ..perception.collision import sensed_points
from ..readings.frame import SensorFrame
from ..robot_info import RobotInfo
from ..settings.baselines import DwaConfig

_LANES = 72  # directions (5° apart) checked for a free lane toward the goal


class DwaController:
    """The Dynamic Window Approach over the scan's points, for goToPose.

    Each step: the window is every (v, ω) reachable from the last command within one control
    period at the robot's acceleration limits, inside its velocity ranges; ``linear_samples``
    × ``angular_samples`` of it are simulated as constant-velocity arcs for ``horizon_s``, a
    pose every ``rollout_dt_s``. A pose collides when a sensed point (the env's: the scan
    through the LiDAR's mount) lies closer than ``collision_tolerance_m`` +
    ``safety_margin_m`` to the footprint (the env's signed distance). A sample is admissible
    when its first collision comes later than stopping from it takes (at the acceleration
    limits) plus one control period: Fox et al.'s admissible velocities. Admissible samples
    score ``heading_weight`` × (1 - |bearing of the target| / π, seen from the rollout's pose
    nearest it) + ``clearance_weight`` × (the distance driven before the first collision,
    ``clearance_cap_m`` when none: Fox et al.'s dist) + ``speed_weight`` × v / max_linear,
    each term divided by its largest value over the admissible samples. With none
    admissible, the sample whose rollout keeps the most clearance is taken.

    The target is the goal while a lane as wide as the footprint plus the collision distance
    is free toward it for ``lookahead_m`` (or up to it); else a point ``lookahead_m`` along
    the free lane nearest the goal's bearing, on the side chosen before (a scan-based subgoal,
    as gap-based planners pick, without which plain DWA stalls facing any wall between it and
    the goal). No map and no memory beyond that side: a mapless opponent, like the agents.
    """

    def __init__(self, robot: RobotInfo, config: DwaConfig | None = None, *,
                 collision_tolerance_m: float = 0.05) -> None:
        accel = (robot.max_linear_accel_m_s2, robot.max_angular_accel_rad_s2)
        if not all(math.isfinite(a) and a > 0 for a in accel):
            raise ConfigError(f"--baseline dwa: robot {robot.name!r} has no acceleration limits "
                              f"{accel}; the dynamic window needs max_linear_accel_m_s2 and "
                              "max_angular_accel_rad_s2 (robot YAML)")
        self.robot = robot
        self.config = c = config or DwaConfig()
        self.collision_m = collision_tolerance_m + c.safety_margin_m
        steps = max(1, round(c.horizon_s / c.rollout_dt_s))
        self._times = c.rollout_dt_s * np.arange(1, steps + 1)  # (K,) s
        # Only points a rollout pose can bring within the collision distance matter.
        self._reach_m = (max(robot.max_linear_m_s, -robot.min_linear_m_s) * c.horizon_s
                         + robot.footprint.bounding_radius_m + self.collision_m)
        self._last: tuple[float, float] | None = None
        self._side = 0.0  # +1: the last detour turned left of the goal, -1: right, 0: none
        self._lane_step = 2.0 * math.pi / _LANES
        self._lanes = self._lane_step * np.arange(_LANES)  # directions (rad, base frame)
        fp = robot.footprint
        half = fp.radius_m if fp.radius_m is not None else 0.5 * fp.width_m
        self._lane_half_m = half + self.collision_m

    def reset(self) -> None:
        """Forget the last command (the next window is centred on the measured twist) and the
        side of the last detour."""
        self._last = None
        self._side = 0.0

    def window(self, v: float, w: float) -> tuple[np.ndarray, np.ndarray]:
        """The sampled forward speeds (m/s) and yaw rates (rad/s) reachable from (v, ω)."""
        r, c, dt = self.robot, self.config, self.robot.control_dt_s
        dv, dw = r.max_linear_accel_m_s2 * dt, r.max_angular_accel_rad_s2 * dt
        v = min(max(v, r.min_linear_m_s), r.max_linear_m_s)
        w = min(max(w, -r.max_angular_rad_s), r.max_angular_rad_s)
        vs = np.linspace(max(v - dv, r.min_linear_m_s), min(v + dv, r.max_linear_m_s),
                         c.linear_samples)
        ws = np.linspace(max(w - dw, -r.max_angular_rad_s), min(w + dw, r.max_angular_rad_s),
                         c.angular_samples)
        return vs, ws

    def command(self, frame: SensorFrame) -> tuple[float, float]:
        """The chosen (v, ω) (m/s, rad/s) for ``frame``; remembered as the window's centre."""
        if frame.goal is None:
            raise ValueError("DwaController: the frame has no goal")
        current = self._last if self._last is not None else (frame.twist.vx, frame.twist.wz)
        vs, ws = self.window(*current)
        v, w = np.meshgrid(vs, ws, indexing="ij")
        v, w = v.ravel(), w.ravel()  # (S,)
        x, y, yaw = self._rollout(v, w)  # (S, K) each, in the base frame now
        points = sensed_points(frame, self.robot)
        px, py = self._near_points(points)
        clearance = self._clearance(px, py, x, y, yaw)
        colliding = clearance < self.collision_m
        hit = colliding.any(axis=1)
        first = np.where(hit, self._times[colliding.argmax(axis=1)], np.inf)
        dt = self.robot.control_dt_s
        stop_s = np.maximum(np.abs(v) / self.robot.max_linear_accel_m_s2,
                            np.abs(w) / self.robot.max_angular_accel_rad_s2) + dt
        admissible = first > stop_s
        if admissible.any():
            free_m = np.where(hit, np.abs(v) * np.where(hit, first, 0.0),
                              self.config.clearance_cap_m)
            target = self._target(frame, points)
            scores = self._scores(target, v, x, y, yaw, free_m, admissible)
            best = int(np.argmax(np.where(admissible, scores, -np.inf)))
        else:
            best = int(np.argmax(clearance.min(axis=1)))
        self._last = (float(v[best]), float(w[best]))
        return self._last

    def action(self, frame: SensorFrame) -> np.ndarray:
        return normalized_action(self.robot, *self.command(frame))

    def _rollout(self, v: np.ndarray, w: np.ndarray) -> tuple[np.ndarray, ...]:
        """Poses (S, K) of constant-velocity arcs from the origin at ``self._times``: exact,
        and finite at ω = 0 (x = v t sinc(ωt), y = v t (ωt/2) sinc²(ωt/2))."""
        yaw = w[:, None] * self._times[None, :]
        vt = v[:, None] * self._times[None, :]
        x = vt * np.sinc(yaw / np.pi)
        y = vt * 0.5 * yaw * np.sinc(yaw / (2.0 * np.pi)) ** 2
        return x, y, yaw

    def _near_points(self, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The sensed points a rollout can come within the collision distance of (float32 x,
        y in the base frame), one per cell of a ``point_resolution_m`` grid: walls seen at 1°
        steps need no more."""
        near = points[np.hypot(points[:, 0], points[:, 1]) < self._reach_m]
        _, first = np.unique(np.floor(near / self.config.point_resolution_m), axis=0,
                             return_index=True)
        px, py = near[first].T.astype(np.float32)
        return px, py

    def _clearance(self, px: np.ndarray, py: np.ndarray, x: np.ndarray, y: np.ndarray,
                   yaw: np.ndarray) -> np.ndarray:
        """The footprint's signed distance (m) to the nearest of the points at every rollout
        pose (S, K); ``inf`` without points."""
        if len(px) == 0:
            return np.full(x.shape, np.inf)
        # Each pose's frame: local = R(-yaw) (p - t), every pose and point at once (float32:
        # millimetres do not matter here, the time does).
        c, s = np.cos(yaw).astype(np.float32)[..., None], np.sin(yaw).astype(np.float32)[..., None]
        tx, ty = x.astype(np.float32)[..., None], y.astype(np.float32)[..., None]
        local = np.empty((2, *x.shape, len(px)), dtype=np.float32)  # (2, S, K, N)
        local[0] = c * px + s * py - (c * tx + s * ty)
        local[1] = c * py - s * px + (s * tx - c * ty)
        distance = self.robot.footprint.signed_distance(np.moveaxis(local, 0, -1))
        return distance.min(axis=-1).astype(np.float64)

    def _target(self, frame: SensorFrame, points: np.ndarray) -> tuple[float, float]:
        """Where the heading term aims (base frame, m): the goal when a lane as wide as the
        footprint plus the collision distance is free toward it for ``lookahead_m`` (or up to
        it); else ``lookahead_m`` along the free lane nearest the goal's bearing."""
        pose, goal = frame.pose, frame.goal
        assert goal is not None
        c0, s0 = math.cos(pose.yaw), math.sin(pose.yaw)
        gx = c0 * (goal[0] - pose.x) + s0 * (goal[1] - pose.y)
        gy = c0 * (goal[1] - pose.y) - s0 * (goal[0] - pose.x)
        reach = min(math.hypot(gx, gy), self.config.lookahead_m)
        if len(points) == 0 or reach <= 0:
            return gx, gy
        bearing = math.atan2(gy, gx)
        turns = wrap_angle(self._lanes - bearing)  # lanes as turns from the goal
        c, s = np.cos(self._lanes)[:, None], np.sin(self._lanes)[:, None]
        px, py = points[:, 0][None, :], points[:, 1][None, :]
        along, across = c * px + s * py, np.abs(c * py - s * px)  # (lanes, points)
        blocked = ((along > 0) & (along < reach) & (across < self._lane_half_m)).any(axis=1)
        if not blocked.all():
            free = turns[~blocked]
            # Keep going round the side chosen before: a detour that flips sides each time the
            # goal's bearing crosses the obstacle's middle goes nowhere.
            cost = np.abs(free) + np.where(np.sign(free) == -self._side, np.pi / 2, 0.0)
            turn = float(free[np.argmin(cost)])
            if abs(turn) > self._lane_step / 2:
                self._side = math.copysign(1.0, turn)
                return reach * math.cos(bearing + turn), reach * math.sin(bearing + turn)
        self._side = 0.0
        return gx, gy

    def _scores(self, target: tuple[float, float], v: np.ndarray, x: np.ndarray, y: np.ndarray,
                yaw: np.ndarray, free_m: np.ndarray, admissible: np.ndarray) -> np.ndarray:
        """Heading, clearance and speed terms, each normalised over the admissible samples."""
        gx, gy = target
        nearest = np.argmin(np.hypot(gx - x, gy - y), axis=1)[:, None]
        ex, ey = (np.take_along_axis(a, nearest, axis=1)[:, 0] for a in (x, y))
        eyaw = np.take_along_axis(yaw, nearest, axis=1)[:, 0]
        bearing = wrap_angle(np.arctan2(gy - ey, gx - ex) - eyaw)
        c = self.config
        terms = ((c.heading_weight, 1.0 - np.abs(bearing) / np.pi),
                 (c.clearance_weight, np.minimum(free_m, c.clearance_cap_m)),
                 (c.speed_weight, v / self.robot.max_linear_m_s))
        total = np.zeros_like(v)
        for weight, term in terms:
            top = float(np.max(np.abs(term[admissible])))
            if weight > 0 and top > 0:
                total += weight * term / top
        return total


#: The baselines ``pic4rl-test --baseline`` knows, and the tasks each drives (each task's
#: ``baselines`` in ``pic4rl_bridge.settings.tasks.TASKS``).
