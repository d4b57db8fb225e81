"""Person-monitoring metrics: where the person is seen from the robot (Eirale et al. 2022).

The person's position is interpolated at the robot's pose stamps within the person topic's
time span; the bearing is measured from the robot's heading (left positive). The desired
distance and the camera's field of view are episode facts (``person_distance_m``,
``camera_fov_rad``) that pic4rl's env writes; a real bag gives them on the command line or
in its topic map. Registered here in table order, imported by ``metrics``.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import TYPE_CHECKING, NamedTuple

import numpy as np

from ..kinematics import bearing_in_body, interval_mean, seconds, time_mean
from ..registry import metric

if TYPE_CHECKING:
    from ..derived import Derived

NAN = float("nan")


class PersonSeen(NamedTuple):
    """The person from the robot at the pose stamps within the person's recorded span."""

    t_s: np.ndarray
    bearing_rad: np.ndarray
    distance_m: np.ndarray


def person_seen(d: Derived) -> PersonSeen | None:
    """The person's bearing and distance from the robot; ``None`` when the pose and person
    series do not overlap in time."""
    pose, person = d.pose, d.episode.person
    assert person is not None  # the registry checks the "person" input first
    inside = (pose.t_ns >= person.t_ns[0]) & (pose.t_ns <= person.t_ns[-1])
    if not inside.any():
        return None
    t0 = pose.t_ns[0]  # float64 of epoch nanoseconds would round to 256 ns
    at = (pose.t_ns[inside] - t0).astype(float)
    person_t = (person.t_ns - t0).astype(float)
    px, py = np.interp(at, person_t, person.x), np.interp(at, person_t, person.y)
    x, y = pose.x[inside], pose.y[inside]
    bearing = bearing_in_body(x, y, pose.yaw[inside], px, py)
    return PersonSeen(seconds(pose.t_ns[inside]), bearing, np.hypot(px - x, py - y))


def _register(name: str, unit: str, label: str, stat: Callable[[PersonSeen, Derived], float],
              needs: tuple[str, ...] = ("person",)) -> None:
    def value(d: Derived) -> float:
        seen = person_seen(d)
        return NAN if seen is None else float(stat(seen, d))

    metric(name, unit=unit, label=label, needs=needs, _builtin=True)(value)


def _in_view(seen: PersonSeen, d: Derived) -> float:
    """Share of time with |bearing| <= fov / 2, each sample holding until the next."""
    inside = np.abs(seen.bearing_rad) <= 0.5 * d.facts.camera_fov_rad
    if len(seen.t_s) < 2:
        return float(inside.all())
    return interval_mean(np.diff(seen.t_s), inside[:-1].astype(float))


_register("follow_heading_mean_rad", "rad", "following heading mean",
          lambda s, d: time_mean(s.t_s, s.bearing_rad))
_register("follow_heading_mae_rad", "rad", "following heading MAE",
          lambda s, d: time_mean(s.t_s, np.abs(s.bearing_rad)))
_register("follow_heading_rmse_rad", "rad", "following heading RMSE",
          lambda s, d: math.sqrt(time_mean(s.t_s, s.bearing_rad**2)))
_register("follow_heading_max_rad", "rad", "following heading max",
          lambda s, d: np.abs(s.bearing_rad).max())
_register("person_in_view_fraction", "fraction", "person in view", _in_view,
          ("person", "camera_fov"))
_register("person_dist_mean_m", "m", "person distance",
          lambda s, d: time_mean(s.t_s, s.distance_m))
_register("person_dist_error_mae_m", "m", "person distance MAE",
          lambda s, d: time_mean(s.t_s, np.abs(s.distance_m - d.facts.person_distance_m)),
          ("person", "person_distance"))
