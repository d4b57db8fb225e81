"""UWB anchors on the robot (``uwb.anchors_on_robot``, issue 40's person-following layout)
against analytic answers: each mounted anchor, turned and moved with the robot, ranges to the
goal's tag; a post between the goal and one anchor biases that range alone, a wall hiding the
tag from all of them biases each by one shared draw; the robot's own tag still ranges to the
goal; the spec refuses robot anchors with none given."""

from __future__ import annotations

import math

import numpy as np
import pytest

from pic4rl_base.errors import ConfigError
from pic4rl_base.geometry import Pose2D
from pic4rl_sim.engine.sensor_kinds.uwb import UwbSpec

from test_uwb import samples  # this folder's: the tag in a one-box world

CORNERS = (0.25, 0.2, 0.25, -0.2, -0.25, 0.2, -0.25, -0.2)


def _world(pose: Pose2D, spec: UwbSpec) -> list[tuple[float, float, float]]:
    c, s = math.cos(pose.yaw), math.sin(pose.yaw)
    return [(pose.x + c * x - s * y, pose.y + s * x + c * y, z) for x, y, z in spec.anchors]


def test_each_robot_anchor_ranges_to_the_goals_tag_from_where_the_robot_carries_it() -> None:
    spec = UwbSpec(anchors_xy_m=CORNERS, anchors_on_robot=True, anchor_height_m=0.4,
                   goal_tag=False, goal_tag_height_m=1.0, noise_std_m=0.0)
    pose, goal = Pose2D(1.0, -2.0, 2.0), (-3.0, 1.5)
    ranges = samples("", spec, 1, goal=goal, pose=pose)[0]
    expected = [math.dist(a, (*goal, 1.0)) for a in _world(pose, spec)]
    assert spec.targets == ("a0", "a1", "a2", "a3")
    np.testing.assert_allclose(ranges, expected, atol=1e-5)
    # the robot turned: the anchors' ranges change, their order follows the robot
    turned = samples("", spec, 1, goal=goal, pose=Pose2D(1.0, -2.0, 2.0 + math.pi))[0]
    np.testing.assert_allclose(turned, expected[::-1], atol=1e-5)


def test_with_the_goal_tag_the_robots_own_tag_ranges_last() -> None:
    spec = UwbSpec(anchors_xy_m=CORNERS[:6], anchors_on_robot=True, anchor_height_m=0.4,
                   goal_tag=True, goal_tag_height_m=1.0, noise_std_m=0.0,
                   mount_xyz_m=(0.1, 0.0, 0.4))
    ranges = samples("", spec, 1, goal=(4.0, 0.0), pose=Pose2D(0.0, 0.0, 0.0))[0]
    assert spec.targets == ("a0", "a1", "a2", "goal")
    assert ranges[-1] == pytest.approx(math.dist((0.1, 0.0, 0.4), (4.0, 0.0, 1.0)), abs=1e-5)


def test_a_wall_between_the_goal_and_one_anchor_biases_that_range_alone() -> None:
    # a post 2 m tall at (0.75, 1.0): on the line from the goal (2, 3) down to anchor a0
    # (0.25, 0.2) there, 0.16 m and 0.36 m beside the lines to a1 and a2
    wall = '<geom type="box" pos="0.75 1.0 1" size="0.05 0.02 1"/>'
    spec = UwbSpec(anchors_xy_m=(0.25, 0.2, -0.25, -0.2, -0.25, 0.2), anchors_on_robot=True,
                   anchor_height_m=0.4, goal_tag=False, noise_std_m=0.0, nlos_bias_m=0.5)
    goal = (2.0, 3.0)
    ranges = samples(wall, spec, 3000, goal=goal)
    true = [math.dist(a, (*goal, 1.0)) for a in _world(Pose2D(0.0, 0.0, 0.0), spec)]
    errors = ranges - np.array(true)
    blocked = errors[:, 0]
    assert blocked.mean() == pytest.approx(0.5, abs=0.04)
    np.testing.assert_allclose(errors[:, 1:], 0.0, atol=1e-5)


def test_anchors_seeing_the_tag_through_one_wall_share_one_late_path() -> None:
    wall = '<geom type="box" pos="1.5 0 1" size="0.05 1 1"/>'  # hides the goal from all four
    spec = UwbSpec(anchors_xy_m=CORNERS, anchors_on_robot=True, anchor_height_m=0.4,
                   goal_tag=False, noise_std_m=0.0, nlos_bias_m=0.5)
    goal = (3.0, 0.0)
    errors = samples(wall, spec, 2000, goal=goal) - np.array(
        [math.dist(a, (*goal, 1.0)) for a in _world(Pose2D(0.0, 0.0, 0.0), spec)])
    assert errors[:, 0].mean() == pytest.approx(0.5, abs=0.04)
    # one draw an instant for every anchor: the range differences (the bearing) keep no bias
    np.testing.assert_allclose(errors - errors[:, :1], 0.0, atol=1e-5)


def test_robot_anchors_need_anchors() -> None:
    with pytest.raises(ConfigError, match="uwb.anchors_on_robot"):
        UwbSpec(anchors_xy_m=(), anchors_on_robot=True)
