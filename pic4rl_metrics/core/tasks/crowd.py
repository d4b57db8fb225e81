"""Social metrics: how the robot treats the people around it, from the ``people`` topic alone.

Hall's proxemic zones (intimate 0.45 m, personal 1.2 m, social 3.6 m; Hall 1966), the closest
approach, the time to collision of the constant-velocity model (Karamouzas et al. 2014),
contacts with people apart from the scan's collisions, the robot's speed near people and the
path irregularity (Guzzi et al. 2013). Distances are body to body, as HuNavSim's evaluator
measures them (Pérez-Higueras et al. 2023): the footprint's edge to the person's disc, whose
radius is the ``person_radius_m`` fact (the sim's crowd writes it) or ``PERSON_RADIUS_M``;
centre to centre, a robot touching a person would never be in the intimate zone. A simulated
crowd and a real robot's tracker are judged alike: everything is evaluated at the people
messages' stamps within the pose span, the robot's pose and velocity interpolated there; a
person is a column of the ``PeopleSeries`` (the PoseArray's index), its velocity the finite
difference of its column. Registered here in table order, imported by ``metrics``;
docs/metrics.md, "Social metrics".
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, NamedTuple
from weakref import WeakKeyDictionary

import numpy as np

from ..kinematics import interval_mean, seconds
from ..registry import metric

if TYPE_CHECKING:
    from ..derived import Derived

NAN = float("nan")
#: Hall's (1966) zones around a person, by their outer radius (m): closer than it intrudes.
ZONES_M: dict[str, float] = {"intimate": 0.45, "personal": 1.2, "social": 3.6}
#: A person's body disc radius (m) where the bag records no ``person_radius_m`` fact (a real
#: tracker's bag; a topic map's ``facts:`` may give one): the sim's ``crowd.radius_m`` default.
PERSON_RADIUS_M = 0.25
#: A time to collision beyond this (s), or none at all, reads as this: no collision course.
TTC_HORIZON_S = 10.0
#: The robot's speed "near people" is its speed while someone is within this zone.
NEAR_ZONE = "personal"


class Crowd(NamedTuple):
    """The people from the robot at the people messages' stamps within the pose span."""

    t_s: np.ndarray  # (n,)
    gap_m: np.ndarray  # (n, k) footprint edge to person's body edge (< 0: overlap), NaN absent
    rel: np.ndarray  # (n, k, 2) person minus robot, world frame (m)
    rel_vel: np.ndarray  # (n, k, 2) person's velocity minus the robot's (m/s)
    body: np.ndarray  # (n, k, 2) person in the robot's body frame (m)
    speed_mps: np.ndarray  # (n,) the robot's speed


_CROWDS: WeakKeyDictionary[Derived, Crowd | None] = WeakKeyDictionary()


def crowd(d: Derived) -> Crowd | None:
    """The episode's ``Crowd`` (computed once per ``Derived``); ``None`` when the people and
    the poses do not overlap in time or no message holds a person. Without a footprint its
    ``gap_m`` is NaN: the columns measured between bodies need one (``_BODIES``)."""
    if d not in _CROWDS:
        _CROWDS[d] = _crowd(d)
    return _CROWDS[d]


