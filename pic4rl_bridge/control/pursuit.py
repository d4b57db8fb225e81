"""The pursuit law that the privileged planner and the mapless explorer follow their plans with.

The controller steers toward the farthest point of the plan within ``lookahead_m`` beyond the
robot's projection on it that the robot sees in a straight line (pure pursuit's look-ahead,
without its corner cutting): a yaw rate proportional to that point's bearing, and a speed that
falls from the full speed, with the bearing within a third of ``turn_in_place_rad``, to none
(turning in place) beyond it, capped by pure pursuit's arc. Both are continuous in the bearing,
so that a student can regress them (``pic4rl_bridge.baselines.planner``,
``pic4rl_bridge.baselines.explorer``).
"""

from __future__ import annotations

import math

import numpy as np
from pic4rl_base.geometry import Pose2D
from pic4rl_sim.engine.geometry import point_along
from pic4rl_sim.engine.taut_path import Visible

from ..perception.observations import target_polar
from ..robot_info import RobotInfo


_LOOKAHEAD_FRACTIONS = (1.0, 0.75, 0.5, 0.25)  # of lookahead_m, tried in turn
_TURN_GAIN = 2.5  # yaw rate (rad/s) per radian of bearing, up to the robot's limit


def pursuit_command(robot: RobotInfo, pose: Pose2D, path: np.ndarray, s: float,
                    visible: Visible, *, lookahead_m: float = 0.4,
                    turn_in_place_rad: float = 0.8,
                    max_linear_m_s: float | None = None) -> tuple[float, float]:
    """(v, ω) (m/s, rad/s) toward the farthest point of ``path`` within ``lookahead_m`` beyond
    arc length ``s`` (the robot's projection) that ``visible`` says the robot reaches in a
    straight line: the law of the module's docstring. ``max_linear_m_s``: a
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
