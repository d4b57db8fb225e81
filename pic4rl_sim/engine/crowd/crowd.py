"""The crowd's state: who walks with whom, where to, and one control period of the social
force model at a time.

Each group shares a goal drawn among the free space of the world and the route to it (a taut
shortest path for a person's disc, ``paths.PathPlanner`` at 0.1 m): the driving force points
at the member's next waypoint, so people walk round walls and through doors; the forces of
``forces`` keep them off each other, the walls and the robot. When a group's first member
reaches the goal, or the route takes over twice its expected time, the group draws the next
goal. Every draw comes from the episode's own ``crowd`` stream: the same world and seed give
the same walks.
"""

from __future__ import annotations

import math

import numpy as np

from ...errors import WorldError
from ..paths import planner_for
from ..worlds.spec import WorldSpec
from . import forces
from .obstacles import Walls
from .params import CrowdParams

MAX_DT_S = 0.05  # the model's integration step, at most
WAYPOINT_REACHED_M = 0.5
ROBOT_KEEP_OFF_M = 1.0  # least gap between a person placed at a reset and the robot's start
_PLAN_RESOLUTION_M = 0.1
_PLAN_MARGINS_M = (0.1, 0.0)  # beyond the radius: a margin where the passage allows it
_GOAL_MIN_DISTANCE_M = 2.0
_PLACE_CLEARANCE_M = 0.15  # beyond the radius, from obstacles and other people
_GROUP_SPREAD_M = 1.0
_BATCH = 256
_BATCHES = 100
_GOAL_TRIES = 20
_SPEED_CLIP = (0.3, 1.5)  # desired speeds, as fractions of the mean
_LATE_FACTOR, _LATE_EXTRA_S = 2.0, 10.0


