"""The person follower's heading law: a yaw rate proportional to the person's bearing.

It keeps the person in the camera's view: the classical yaw rate of the person-following task
(``pic4rl_bridge.baselines.follow.HeadingController``, the ``dwa_heading`` baseline and the
task's expert), beside the DWA that plans the translation.
"""

from __future__ import annotations

import numpy as np
from pic4rl_base.geometry import Pose2D

from ..perception.observations import target_polar
from ..robot_info import RobotInfo


def heading_rate(robot: RobotInfo, pose: Pose2D, person: Pose2D, gain: float) -> float:
    """ω (rad/s) = ``gain`` × the bearing of ``person`` seen from ``pose`` (rad, left
    positive), clipped to the robot's [-max_angular, max_angular]."""
    _, bearing = target_polar(pose, person.x, person.y)
    return float(np.clip(gain * bearing, -robot.max_angular_rad_s, robot.max_angular_rad_s))
