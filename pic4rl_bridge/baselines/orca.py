"""Optimal Reciprocal Collision Avoidance (van den Berg, Guy, Lin, Manocha 2011): the ``orca``
baseline, the classical velocity-obstacle reference for crowds that the social-navigation
literature compares learned planners with. Pure numpy over the env's decoded frame: the goal,
the scan and the crowd's ``people`` reading, whose velocities it estimates itself.

The robot is planned for as a holonomic disc (its footprint's bounding radius plus a margin);
the chosen velocity is tracked by a differential drive: turn toward it, drive at its speed
times the cosine of the heading error.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from pic4rl_base.geometry import wrap_angle

from ..control.actions import normalized_action
from ..perception.movers import PeopleMotion
from ..perception.occupancy import to_world
from ..readings.frame import SensorFrame
from ..robot_info import RobotInfo

_EPS = 1e-9
_SECTORS = 36  # scan obstacles: the nearest return per 10° sector


class Line(NamedTuple):
    """A half-plane of permitted velocities: those left of ``direction`` through ``point``."""

    point: np.ndarray
    direction: np.ndarray


def _det(a: np.ndarray, b: np.ndarray) -> float:
    return float(a[0] * b[1] - a[1] * b[0])


def orca_line(rel_position: np.ndarray, rel_velocity: np.ndarray, velocity: np.ndarray,
              radius: float, horizon_s: float, dt_s: float, responsibility: float) -> Line:
    """The ORCA half-plane for an agent at ``velocity`` against a neighbour at
    ``rel_position`` moving ``rel_velocity`` slower (own minus its; m, m/s), discs of summed
    ``radius``: the smallest change ``u`` that takes the relative velocity out of the
    velocity obstacle truncated at ``horizon_s`` (already overlapping: at ``dt_s``), of which
    this agent takes ``responsibility`` (½: reciprocal; 1: the neighbour does not avoid)."""
    dist_sq = float(rel_position @ rel_position)
    r_sq = radius * radius
    if dist_sq > r_sq:
        w = rel_velocity - rel_position / horizon_s
        w_sq = float(w @ w)
        dot = float(w @ rel_position)
        if dot < 0.0 and dot * dot > r_sq * w_sq:  # nearest the truncation's circle
            w_len = math.sqrt(w_sq)
            unit = w / w_len
            direction = np.array([unit[1], -unit[0]])
            u = (radius / horizon_s - w_len) * unit
        else:  # nearest a leg of the cone
            leg = math.sqrt(dist_sq - r_sq)
            x, y = rel_position
            if _det(rel_position, w) > 0.0:
                direction = np.array([x * leg - y * radius, x * radius + y * leg]) / dist_sq
            else:
                direction = -np.array([x * leg + y * radius, -x * radius + y * leg]) / dist_sq
            u = float(rel_velocity @ direction) * direction - rel_velocity
    else:  # overlapping: out of it within one step
        w = rel_velocity - rel_position / dt_s
        w_len = max(math.sqrt(float(w @ w)), _EPS)
        unit = w / w_len
        direction = np.array([unit[1], -unit[0]])
        u = (radius / dt_s - w_len) * unit
    return Line(velocity + responsibility * u, direction)


def _on_line(lines: list[Line], i: int, speed: float, preferred: np.ndarray,
             along: bool) -> np.ndarray | None:
    """The velocity of line ``i`` within ``speed`` and lines before it nearest ``preferred``
    (``along``: furthest in its direction), or ``None`` when there is none."""
    line = lines[i]
    dot = float(line.point @ line.direction)
    disc = dot * dot + speed * speed - float(line.point @ line.point)
    if disc < 0.0:
        return None
    t_left, t_right = -dot - math.sqrt(disc), -dot + math.sqrt(disc)
    for other in lines[:i]:
        denom = _det(line.direction, other.direction)
        numer = _det(other.direction, line.point - other.point)
        if abs(denom) <= _EPS:
            if numer < 0.0:
                return None
            continue
        t = numer / denom
        if denom >= 0.0:
            t_right = min(t_right, t)
        else:
            t_left = max(t_left, t)
        if t_left > t_right:
            return None
    if along:
        t = t_right if float(preferred @ line.direction) > 0.0 else t_left
    else:
        t = float(np.clip(line.direction @ (preferred - line.point), t_left, t_right))
    return line.point + t * line.direction


def _solve_2d(lines: list[Line], speed: float, preferred: np.ndarray,
              along: bool) -> tuple[int, np.ndarray]:
    """Incremental 2-D LP: (index of the first line that made it infeasible, or ``len``; the
    velocity within ``speed`` and the lines before it nearest ``preferred``)."""
    norm = float(np.hypot(*preferred))
    if along:
        result = preferred * speed
    elif norm > speed:
        result = preferred / norm * speed
    else:
        result = preferred.copy()
    for i, line in enumerate(lines):
        if _det(line.direction, line.point - result) > 0.0:
            found = _on_line(lines, i, speed, preferred, along)
            if found is None:
                return i, result
            result = found
    return len(lines), result


def solve(lines: list[Line], speed: float, preferred: np.ndarray) -> np.ndarray:
    """The velocity within ``speed`` (m/s) nearest ``preferred`` that all ``lines`` permit;
    when none does, the one that violates the worst of them least (the 3-D LP of RVO2)."""
    failed, result = _solve_2d(lines, speed, preferred, along=False)
    distance = 0.0
    for i in range(failed, len(lines)):
        line = lines[i]
        if _det(line.direction, line.point - result) <= distance:
            continue
        projected = []
        for other in lines[:i]:
            det = _det(line.direction, other.direction)
            if abs(det) <= _EPS:
                if float(line.direction @ other.direction) > 0.0:
                    continue
                point = 0.5 * (line.point + other.point)
            else:
                point = line.point + (_det(other.direction, line.point - other.point) / det
                                      ) * line.direction
            direction = other.direction - line.direction
            projected.append(Line(point, direction / max(float(np.hypot(*direction)), _EPS)))
        normal = np.array([-line.direction[1], line.direction[0]])
        done, candidate = _solve_2d(projected, speed, normal, along=True)
        if done == len(projected):
            result = candidate
        distance = _det(line.direction, line.point - result)
    return result


class OrcaController:
    """ORCA for goToPose among people and the scan's obstacles.

    Each step the preferred velocity heads for the goal at full speed (slowing within
    ``slow_m`` of it), turned ``keep_right_rad`` to the right: without it an obstacle dead
    ahead only slows the robot (the half-plane is then square to the path) until it stops,
    ORCA's symmetric deadlock; with it the robot keeps right, as people pass. Each person of the ``people`` reading (velocity: the difference of its
    positions over the last two frames' stamps, the array's order their identity) gives an
    ORCA half-plane over ``horizon_s``, a disc of ``person_radius_m`` with ``responsibility``
    taken by the robot; the scan's nearest return per 10° sector within ``obstacle_range_m``
    (those within ``person_radius_m`` + 0.1 m of a person left out: the person is one
    already) a static point over ``obstacle_horizon_s``, fully the robot's to avoid. The robot
    is a disc of its footprint's bounding radius + ``margin_m``. The velocity nearest the
    preferred one within all half-planes (the least violating when none fits) is tracked by
    ω = ``turn_gain`` × heading error, v = its speed × cos(heading error) (≥ 0).
    """

    def __init__(self, robot: RobotInfo, *, person_radius_m: float = 0.25,
                 margin_m: float = 0.15, horizon_s: float = 3.0,
                 obstacle_horizon_s: float = 1.0, obstacle_range_m: float = 2.0,
                 responsibility: float = 1.0, turn_gain: float = 2.5,
                 slow_m: float = 0.5, keep_right_rad: float = 0.15) -> None:
        self.robot = robot
        self.radius_m = robot.footprint.bounding_radius_m + margin_m
        self.person_radius_m = person_radius_m
        self.horizon_s, self.obstacle_horizon_s = horizon_s, obstacle_horizon_s
        self.obstacle_range_m = obstacle_range_m
        self.responsibility = responsibility
        self.turn_gain, self.slow_m = turn_gain, slow_m
        self.keep_right_rad = keep_right_rad
        self._people = PeopleMotion()

    def reset(self) -> None:
        """Forget the people seen: their velocities start again from zero."""
        self._people.reset()

    def people_velocities(self, frame: SensorFrame) -> tuple[np.ndarray, np.ndarray]:
        """The people's positions (n × 2) and velocities (n × 2, m/s): ``PeopleMotion``."""
        return self._people.update(frame)

    def _scan_obstacles(self, frame: SensorFrame, people: np.ndarray) -> np.ndarray:
        """The scan's nearest return per sector within range, in the world frame, people's
        returns left out."""
        if frame.scan is None:
            return np.empty((0, 2))
        local = frame.scan.points()
        dist = np.hypot(local[:, 0], local[:, 1])
        keep = dist < self.obstacle_range_m
        local, dist = local[keep], dist[keep]
        world = to_world(local, frame.pose)
        if len(people):
            gap = np.hypot(*(world[:, None, :] - people[None, :, :]).transpose(2, 0, 1))
            alone = (gap > self.person_radius_m + 0.1).all(axis=1)
            world, local, dist = world[alone], local[alone], dist[alone]
        sector = ((np.arctan2(local[:, 1], local[:, 0]) + math.pi)
                  / (2 * math.pi) * _SECTORS).astype(int) % _SECTORS
        nearest = {}
        for i in np.argsort(dist):
            nearest.setdefault(int(sector[i]), i)
        return world[sorted(nearest.values())]

    def velocity(self, frame: SensorFrame) -> np.ndarray:
        """The holonomic velocity (world frame, m/s) ORCA chooses for ``frame``."""
        if frame.goal is None:
            raise ValueError("OrcaController: the frame has no goal")
        pose, dt_s = frame.pose, self.robot.control_dt_s
        position = np.array([pose.x, pose.y])
        own = frame.twist.vx * np.array([math.cos(pose.yaw), math.sin(pose.yaw)])
        to_goal = np.array([frame.goal[0], frame.goal[1]]) - position
        distance = float(np.hypot(*to_goal))
        speed = self.robot.max_linear_m_s
        preferred = (to_goal / distance * speed * min(1.0, distance / self.slow_m)
                     if distance > _EPS else np.zeros(2))
        c, s = math.cos(self.keep_right_rad), math.sin(self.keep_right_rad)
        preferred = np.array([c * preferred[0] + s * preferred[1],
                              -s * preferred[0] + c * preferred[1]])
        people, moving = self.people_velocities(frame)
        lines = [orca_line(p - position, own - v, own, self.radius_m + self.person_radius_m,
                           self.horizon_s, dt_s, self.responsibility)
                 for p, v in zip(people, moving)]
        lines += [orca_line(q - position, own, own, self.radius_m, self.obstacle_horizon_s,
                            dt_s, 1.0) for q in self._scan_obstacles(frame, people)]
        return solve(lines, speed, preferred)

    def action(self, frame: SensorFrame) -> np.ndarray:
        chosen = self.velocity(frame)
        speed = float(np.hypot(*chosen))
        if speed < _EPS:
            return normalized_action(self.robot, 0.0, 0.0)
        error = wrap_angle(math.atan2(chosen[1], chosen[0]) - frame.pose.yaw)
        r = self.robot
        w = float(np.clip(self.turn_gain * error, -r.max_angular_rad_s, r.max_angular_rad_s))
        v = float(np.clip(speed * max(0.0, math.cos(error)), r.min_linear_m_s,
                          r.max_linear_m_s))
        return normalized_action(r, v, w)
