"""Following a person with an omnidirectional base: DWA for (vx, vy), a heading law for ω.

The RL-DWA hybrid of Eirale et al. (2022) splits the command: the Dynamic Window Approach
plans the translation, keeping the person at a desired distance and the footprint off the
scan's points, while the yaw rate, which keeps the person in the camera's view, is the
agent's. ``PersonFollower`` is that DWA; ``HeadingController`` the classical yaw rate (a
proportional law on the person's bearing), which with the follower is the classical version
of the task (``pic4rl-test --baseline dwa_heading``) and the expert that labels states for
imitation. Pure numpy over the env's decoded frame, as the goToPose baselines.
"""

from __future__ import annotations

import math

import numpy as np

from ..config import EnvConfig
from ..control.following import heading_rate
from ..perception.collision import sensed_points
from ..perception.observations import target_polar
from ..robot_info import RobotInfo
from ..settings.tasks import PersonControl
from ..readings.frame import SensorFrame
from ..settings.baselines import DwaConfig
from .dwa import DwaController


class PersonFollower(DwaController):
    """DWA over body velocities (vx, vy) for an omni base whose yaw rate is given.

    The window is every (vx, vy) reachable from the measured twist within one control period
    at the robot's linear acceleration limit (both axes), inside its velocity ranges;
    ``linear_samples`` per axis. Each sample is rolled out for ``horizon_s`` with the given
    yaw rate ω (exact arcs: the body velocity turns with the base). Admissibility and the
    clearance term are goToPose DWA's (``DwaController``); the target term is the distance
    from the rollout's last pose to the follow point, ``distance_m`` short of the person on
    the line from the robot, weighted by ``heading_weight``: the sample that ends nearest it
    wins, so the base slows as it gets there and backs off when the person comes closer.
    Stateless: the window is centred on the frame's twist, so the command is a function of
    the frame and ω alone.
    """

    def __init__(self, robot: RobotInfo, config: DwaConfig | None = None, *,
                 distance_m: float = 2.0, collision_tolerance_m: float = 0.05) -> None:
        super().__init__(robot, config, collision_tolerance_m=collision_tolerance_m)
        self.distance_m = distance_m
        top = math.hypot(robot.max_linear_m_s, robot.max_lateral_m_s)
        self._reach_m = (top * self.config.horizon_s + robot.footprint.bounding_radius_m
                         + self.collision_m)

    def follow_point(self, frame: SensorFrame) -> tuple[float, float]:
        """Where the base should be (m, base frame): ``distance_m`` short of the person."""
        if frame.person is None:
            raise ValueError("PersonFollower: the frame has no person pose")
        distance, bearing = target_polar(frame.pose, frame.person.x, frame.person.y)
        along = distance - self.distance_m
        return along * math.cos(bearing), along * math.sin(bearing)

    def translation(self, frame: SensorFrame, wz: float) -> tuple[float, float]:
        """The chosen (vx, vy) (m/s, base frame) for ``frame`` while turning at ``wz``."""
        r, c = self.robot, self.config
        dv = r.max_linear_accel_m_s2 * r.control_dt_s
        axes = [np.linspace(max(now - dv, -top), min(now + dv, top), c.linear_samples)
                for now, top in ((frame.twist.vx, r.max_linear_m_s),
                                 (frame.twist.vy, r.max_lateral_m_s))]
        vx, vy = (a.ravel() for a in np.meshgrid(*axes, indexing="ij"))  # (S,)
        x, y, yaw = self._rollout_omni(vx, vy, wz)
        points = sensed_points(frame, r)
        clearance = self._clearance(*self._near_points(points), x, y, yaw)
        colliding = clearance < self.collision_m
        hit = colliding.any(axis=1)
        first = np.where(hit, self._times[colliding.argmax(axis=1)], np.inf)
        stop_s = np.hypot(vx, vy) / r.max_linear_accel_m_s2 + r.control_dt_s
        admissible = first > stop_s
        if not admissible.any():
            best = int(np.argmax(clearance.min(axis=1)))
            return float(vx[best]), float(vy[best])
        speed = np.hypot(vx, vy)
        free_m = np.where(hit, speed * np.where(hit, first, 0.0), c.clearance_cap_m)
        fx, fy = self.follow_point(frame)
        miss = np.hypot(x[:, -1] - fx, y[:, -1] - fy)
        total = np.zeros_like(vx)
        for weight, term in ((c.heading_weight, -miss),
                             (c.clearance_weight, np.minimum(free_m, c.clearance_cap_m))):
            top = float(np.max(np.abs(term[admissible])))
            if weight > 0 and top > 0:
                total += weight * term / top
        best = int(np.argmax(np.where(admissible, total, -np.inf)))
        return float(vx[best]), float(vy[best])

    def _rollout_omni(self, vx: np.ndarray, vy: np.ndarray, wz: float
                      ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Poses (S, K) from the origin at ``self._times`` under a constant body velocity
        (vx, vy) and yaw rate ``wz``: p(t) = [[a, -b], [b, a]] (vx, vy) with a = sin(ωt)/ω,
        b = (1 - cos(ωt))/ω, finite at ω = 0 (sinc forms, as the goToPose rollout)."""
        t = self._times[None, :]
        turn = wz * t
        a = t * np.sinc(turn / np.pi)
        b = t * 0.5 * turn * np.sinc(turn / (2.0 * np.pi)) ** 2
        vx, vy = vx[:, None], vy[:, None]
        x, y = vx * a - vy * b, vx * b + vy * a
        return x, y, np.broadcast_to(turn, x.shape)


class HeadingController:
    """The classical yaw rate: ω = ``gain`` × the person's bearing (rad, left positive),
    clipped to the robot's range (``pic4rl_bridge.control.following.heading_rate``). Its
    normalised action fits the env's control: [ω] when hybrid (the env's DWA adds the
    translation), else [vx, vy, ω] with ``PersonFollower``'s translation: DWA with a
    proportional heading controller."""

    def __init__(self, config: EnvConfig, robot: RobotInfo, *, gain: float = 2.0) -> None:
        self.robot = robot
        self.gain = gain
        self.hybrid = config.person.control == PersonControl.HYBRID.value
        self.follower = None if self.hybrid else PersonFollower(
            robot, config.person.dwa, distance_m=config.person.distance_m,
            collision_tolerance_m=config.collision_tolerance_m)

    def reset(self) -> None:
        """Nothing to forget: the law and the follower keep no state."""

    def action(self, frame: SensorFrame) -> np.ndarray:
        if frame.person is None:
            raise ValueError("HeadingController: the frame has no person pose")
        r = self.robot
        wz = heading_rate(r, frame.pose, frame.person, self.gain)
        if self.follower is None:
            return np.array([wz / r.max_angular_rad_s], np.float32)
        vx, vy = self.follower.translation(frame, wz)
        return np.clip(np.array([vx / r.max_linear_m_s, vy / r.max_lateral_m_s,
                                 wz / r.max_angular_rad_s], np.float32), -1.0, 1.0)
