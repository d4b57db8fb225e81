"""People for synthetic bags: the ``people`` topic's PoseArrays from tracks with known answers.

A robot passing a standing person at a known offset, or meeting a walking one head-on, has
social metrics known by hand (zone times are chords over the speed, the time to collision the
gap over the closing speed); ``synthetic.write_episode_bag(people=...)`` writes them as the
simulator and a tracker publish them: one ``geometry_msgs/PoseArray`` per stamp, the i-th pose
the i-th person.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np

from .. import contract
from ..contract import typestore
from .synthetic_tracks import Track, straight_line

#: The people's messages come after the robot's of the same stamp (``synthetic._Record``).
ORDER = 7


def standing(x: float, y: float, duration_s: float, dt_s: float = 0.1) -> Track:
    """A person standing at ``(x, y)`` for ``duration_s``."""
    return straight_line(0.0, duration_s, dt_s, start=(x, y, 0.0))


def people_records(people: Sequence[Track], t0_ns: int, *, frame: str = "map",
                   topic: str = contract.PEOPLE_TOPIC) -> list[tuple[int, int, str, Any]]:
    """One PoseArray per stamp of the people's common clock (``t0_ns + t_s``), the people in
    ``people``'s order; ``ValueError`` unless every track has the first one's ``t_s``. A
    person whose position is NaN at a stamp is left out of that message, as a tracker drops a
    lost track (put such people last: the index is the identity)."""
    if not people:
        return []
    t_s = people[0].t_s
    if any(len(p.t_s) != len(t_s) or not np.array_equal(p.t_s, t_s) for p in people):
        msg = "people: every track needs the same t_s (one PoseArray per stamp holds them all)"
        raise ValueError(msg)
    types = typestore().types
    point, quat = types["geometry_msgs/msg/Point"], types["geometry_msgs/msg/Quaternion"]
    pose, array = types["geometry_msgs/msg/Pose"], types["geometry_msgs/msg/PoseArray"]
    header, stamp = types["std_msgs/msg/Header"], types["builtin_interfaces/msg/Time"]
    records = []
    for i, ns in enumerate((t0_ns + np.round(t_s * 1e9).astype(np.int64)).tolist()):
        poses = [pose(point(p.x[i], p.y[i], 0.0),
                      quat(0.0, 0.0, math.sin(p.yaw[i] / 2), math.cos(p.yaw[i] / 2)))
                 for p in people if math.isfinite(p.x[i])]
        records.append((ns, ORDER, topic, array(header(stamp(*divmod(ns, 10**9)), frame), poses)))
    return records