class Crowd:
    """``params.count`` people in ``world``; ``reset`` places them, ``advance`` walks them."""

    def __init__(self, params: CrowdParams, world: WorldSpec) -> None:
        self.params, self.world = params, world
        self._walls = Walls(world)
        self._planners = [planner_for(world, robot_radius_m=params.radius_m + m,
                                      resolution_m=_PLAN_RESOLUTION_M) for m in _PLAN_MARGINS_M]
        n = params.count
        self.pos = np.zeros((n, 2))
        self.vel = np.zeros((n, 2))
        self.yaw = np.zeros(n)
        self.speed = np.zeros(n)
        self.group = np.zeros(n, dtype=np.int64)
        self._radius = np.full(n, params.radius_m)
        self._routes: list[np.ndarray] = []
        self._deadline = np.zeros(0)
        self._waypoint = np.zeros(n, dtype=np.int64)
        self._time = 0.0
        self._rng = np.random.default_rng(0)

    # -- episodes ------------------------------------------------------------------------------

    def reset(self, rng: np.random.Generator, robot_xy: tuple[float, float],
              robot_radius_m: float) -> None:
        """Groups, desired speeds and places (clear of the obstacles, each other and the robot
        at ``robot_xy``), at rest, each group with a goal and its route."""
        p, n = self.params, self.params.count
        self._rng, self._time = rng, 0.0
        sizes: list[int] = []
        while sum(sizes) < n:
            sizes.append(min(int(rng.integers(1, p.max_group_size + 1)), n - sum(sizes)))
        self.group = np.repeat(np.arange(len(sizes)), sizes)
        mean = p.speed_mean_m_s
        self.speed = np.clip(rng.normal(mean, p.speed_std_m_s, n), *(f * mean for f in _SPEED_CLIP))
        keep_off = np.array([[*robot_xy, robot_radius_m + ROBOT_KEEP_OFF_M - _PLACE_CLEARANCE_M]])
        for i in range(n):
            follower = i > 0 and self.group[i] == self.group[i - 1]
            near = self.pos[i - 1] if follower else None
            self.pos[i] = self._free_point(near, np.vstack((
                keep_off, np.column_stack((self.pos[:i], self._radius[:i])))))
        self.vel[:] = 0.0
        self._routes = [np.zeros((0, 2))] * len(sizes)
        self._deadline = np.zeros(len(sizes))
        for g in range(len(sizes)):
            self._new_goal(g)
        self.yaw = self._heading_to_waypoints()

    def _free_point(self, near: np.ndarray | None, taken: np.ndarray) -> np.ndarray:
        """A point clear of the obstacles and of ``taken`` discs (x, y, radius), uniform in
        the bounds, or within ``_GROUP_SPREAD_M`` of ``near``."""
        xmin, ymin, xmax, ymax = self.world.bounds
        clear = self.params.radius_m + _PLACE_CLEARANCE_M
        for _ in range(_BATCHES):
            if near is None:
                pts = self._rng.uniform((xmin, ymin), (xmax, ymax), (_BATCH, 2))
            else:
                pts = near + self._rng.uniform(-_GROUP_SPREAD_M, _GROUP_SPREAD_M, (_BATCH, 2))
            ok = ((pts[:, 0] >= xmin + clear) & (pts[:, 0] <= xmax - clear)
                  & (pts[:, 1] >= ymin + clear) & (pts[:, 1] <= ymax - clear))
            ok &= self.world.clearance(pts) >= clear
            gaps = np.hypot(*(pts[:, None, :] - taken[None, :, :2]).transpose(2, 0, 1))
            ok &= (gaps >= taken[None, :, 2] + clear).all(axis=1)
            if ok.any():
                return pts[np.argmax(ok)]
            near = None  # no room beside the group: anywhere
        raise WorldError(f"crowd.count: {self.params.count} is invalid; expected a crowd that "
                         f"fits world {self.world.name!r} (no free place left for a person)")

    def _new_goal(self, g: int) -> None:
        """Group ``g``'s next goal and the route to it from its first member."""
        members = np.flatnonzero(self.group == g)
        here = self.pos[members[0]]
        route = np.array([here, here])
        for _ in range(_GOAL_TRIES):
            goal = self._free_point(None, np.array([[*here, _GOAL_MIN_DISTANCE_M]]))
            found = next((path for planner in self._planners
                          if len(path := planner.path(here, goal)) >= 2), None)
            if found is not None:
                route = found
                break
        self._routes[g] = route
        self._waypoint[members] = 1
        length = float(np.hypot(*np.diff(route, axis=0).T).sum())
        slowest = float(self.speed[members].min())
        self._deadline[g] = self._time + _LATE_FACTOR * length / slowest + _LATE_EXTRA_S

    # -- stepping ------------------------------------------------------------------------------

    def advance(self, duration_s: float, robot_xy: tuple[float, float],
                robot_velocity: tuple[float, float], robot_radius_m: float) -> None:
        """Walk ``duration_s`` in steps of at most ``MAX_DT_S``, the robot a moving body at
        ``robot_xy`` with ``robot_velocity`` (world, m/s) that people avoid."""
        steps = max(1, math.ceil(duration_s / MAX_DT_S - 1e-9))
        dt = duration_s / steps
        robot = (np.array([robot_xy]), np.array([robot_velocity]), np.array([robot_radius_m]))
        for _ in range(steps):
            self._integrate(dt, robot)
        moving = np.hypot(*self.vel.T) > 0.05
        self.yaw = np.where(moving, np.arctan2(self.vel[:, 1], self.vel[:, 0]), self.yaw)

    def _integrate(self, dt: float, robot: tuple[np.ndarray, np.ndarray, np.ndarray]) -> None:
        self._time += dt
        self._follow_routes()
        direction = self._directions()
        others = np.vstack((self.pos, robot[0]))
        steps = np.vstack((self.vel, robot[1])) * forces.STEP_TIME_S
        r = forces.surface_vectors(self.pos, self._radius, others,
                                   np.concatenate((self._radius, robot[2])))
        pair = forces.pair_forces(r, np.broadcast_to(steps, r.shape))
        pair[:, : len(self.pos)][np.eye(len(self.pos), dtype=bool)] = 0.0
        pair *= forces.field_of_view(direction, pair)[..., None]
        away, dist = self._walls.nearest(self.pos)
        total = (forces.driving(self.vel, direction, self.speed) + pair.sum(axis=1)
                 + forces.wall_forces(away, dist)
                 + forces.group_forces(self.pos, self.vel, self.params.radius_m, self.group))
        self.vel = forces.cap_speed(self.vel + total * dt, self.speed)
        self.pos = self.pos + self.vel * dt
        self._separate(robot[0], robot[2])

    def _separate(self, robot_xy: np.ndarray, robot_radius: np.ndarray) -> None:
        """Contacts: people who overlap are moved apart equally along their centres' line, a
        person overlapping the robot's disc is moved off it, then a person overlapping an
        obstacle is moved out to touch it and loses its velocity into it. The paper's
        walkers are points and need none; Helbing, Farkas & Vicsek (2000) give bodies a stiff
        contact force instead, which the 0.05 s step cannot integrate stably."""
        n = len(self.pos)
        r = self.pos[:, None, :] - np.vstack((self.pos, robot_xy))[None, :, :]
        dist = np.hypot(r[..., 0], r[..., 1])
        reach = self._radius[:, None] + np.concatenate((self._radius, robot_radius))[None, :]
        overlap = np.maximum(reach - dist, 0.0)
        overlap[:, :n][np.eye(n, dtype=bool)] = 0.0
        overlap[:, :n] *= 0.5  # each of two people moves half the way
        self.pos = self.pos + (overlap[..., None] * r / np.maximum(dist, 1e-9)[..., None]).sum(1)
        away, depth = self._walls.nearest(self.pos)
        push = np.maximum(self._radius[:, None] - depth, 0.0)
        self.pos = self.pos + (push[..., None] * away).sum(axis=1)
        into = np.minimum(np.einsum("nk,nmk->nm", self.vel, away), 0.0) * (push > 0)
        self.vel = self.vel - (into[..., None] * away).sum(axis=1)

    def _follow_routes(self) -> None:
        """Advance each member past reached waypoints; a group whose first member reached
        the goal, or is late, draws its next one."""
        for g, route in enumerate(self._routes):
            members = np.flatnonzero(self.group == g)
            last = len(route) - 1
            for i in members:
                while (self._waypoint[i] < last and np.hypot(
                        *(route[self._waypoint[i]] - self.pos[i])) < WAYPOINT_REACHED_M):
                    self._waypoint[i] += 1
            lead = members[0]
            arrived = np.hypot(*(route[last] - self.pos[lead])) < WAYPOINT_REACHED_M
            if arrived or self._time > self._deadline[g]:
                self._new_goal(g)

    def _directions(self) -> np.ndarray:
        """Unit vectors (n × 2) from each person to its next waypoint (0 at its goal)."""
        targets = np.array([self._routes[g][k] for g, k in zip(self.group, self._waypoint)])
        vec = targets - self.pos
        norm = np.hypot(*vec.T)
        return np.where((norm > 1e-6)[:, None], vec / np.maximum(norm, 1e-9)[:, None], 0.0)

    def _heading_to_waypoints(self) -> np.ndarray:
        d = self._directions()
        return np.arctan2(d[:, 1], d[:, 0])
