"""The control laws tasks and baselines share (``pic4rl_bridge.control``), against their
analytic answers: the normalised action and its planar command are each other's inverse, the
heading law is a clipped proportional yaw rate, and pursuit drives straight at full speed down
a straight path ahead and turns in place toward one behind."""

from __future__ import annotations

import math

import numpy as np
import pytest

from pic4rl_base.geometry import Footprint, Pose2D
from pic4rl_bridge.control import (heading_rate, normalized_action, planar_action_space,
                                   planar_command, pursuit_command)
from pic4rl_bridge.robot_info import RobotInfo

#: v in [-0.2, 0.5] m/s, |ω| <= 1 rad/s.
ROBOT = RobotInfo(name="r", footprint=Footprint(length_m=0.5, width_m=0.4), omni=False,
                  min_linear_m_s=-0.2, max_linear_m_s=0.5, max_angular_rad_s=1.0,
                  max_lateral_m_s=0.0, control_dt_s=0.1, mounts={},
                  max_linear_accel_m_s2=3.0, max_angular_accel_rad_s2=6.0)


def _all_visible(xy: np.ndarray, points: np.ndarray) -> np.ndarray:
    return np.ones(len(points), dtype=bool)


@pytest.mark.parametrize(("v", "w"), [(-0.2, -1.0), (0.0, 0.0), (0.15, 0.5), (0.5, 1.0)])
def test_the_normalised_action_and_the_planar_command_invert_each_other(v: float,
                                                                        w: float) -> None:
    action = normalized_action(ROBOT, v, w)
    command = planar_command(action, ROBOT)
    assert command.vx == pytest.approx(v, abs=1e-6) and command.wz == pytest.approx(w, abs=1e-6)
    assert command.vy == 0.0 and action in planar_action_space()


def test_the_normalised_action_spans_the_robots_ranges_and_clips_beyond() -> None:
    # v = -0.2 → -1, v = 0.5 → +1: a = 2 (v - v_min) / (v_max - v_min) - 1
    np.testing.assert_allclose(normalized_action(ROBOT, 0.15, 0.25), [0.0, 0.25], atol=1e-6)
    np.testing.assert_allclose(normalized_action(ROBOT, 3.0, -5.0), [1.0, -1.0])


def test_the_heading_law_is_a_clipped_proportional_yaw_rate() -> None:
    pose = Pose2D(1.0, 1.0, math.pi / 2)  # facing +y
    left = Pose2D(1.0 - 2.0 * math.sin(0.2), 1.0 + 2.0 * math.cos(0.2), 0.0)  # 0.2 rad left
    assert heading_rate(ROBOT, pose, left, gain=2.0) == pytest.approx(0.4)
    behind_right = Pose2D(2.0, 0.0, 0.0)  # bearing -3π/4: clipped to -max_angular
    assert heading_rate(ROBOT, pose, behind_right, gain=2.0) == pytest.approx(-1.0)


def test_pursuit_drives_a_straight_path_ahead_at_full_speed_and_turns_in_place_for_one_behind(
        ) -> None:
    path = np.array([[0.0, 0.0], [5.0, 0.0]])
    v, w = pursuit_command(ROBOT, Pose2D(0.0, 0.0, 0.0), path, 0.0, _all_visible)
    assert (v, w) == (pytest.approx(0.5), pytest.approx(0.0))
    v, w = pursuit_command(ROBOT, Pose2D(0.0, 0.0, 0.0), path, 0.0, _all_visible,
                           max_linear_m_s=0.3)
    assert v == pytest.approx(0.3)
    v, w = pursuit_command(ROBOT, Pose2D(0.0, 0.0, math.pi), path, 0.0, _all_visible)
    assert v == 0.0 and abs(w) == pytest.approx(1.0)  # 2.5 × π clipped to the robot's limit
