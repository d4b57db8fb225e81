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

Among people (a ``people`` reading: the env has one when its sim has a crowd) it checks its
plan ahead every ``people_replan_s`` against each person's current position as a disc of its
circumscribed radius plus ``people_margin_m``, and when one is in the way replans round them
all on the world's map (``pic4rl_bridge.baselines.crowd_plan``; the world's plan when the
people close every way); ``people_replan_s`` 0 plans on the world's map alone, as without
people. It plans anew at every new goal and off its plan with the people too.

The ``predictive`` baseline is this planner with its speed timed against the world's moving
obstacles and the people (``PredictiveController``): neither DWA nor this planner predicts
motion, and on the dynamic BARN nearly all their collisions are with a moving obstacle
(docs/results.md).

The controller is the pursuit law of ``pic4rl_bridge.control.pursuit``: it steers toward the
farthest point of the plan within ``lookahead_m`` that the robot sees in a straight line with
``clearance_m`` to spare. The commands stay within
the env's speed ranges (and its own ``max_linear_m_s``, when set); the robot's acceleration
limits are the simulator's (its actuators are force-capped at them). Its settings are the
``baselines:`` section's ``planner.*`` (``PlannerConfig``): BARN's dense fields want it slower
or wider (``plan_margin_m``: a plan that keeps more than the simulator's widest margin).
"""

from __future__ import annotations

import math

import numpy as np

from pic4rl_base.geometry import project
from pic4rl_sim.engine.paths import PLAN_MARGINS_M, plan_path, planner_for
from pic4rl_sim.engine.worlds.spec import WorldSpec

from ..control.actions import normalized_action
from ..control.pursuit import pursuit_command
from ..perception.movers import MoverTracker, PeopleMotion
from ..readings.frame import SensorFrame
from ..robot_info import RobotInfo
from .crowd_plan import blocks, plan_around_people


class PlannerController:
    """The privileged planner for goToPose on ``world`` (see the module's docstring)."""

    def __init__(self, robot: RobotInfo, world: WorldSpec, *, lookahead_m: float = 0.4,
                 turn_in_place_rad: float = 0.8, replan_distance_m: float = 0.3,
                 clearance_m: float = 0.07, plan_margin_m: float = 0.0,
                 max_linear_m_s: float = 0.0, people_replan_s: float = 1.0,
                 people_margin_m: float = 0.5) -> None:
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
        self.people_plans = 0  # of which round the people
        #: Steps between plans round the people (0: never).
        self._people_every = (max(1, round(people_replan_s / robot.control_dt_s))
                              if people_replan_s > 0 else 0)
        self._keep_off_m = robot.footprint.bounding_radius_m + people_margin_m
        self._since = 0  # steps since the plan was last made or checked
        self._path: np.ndarray | None = None
        self._goal: tuple[float, float] | None = None

    def reset(self) -> None:
        """Forget the plan: the next frame plans from the robot's position."""
        self._path, self._goal, self._since = None, None, 0

    @property
    def path(self) -> np.ndarray | None:
        """The plan being followed (k × 2, m), or ``None`` before the first frame."""
        return self._path

    def _replan(self, xy: tuple[float, float], goal: tuple[float, float],
                people: np.ndarray | None) -> np.ndarray:
        self.plans += 1
        self._since = 0
        radius = self.robot.footprint.bounding_radius_m
        path = None
        if people is not None and len(people) and self._people_every:
            path = plan_around_people(self.world, xy, goal, np.asarray(people)[:, :2],
                                      robot_radius_m=radius, margins_m=self.margins_m,
                                      keep_off_m=self._keep_off_m)
            self.people_plans += path is not None
        if path is None:
            path = plan_path(self.world, xy, goal, robot_radius_m=radius,
                             margins_m=self.margins_m)
        self._path, self._goal = (path if len(path) else np.array([xy, goal])), goal
        return self._path

    def command(self, frame: SensorFrame) -> tuple[float, float]:
        """(v, ω) (m/s, rad/s) for ``frame`` (see the module's docstring)."""
        if frame.goal is None:
            raise ValueError("PlannerController: the frame has no goal")
        xy, goal = (frame.pose.x, frame.pose.y), (float(frame.goal[0]), float(frame.goal[1]))
        people = frame.readings.get("people")
        path, self._since = self._path, self._since + 1
        if path is None or goal != self._goal:
            path = self._replan(xy, goal, people)
        s, offset = project(path, xy) if len(path) > 1 else (0.0, 0.0)
        due = (people is not None and len(people) > 0 and self._people_every > 0
               and self._since >= self._people_every)
        if due:
            self._since = 0
        if abs(offset) > self.replan_distance_m or (due and blocks(
                path, s, xy, np.asarray(people)[:, :2], self._keep_off_m)):
            path = self._replan(xy, goal, people)
            s = 0.0
        return pursuit_command(self.robot, frame.pose, path, s, self._sight.visible,
                               lookahead_m=self.lookahead_m,
                               turn_in_place_rad=self.turn_in_place_rad,
                               max_linear_m_s=self.max_linear_m_s)

    def action(self, frame: SensorFrame) -> np.ndarray:
        """The goToPose normalised action of ``command``."""
        return normalized_action(self.robot, *self.command(frame))


#: The speeds ``PredictiveController`` tries, fractions of its limit, fastest first.
_SPEED_FRACTIONS = (1.0, 0.75, 0.5, 0.25, 0.0)
#: No people: their positions and velocities (0 × 2 each).
_NOBODY = (np.empty((0, 2)), np.empty((0, 2)))


class PredictiveController(PlannerController):
    """The privileged planner whose speed is timed against what moves (a path-velocity
    decomposition, Kant and Zucker 1986): the plan and the steering are the planner's; the
    world's moving obstacles are tracked from the scan against its map and the people come
    with their positions in the ``people`` reading (``pic4rl_bridge.perception.movers``), all
    predicted at constant velocity. Each step the robot's progress along its plan is simulated
    for ``horizon_s`` at each of ``_SPEED_FRACTIONS`` of its limit (reached at the robot's
    acceleration limit), as its bounding disc on the plan; the fastest that stays
    ``mover_margin_m`` clear of every mover's and person's (a disc of ``person_radius_m``)
    predicted disc over the horizon caps the pursuit law's speed. When none does, the one
    whose first contact comes latest (it may be the fastest: a blind mover hits a robot that
    stops). A world without moving obstacles or people leaves it the planner."""

    def __init__(self, robot: RobotInfo, world: WorldSpec, *, horizon_s: float = 2.0,
                 mover_margin_m: float = 0.1, person_radius_m: float = 0.25,
                 **planner: float) -> None:
        super().__init__(robot, world, **planner)
        moving = world.moving
        self.tracker = None if moving is None else MoverTracker(
            world, moving.radius_m, top_speed_m_s=moving.speed_range_m_s[1])
        self._reach_m = (robot.footprint.bounding_radius_m + mover_margin_m
                         + (moving.radius_m if moving is not None else 0.0))
        self._person_reach_m = robot.footprint.bounding_radius_m + mover_margin_m + person_radius_m
        self.people = PeopleMotion()
        self._people_now = _NOBODY
        self._times = robot.control_dt_s * np.arange(
            1, max(1, round(horizon_s / robot.control_dt_s)) + 1)

    def reset(self) -> None:
        """Forget the plan, the tracks and the people."""
        super().reset()
        if self.tracker is not None:
            self.tracker.reset()
        self.people.reset()
        self._people_now = _NOBODY

    def predictions(self) -> tuple[np.ndarray, np.ndarray]:
        """The tracked movers' and the people's predicted centres over the horizon
        (K × n × 2) and each one's contact distance from the robot's centre (n, m)."""
        xy, velocity = self._people_now
        centres = [xy[None, :, :] + self._times[:, None, None] * velocity[None, :, :]]
        reach = [np.full(len(xy), self._person_reach_m)]
        if self.tracker is not None:
            centres.insert(0, self.tracker.predict(self._times))
            reach.insert(0, np.full(len(self.tracker.pos), self._reach_m))
        return np.concatenate(centres, axis=1), np.concatenate(reach)

    def speed_cap(self, frame: SensorFrame) -> float:
        """The speed (m/s) whose progress along the plan keeps clear of the predictions
        longest, the fastest of those that keep clear over the whole horizon."""
        assert self._path is not None
        path, dt = self._path, self.robot.control_dt_s
        along = np.r_[0.0, np.cumsum(np.hypot(*np.diff(path, axis=0).T))]
        start, _ = project(path, (frame.pose.x, frame.pose.y))
        movers, reach = self.predictions()  # (K, n, 2), (n,)
        v0, accel = frame.twist.vx, self.robot.max_linear_accel_m_s2
        best = (-math.inf, 0.0)
        for fraction in _SPEED_FRACTIONS:
            target = fraction * self.max_linear_m_s
            change = np.minimum(accel * self._times, abs(target - v0))
            speed = v0 + np.sign(target - v0) * change
            s = np.minimum(start + np.cumsum(speed * dt), along[-1])
            xy = np.column_stack((np.interp(s, along, path[:, 0]), np.interp(s, along, path[:, 1])))
            gap = np.hypot(*(movers - xy[:, None, :]).transpose(2, 0, 1))
            contact = (gap < reach[None, :]).any(axis=1)
            first = float(self._times[contact.argmax()]) if contact.any() else math.inf
            if first > best[0]:
                best = (first, target)
            if math.isinf(first):
                break
        return best[1]

    def command(self, frame: SensorFrame) -> tuple[float, float]:
        """The planner's (v, ω) for ``frame``, v capped by ``speed_cap``."""
        v, w = super().command(frame)
        if self.tracker is not None:
            self.tracker.update(frame)
        self._people_now = self.people.update(frame)
        if not (len(self._people_now[0]) or (self.tracker is not None and len(self.tracker.pos))):
            return v, w
        return min(v, self.speed_cap(frame)), w
