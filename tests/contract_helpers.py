"""What the bag-contract tests of the metrics and of the bridge's recorder share: episode facts
as the env writes them."""

from __future__ import annotations

import math

from pic4rl_base.geometry import Footprint, Pose2D
from pic4rl_metrics.contract import EpisodeFacts

#: Facts as the env writes them (a Jackal after a goToPose episode).
ENV_FACTS = EpisodeFacts(
    agent="sac", task="goToPose/lidar", world="indoor:0", robot="jackal", run="run1",
    episode="episode_0000", seed=7, footprint=Footprint(length_m=0.508, width_m=0.43),
    start=(0.0, 0.0, 0.0), goal=(2.0, 0.0), goal_tolerance_m=0.3, collision_tolerance_m=0.05,
    safety_margin_m=0.1, max_speed_mps=2.0, shortest_path_m=math.inf, straight_line_m=2.0,
    scan_mount=Pose2D(0.12, 0.0, 0.0),
)
