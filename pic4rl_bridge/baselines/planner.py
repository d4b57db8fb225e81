"""The privileged planner: a global path on the world's map, followed by a pursuit controller.

It knows what no agent observes (the world's geometry), so it is the map-aware reference in
the tables (what a planner with a known map, as nav2's, achieves) and the expert that labels
states for imitation (``pic4rl_agents.training.imitation``). Its plan is ``pic4rl_sim``'s
``plan_path`` (the shortest path with a clearance margin: the same plan the sim publishes on
``plan``), made again from the robot's position whenever the robot is more than
``replan_distance_m`` off it.
It keeps to its plan until then: a route planned anew at every step flips between the two
ways round an obstacle near the middle, and a student imitating those labels averages them
and stalls (in a DAgger probe, such students reached 5 of 50 goals after two rounds, with 35
timeouts, against 10 and 22 for students of this planner).

The controller steers toward the farthest point of the plan within ``lookahead_m`` beyond the
robot's projection on it that the robot sees in a straight line with ``clearance_m`` to spare
(pure pursuit's look-ahead, without its corner cutting): a yaw rate proportional to that
point's bearing, and a speed that falls from the full speed, with the bearing within a third of
``turn_in_place_rad``, to none (turning in place) beyond it, capped by pure pursuit's arc. Both
are continuous in the bearing, so that a student can regress them. The commands stay within
the env's speed ranges (and its own ``max_linear_m_s``, when set); the robot's acceleration
limits are the simulator's (its actuators are force-capped at them). Its settings are the
``baselines:`` section's ``planner.*`` (``PlannerConfig``): BARN's dense fields want it slower
or wider (``plan_margin_m``: a plan that keeps more than the simulator's widest margin).
"""

from __future__ import annotations

import math

import numpy as np
from pic4rl_metrics.geometry import project
from pic4rl_sim.engine.geometry import Pose2D, point_along
from pic4rl_sim.engine.paths import PLAN_MARGINS_M, plan_path, planner_for
from pic4rl_sim.engine.taut_path import Visible
from pic4rl_sim.engine.worlds.spec import WorldSpec

from ..perception.observations import target_polar
from ..robot_info import RobotInfo
from ..tasks.goto import normalized_action
from ..transports.frame import SensorFrame


_LOOKAHEAD_FRACTIONS = (1.0, 0.75, 0.5, 0.25)  # of lookahead_m, tried in turn
_TURN_GAIN = 2.5  # yaw rate (rad/s) per radian of bearing, up to the robot's limit


def pursuit_command(robot: RobotInfo, pose: Pose2D, path: np.ndarray, s: float,
                    visible: Visible, *, lookahead_m: float = 0.4,
                    turn_in_place_rad: float = 0.8,
                    max_linear_m_s: float | None = None) -> tuple[float, float]:
    """(v, ω) (m/s, rad/s) toward the farthest point of ``path`` within ``lookahead_m`` beyond
    arc length ``s`` (the robot's projection) that ``visible`` says the robot reaches in a
    straight line: the pursuit law of the module's docstring, which the mapless explorer
    (``pic4rl_bridge.baselines.explorer``) follows its own plans with too. ``max_linear_m_s``: a
    speed limit below the robot's (None: the robot's)."""
    xy = np.array([pose.x, pose.y])
    ahead = [point_along(path, s + f * lookahead_m) for f in _LOOKAHEAD_FRACTIONS]
    seen = visible(xy, np.array(ahead))
    target = ahead[int(np.argmax(seen))] if seen.any() else ahead[-1]
    distance, bearing = target_polar(pose, float(target[0]), float(target[1]))
    r = robot
    v_max = r.max_linear_m_s if max_linear_m_s is None else max_linear_m_s
    w = float(np.clip(_TURN_GAIN * bearing, -r.max_angular_rad_s, r.max_angular_rad_s))
    facing = (turn_in_place_rad - abs(bearing)) / (2.0 * turn_in_place_rad / 3.0)
    v = v_max * min(max(facing, 0.0), 1.0)
    curvature = 2.0 * math.sin(bearing) / max(distance, 1e-6)  # pure pursuit's arc
    if abs(curvature) * v > r.max_angular_rad_s:
        v = r.max_angular_rad_s / abs(curvature)
    return float(min(max(v, r.min_linear_m_s, 0.0), v_max)), w


class PlannerController:
    """The privileged planner for goToPose on ``world`` (see the module's docstring)."""

    def __init__(self, robot: RobotInfo, world: WorldSpec, *, lookahead_m: float = 0.4,
                 turn_in_place_rad: float = 0.8, replan_distance_m: float = 0.3,
                 clearance_m: float = 0.07, plan_margin_m: float = 0.0,
                 max_linear_m_s: float = 0.0) -> None:
        self.robot, self.world = robot, world
        self.margins_m = ((plan_margin_m, *PLAN_MARGINS_M) if plan_margin_m > 0
                          else PLAN_MARGINS_M)  # the widest that has a path
        self.max_linear_m_s = (min(max_linear_m_s, robot.max_linear_m_s) if max_linear_m_s > 0
                               else robot.max_linear_m_s)
        self._sight = planner_for(world, robot_radius_m=robot.footprint.bounding_radius_m
                                  + clearance_m)
        self.lookahead_m = lookahead_m
        self.turn_in_place_rad = turn_in_place_rad
        self.replan_distance_m = replan_distance_m
        self.plans = 0  # paths planned since the controller was made
        self._path: np.ndarray | None = None
        self._goal: tuple[float, float] | None = None

    def reset(self) -> None:
        """Forget the plan: the next frame plans from the robot's position."""
        self._path, self._goal = None, None

    @property
    def path(self) -> np.ndarray | None:
        """The plan being followed (k × 2, m), or ``None`` before the first frame."""
        return self._path

    def _replan(self, xy: tuple[float, float], goal: tuple[float, float]) -> np.ndarray:
        self.plans += 1
        path = plan_path(self.world, xy, goal,
                         robot_radius_m=self.robot.footprint.bounding_radius_m,
                         margins_m=self.margins_m)
        self._path, self._goal = (path if len(path) else np.array([xy, goal])), goal
        return self._path

    def command(self, frame: SensorFrame) -> tuple[float, float]:
        """(v, ω) (m/s, rad/s) for ``frame`` (see the module's docstring)."""
        if frame.goal is None:
            raise ValueError("PlannerController: the frame has no goal")
        xy, goal = (frame.pose.x, frame.pose.y), (float(frame.goal[0]), float(frame.goal[1]))
        path = self._path
        if path is None or goal != self._goal:
            path = self._replan(xy, goal)
        s, offset = project(path, xy) if len(path) > 1 else (0.0, 0.0)
        if abs(offset) > self.replan_distance_m:
            path = self._replan(xy, goal)
            s = 0.0
        return pursuit_command(self.robot, frame.pose, path, s, self._sight.visible,
                               lookahead_m=self.lookahead_m,
                               turn_in_place_rad=self.turn_in_place_rad,
                               max_linear_m_s=self.max_linear_m_s)

    def action(self, frame: SensorFrame) -> np.ndarray:
        """The goToPose normalised action of ``command``."""
        return normalized_action(self.robot, *self.command(frame))
