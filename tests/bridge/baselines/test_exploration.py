"""The explore baselines on synthetic scans: the frontier explorer heads for the opening of a
round room and stops in a closed one; the random walk drives on in the open and turns in
place before a wall."""

from __future__ import annotations

import math

import numpy as np
import pytest

from pic4rl_base.geometry import Footprint, Pose2D
from pic4rl_bridge.baselines.exploration import FrontierExplorer, RandomWalk
from pic4rl_bridge.readings.frame import ScanData, SensorFrame
from pic4rl_bridge.robot_info import RobotInfo
from pic4rl_sim.engine.geometry import Twist2D

BEAMS = 720
ROBOT = RobotInfo(name="test", footprint=Footprint(radius_m=0.2), omni=False,
                  min_linear_m_s=0.0, max_linear_m_s=0.5, max_angular_rad_s=1.0,
                  max_lateral_m_s=0.0, control_dt_s=0.1)
ANGLES = -math.pi + 2 * math.pi / BEAMS * np.arange(BEAMS)


def frame(ranges: np.ndarray, yaw: float = 0.0) -> SensorFrame:
    scan = ScanData(ranges.astype(np.float32), -math.pi, 2 * math.pi / BEAMS, 0.05, 10.0)
    return SensorFrame(0, Pose2D(0.0, 0.0, yaw), Twist2D(), scan=scan)


def test_the_frontier_explorer_heads_for_the_rooms_opening():
    ranges = np.full(BEAMS, 2.0)
    opening = np.abs(ANGLES - math.radians(90.0)) < math.radians(15.0)
    ranges[opening] = np.inf  # a door to the left: nothing seen within range
    explorer = FrontierExplorer(ROBOT)
    v, w = explorer.command(frame(ranges))
    assert explorer.target is not None
    bearing = math.degrees(math.atan2(explorer.target[1], explorer.target[0]))
    assert abs(bearing - 90.0) < 20.0 and 1.5 < math.hypot(*explorer.target) < 3.0
    assert v == 0.0 and w > 0.0  # it turns in place toward the door first


def test_the_frontier_explorer_stops_in_a_closed_room():
    explorer = FrontierExplorer(ROBOT)
    assert explorer.command(frame(np.full(BEAMS, 2.0))) == (0.0, 0.0)
    assert explorer.target is None and explorer.targets == 0


def test_the_random_walk_drives_on_in_the_open_and_turns_before_a_wall():
    walk = RandomWalk(ROBOT, seed=3)
    assert walk.action(frame(np.full(BEAMS, np.inf))).tolist() == [1.0, 0.0]
    turning = walk.action(frame(np.where(np.abs(ANGLES) < 0.3, 0.4, np.inf)))
    assert turning[0] == -1.0 and abs(turning[1]) == pytest.approx(1.0)
    # it keeps turning the same way for at least 0.5 s, whatever it sees
    for _ in range(4):
        assert walk.action(frame(np.full(BEAMS, np.inf))).tolist() == turning.tolist()