def _crowd(d: Derived) -> Crowd | None:
    pose, people, footprint = d.pose, d.episode.people, d.facts.footprint
    assert people is not None  # the registry checks the "people" input first
    inside = (people.t_ns >= pose.t_ns[0]) & (people.t_ns <= pose.t_ns[-1])
    if inside.sum() == 0 or people.x.shape[1] == 0:
        return None
    t0 = pose.t_ns[0]  # float64 of epoch nanoseconds would round to 256 ns
    at = (people.t_ns[inside] - t0).astype(float)
    pose_t = (pose.t_ns - t0).astype(float)
    rx, ry = np.interp(at, pose_t, pose.x), np.interp(at, pose_t, pose.y)
    yaw = np.interp(at, pose_t, np.unwrap(pose.yaw))
    v = d.velocity
    vel_t = (v.t_ns - t0).astype(float)
    vel_yaw = np.interp(vel_t, pose_t, np.unwrap(pose.yaw))
    world_vx = np.cos(vel_yaw) * v.vx - np.sin(vel_yaw) * v.vy
    world_vy = np.sin(vel_yaw) * v.vx + np.cos(vel_yaw) * v.vy
    robot_v = (np.column_stack([np.interp(at, vel_t, world_vx), np.interp(at, vel_t, world_vy)])
               if len(vel_t) else np.zeros((len(at), 2)))
    p = np.stack([people.x, people.y], axis=-1)  # (m, k, 2)
    people_s = seconds(people.t_ns, t0)
    p_vel = (np.gradient(p, people_s, axis=0) if len(people_s) > 1
             else np.zeros_like(p))[inside]
    rel = p[inside] - np.stack([rx, ry], axis=-1)[:, None, :]
    cos, sin = np.cos(yaw)[:, None], np.sin(yaw)[:, None]
    body = np.stack([cos * rel[..., 0] + sin * rel[..., 1],
                     -sin * rel[..., 0] + cos * rel[..., 1]], axis=-1)
    gap = (np.full(body.shape[:2], NAN) if footprint is None else
           footprint.signed_distance_xy(body[..., 0], body[..., 1]) - person_radius_m(d))
    return Crowd(seconds(people.t_ns[inside], t0), gap, rel, p_vel - robot_v[:, None, :], body,
                 np.hypot(robot_v[:, 0], robot_v[:, 1]))


def person_radius_m(d: Derived) -> float:
    """The people's body radius (m): the ``person_radius_m`` fact, else ``PERSON_RADIUS_M``."""
    radius = d.facts.person_radius_m
    return PERSON_RADIUS_M if radius is None else radius


def distances(c: Crowd) -> np.ndarray:
    """Body-to-body distance (m) to each person, 0 while they overlap, +inf where absent."""
    return np.where(np.isnan(c.gap_m), np.inf, np.maximum(c.gap_m, 0.0))


def nearest(c: Crowd) -> np.ndarray:
    """Body-to-body distance (m) to the nearest person at each stamp, +inf where nobody is
    reported."""
    return np.min(distances(c), axis=1)


def time_within(t_s: np.ndarray, dist_m: np.ndarray, radius_m: float) -> float:
    """Time (s) with ``dist_m < radius_m``, the distance linear between samples (a crossing
    placed where the line crosses the radius); an interval with an unknown end holds its
    first sample's state."""
    if len(t_s) < 2:
        return 0.0
    a, b, dt = dist_m[:-1], dist_m[1:], np.diff(t_s)
    lo, hi = np.minimum(a, b), np.maximum(a, b)
    known = np.isfinite(lo) & np.isfinite(hi)
    with np.errstate(divide="ignore", invalid="ignore"):
        crossing = np.clip((radius_m - lo) / (hi - lo), 0.0, 1.0)
    share = np.where(hi > lo, crossing, (lo < radius_m).astype(float))
    share = np.where(known, share, (a < radius_m).astype(float))
    return float(np.sum(share * dt))


def entries(flags: np.ndarray) -> int:
    """Rising edges of a (samples, people) flag, summed over people (a first True counts)."""
    if flags.size == 0:
        return 0
    return int(flags[0].sum() + (flags[1:] & ~flags[:-1]).sum())


def time_to_collision(rel: np.ndarray, rel_vel: np.ndarray, radius_m: float) -> np.ndarray:
    """Per sample and person, the first time (s) at which two discs whose centres are ``rel``
    apart and close at ``-rel_vel`` touch (radii summing to ``radius_m``): the smallest
    ``t >= 0`` with ``|rel + rel_vel t| = radius_m``; 0 when they touch already, +inf when
    they never do (Karamouzas et al. 2014's tau); NaN where the person is absent."""
    a = np.sum(rel_vel**2, axis=-1)
    b = np.sum(rel * rel_vel, axis=-1)
    c = np.sum(rel**2, axis=-1) - radius_m**2
    disc = b * b - a * c
    with np.errstate(divide="ignore", invalid="ignore"):
        tau = np.where((b < 0) & (disc >= 0) & (a > 0), (-b - np.sqrt(disc)) / a, np.inf)
    tau = np.where(c <= 0, 0.0, tau)
    return np.where(np.isnan(c) | np.isnan(a), np.nan, tau)


