"""A user's baseline, written outside pic4rl: it turns toward the goal and drives at a speed
that falls with the bearing (cos²), slowing to half near the goal. Its package registers it
in ``pyproject.toml`` beside it (the ``pic4rl.baselines`` entry point names ``SPEC``), and
``pic4rl-test --baseline bearing`` drives it (``tests/places/test_places.py``)."""

import math

import numpy as np

from pic4rl_base.geometry import wrap_angle
from pic4rl_bridge.baselines.registry import BaselineSpec
from pic4rl_bridge.control.actions import normalized_action


class Bearing:
    """(v, ω) from the frame's pose and goal, as a normalised goToPose action."""

    def __init__(self, robot):
        self.robot = robot

    def reset(self):
        """It keeps no state between episodes."""

    def action(self, frame):
        r = self.robot
        dx, dy = frame.goal[0] - frame.pose.x, frame.goal[1] - frame.pose.y
        bearing = wrap_angle(math.atan2(dy, dx) - frame.pose.yaw)
        w = float(np.clip(1.5 * bearing, -r.max_angular_rad_s, r.max_angular_rad_s))
        slow = 0.5 if math.hypot(dx, dy) < 0.5 else 1.0
        v = r.max_linear_m_s * slow * max(0.0, math.cos(bearing)) ** 2
        return normalized_action(r, max(v, r.min_linear_m_s), w)


SPEC = BaselineSpec(("goToPose",), lambda config, robot, world, settings: Bearing(robot))
