"""goToPose toward a UWB tag (``goal_input: uwb``, issue 40): the goal part is the tag's
distance and bearing from the robot-mounted anchors' ranges alone — analytic against known
tag positions, equal to the true polar goal without noise, unchanged when the frame's pose or
goal is replaced by nonsense (no odometry, no goal pose) — then a mask that shows each lost
range; a robot without anchors on it is refused in one line."""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np
import pytest

from pic4rl_base.errors import ConfigError
from pic4rl_base.geometry import Pose2D
from pic4rl_bridge.env import NavEnv
from pic4rl_bridge.perception.observations import NORMALIZED_GOAL_DISTANCE_M, target_polar
from pic4rl_bridge.readings.frame import SensorFrame
from pic4rl_bridge.readings.uwb_goal import UwbGoal
from pic4rl_sim.engine.sensor_kinds.uwb import UwbSpec

CONFIG = Path(__file__).resolve().parents[3] / "config" / "env_goto_uwb.yaml"
CORNERS = ((0.25, 0.2), (0.25, -0.2), (-0.25, 0.2), (-0.25, -0.2))
QUIET = {"uwb.noise_std_m": 0.0, "uwb.nlos_bias_m": 0.0, "uwb.dropout_prob": 0.0}


def _ranges(tag_xy: tuple[float, float], dz: float) -> np.ndarray:
    return np.array([math.sqrt(math.dist(tag_xy, a) ** 2 + dz * dz) for a in CORNERS])


@pytest.mark.parametrize(("distance", "bearing", "tol_m"),
                         [(8.0, 3.0, 0.005), (5.0, 1.2, 0.01), (2.0, -2.5, 0.02),
                          (1.0, 0.5, 0.04)])
def test_distance_and_bearing_from_exact_ranges(distance: float, bearing: float,
                                                tol_m: float) -> None:
    goal = UwbGoal(CORNERS, dz_m=0.6)
    tag = (distance * math.cos(bearing), distance * math.sin(bearing))
    d, b, mask = goal.estimate(_ranges(tag, 0.6))
    # far-field: the error falls as the anchors' spread over the distance
    assert d == pytest.approx(distance, abs=tol_m)
    assert b == pytest.approx(bearing, abs=0.01)
    np.testing.assert_array_equal(mask, [1, 1, 1, 1])


def test_a_lost_range_is_masked_and_three_still_give_the_bearing() -> None:
    goal = UwbGoal(CORNERS, dz_m=0.0)
    ranges = _ranges((3.0, 3.0), 0.0)
    ranges[1] = np.inf
    d, b, mask = goal.estimate(ranges)
    np.testing.assert_array_equal(mask, [1, 0, 1, 1])
    # three anchors fit the far-field model exactly: its curvature error stays (2 deg at 4 m)
    assert b == pytest.approx(math.pi / 4, abs=0.05) and d == pytest.approx(math.hypot(3, 3),
                                                                              abs=0.03)
    ranges[2] = np.inf  # two left: no bearing, the nearest range for the distance
    d, b, mask = goal.estimate(ranges)
    np.testing.assert_array_equal(mask, [1, 0, 0, 1])
    assert b == 0.0 and d == pytest.approx(min(ranges[0], ranges[3]))
    assert goal.estimate(np.full(4, np.inf))[:2] == (math.inf, 0.0)


def test_a_robot_without_anchors_on_it_is_refused_in_one_line() -> None:
    for specs in ({}, {"uwb": UwbSpec(anchors_xy_m=(1.0, 1.0, 2.0, 2.0, 3.0, 1.0))},
                  {"uwb": UwbSpec(anchors_xy_m=(1.0, 1.0, 2.0, 2.0), anchors_on_robot=True)}):
        with pytest.raises(ConfigError, match="goal_input: uwb needs") as err:
            UwbGoal.of(specs)
        assert "\n" not in str(err.value)
    with pytest.raises(ConfigError, match="uwb.anchors_on_robot"):
        NavEnv(str(CONFIG), sim={"uwb.anchors_on_robot": False})


def test_the_goal_part_is_the_true_polar_goal_from_ranges_alone() -> None:
    env = NavEnv(str(CONFIG), sim=QUIET)
    rng = np.random.default_rng(3)
    try:
        assert env.observation_space.shape == (36 + 2 + 4 + 2,)
        assert {"uwb_a0", "uwb_a1", "uwb_a2", "uwb_a3"} <= env.task.required
        for seed in (1, 2):
            obs, _ = env.reset(seed=seed)
            for _ in range(15):
                frame, context = env._frame, env._context
                true_d, true_b = target_polar(frame.pose, *context.goal)
                goal_part = obs[36:42]
                assert goal_part[0] == pytest.approx(
                    min(true_d / NORMALIZED_GOAL_DISTANCE_M, 1.0), abs=0.01)
                assert goal_part[1] == pytest.approx(true_b / math.pi, abs=0.01)
                np.testing.assert_array_equal(goal_part[2:], [1, 1, 1, 1])
                # nonsense pose and goal: the same observation
                blind = SensorFrame(frame.stamp_ns, Pose2D(-40.0, 17.0, 2.0), frame.twist,
                                    None, frame.readings)
                np.testing.assert_array_equal(
                    env.task.observe(blind, context, env._last_action), obs)
                obs, _, terminated, truncated, _ = env.step(
                    rng.uniform(-1, 1, 2).astype(np.float32))
                if terminated or truncated:
                    break
    finally:
        env.close()


def test_dropouts_show_in_the_mask_and_observations_stay_in_the_space() -> None:
    env = NavEnv(str(CONFIG), sim={"uwb.dropout_prob": 0.3})
    rng = np.random.default_rng(4)
    masks = []
    try:
        obs, _ = env.reset(seed=5)
        for _ in range(30):
            assert env.observation_space.contains(obs)
            masks.append(obs[38:42])
            obs, _, terminated, truncated, _ = env.step(rng.uniform(-1, 1, 2).astype(np.float32))
            if terminated or truncated:
                break
    finally:
        env.close()
    lost = 1.0 - np.mean(masks)
    assert 0.15 < lost < 0.45  # 30 % of the ranges


def test_an_agent_trained_toward_the_tag_refuses_the_true_goal() -> None:
    from pic4rl_bridge.config import agent_conflicts, load_env_config

    uwb = load_env_config(CONFIG)
    assert ("goal_input", "uwb", "goal") in agent_conflicts(
        uwb, dataclasses.replace(uwb, goal_input=type(uwb.goal_input)("goal")))