#: What a column measured between bodies needs: the people and the robot's footprint.
_BODIES = ("people", "footprint")


def _register(name: str, unit: str, label: str, stat: Callable[[Crowd, Derived], float],
              position: int | None, needs: tuple[str, ...] = _BODIES) -> None:
    """Register a column; ``position``: its place in the comparison tables' social section."""
    def value(d: Derived) -> float:
        c = crowd(d)
        return NAN if c is None else float(stat(c, d))

    table = None if position is None else ("social", position)
    metric(name, unit=unit, label=label, needs=needs, table=table, _builtin=True)(value)


for _i, (_zone, _radius) in enumerate(ZONES_M.items()):
    _register(f"{_zone}_intrusion_count", "count", f"{_zone} zone entries",
              lambda c, d, r=_radius: entries(distances(c) < r), None, _BODIES)
    _register(f"{_zone}_intrusion_time_s", "s", f"{_zone} zone time",
              lambda c, d, r=_radius: time_within(c.t_s, nearest(c), r),
              _i if _i < 2 else None, _BODIES)


def _min_distance(c: Crowd, _d: Derived) -> float:
    near = nearest(c)
    return float(near.min()) if np.isfinite(near).any() else NAN


def _ttc_min(c: Crowd, d: Derived) -> float:
    footprint = d.facts.footprint
    assert footprint is not None  # the registry checks the "footprint" input first
    radius = footprint.bounding_radius_m + person_radius_m(d)
    tau = time_to_collision(c.rel, c.rel_vel, radius)
    return float(min(np.nanmin(tau), TTC_HORIZON_S)) if np.isfinite(c.gap_m).any() else NAN


def _people_collisions(c: Crowd, d: Derived) -> float:
    """Contacts: a person's body within the collision tolerance of the footprint's boundary;
    each person's rising edges, summed."""
    return float(entries(np.nan_to_num(c.gap_m, nan=np.inf) < d.facts.collision_tolerance_m))


def _speed_near_people(c: Crowd, _d: Derived) -> float:
    near = nearest(c) < ZONES_M[NEAR_ZONE]
    if len(c.t_s) < 2 or not near[:-1].any():
        return NAN
    return interval_mean(np.diff(c.t_s)[near[:-1]], c.speed_mps[:-1][near[:-1]])


def _path_irregularity(_c: Crowd, d: Derived) -> float:
    """(Σ|Δyaw| − |the goal's bearing at the start|) / path length (Guzzi et al. 2013): the
    turning beyond what facing the goal needs, per metre; without a goal, all the turning."""
    if d.path_m <= 0:
        return NAN
    turned = float(np.sum(np.abs(np.diff(np.unwrap(d.pose.yaw)))))
    needed = abs(float(d.goal_bearing[0])) if d.facts.goal is not None else 0.0
    return max(turned - needed, 0.0) / d.path_m


_register("people_dist_min_m", "m", "min person distance", _min_distance, 2)
_register("people_ttc_min_s", "s", "min time to collision", _ttc_min, 3)
_register("people_collision_count", "count", "people collisions", _people_collisions, 4)
_register("speed_near_people_mean_mps", "m/s", "speed near people", _speed_near_people, 5)
_register("path_irregularity_radpm", "rad/m", "path irregularity", _path_irregularity, None,
          ("people",))
#: The crowd table's social columns (``tables.protocol``'s ``crowd`` layout): each zone's
#: entries and time, the closest approach, the time to collision, the people contacts and the
#: speed near people.
SOCIAL_COLUMNS: tuple[str, ...] = (
    *(f"{zone}_intrusion_{kind}" for zone in ZONES_M for kind in ("count", "time_s")),
    "people_dist_min_m", "people_ttc_min_s", "people_collision_count",
    "speed_near_people_mean_mps")
del _i, _zone, _radius
