"""``NavEnv`` over the in-process transport (MuJoCo in this process, no ROS graph): the four
registered envs pass Gymnasium's checker, seeds make episodes reproducible, the reward is the
sum of its terms, episodes end by timeout, collision and goal as the config says, bad resets
are refused, and recorded episodes are bags the metrics judge.

Episodes that need known geometry run in the 10 m walled arena of ``tests/ros_helpers.py``
(walls at |x|, |y| = 5 m, a crate at (3, 3), a post at (-3, 3)).
"""

from __future__ import annotations

import math
import subprocess
import sys
import warnings
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env
from rosbags.highlevel import AnyReader
from ros_helpers import ARENA_MJCF

import pic4rl_bridge
from pic4rl_bridge.config import load_env_config
from pic4rl_bridge.env import NavEnv
from pic4rl_bridge.errors import BridgeError, ConfigError, EpisodeRejected
from pic4rl_bridge.recording import make_env
from pic4rl_metrics import compute
from bridge_helpers import ENV_CONFIGS, LIDAR_CONFIG, REPO

BEAMS = 36  # lidar.sectors of env_goto_lidar.yaml: obs[BEAMS] is the goal distance (m)
STOP = np.array([-1.0, 0.0], np.float32)  # v = min_linear = 0, no turn
START, GOAL = [-2.0, 0.0, 0.0], [0.0, 0.0]  # 2 m of free floor along +x
NEAR_WALL = [3.5, 0.0, 0.0]  # 1.5 m from the east wall, facing it


@pytest.fixture(scope="module")
def arena(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("world") / "arena.xml"
    path.write_text(ARENA_MJCF)
    return path


def arena_env(arena: Path, **overrides: Any) -> Any:
    """goToPose (LiDAR) from env_goto_lidar.yaml in the arena, with dotted ``overrides``: a
    ``NavEnv``, in ``RecordEpisodes`` when ``record.enabled``."""
    return make_env(LIDAR_CONFIG, sim={"world": str(arena)}, overrides=overrides)


def drive_to_goal(env: NavEnv, obs: np.ndarray) -> tuple[list[dict[str, Any]], list[float]]:
    """A proportional controller toward the goal until the episode ends; infos and rewards."""
    infos, rewards = [], []
    for _ in range(200):
        distance, angle = float(obs[BEAMS]), float(obs[BEAMS + 1])
        action = np.array([2.0 * min(1.0, distance) - 1.0, np.clip(2.0 * angle, -1, 1)])
        obs, reward, terminated, truncated, info = env.step(action)
        infos.append(info)
        rewards.append(reward)
        if terminated or truncated:
            return infos, rewards
    raise AssertionError("the episode did not end in 200 steps")


# --- Gymnasium's contract ---------------------------------------------------------------------


@pytest.mark.parametrize("env_id", sorted(ENV_CONFIGS))
def test_registered_envs_pass_the_checker_without_warnings(env_id: str) -> None:
    """Each registered id builds with its config file, runs its task and sensor, and passes
    ``check_env`` (spaces, seeding, determinism) without a single warning."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        env = gym.make(env_id, config=str(ENV_CONFIGS[env_id]))
        try:
            check_env(env.unwrapped)
            obs, _ = env.reset(seed=1)
            assert env.observation_space.contains(obs)
        finally:
            env.close()
    assert [str(w.message) for w in caught] == []
    spec = pic4rl_bridge.ENV_IDS[env_id]
    config = env.unwrapped.config
    assert (config.task, config.sensor) == (spec["task"], spec["sensor"])


def test_spaces_follow_task_and_sensor() -> None:
    """LiDAR sectors + goal vector; depth image + goal dict; depth image; omni 3-D actions."""
    spaces = {}
    for env_id, path in ENV_CONFIGS.items():
        env = gym.make(env_id, config=str(path))
        spaces[env_id] = (env.observation_space, env.action_space)
        env.close()
    lidar_obs, lidar_act = spaces["pic4rl/GoToPoseLidar-v0"]
    assert lidar_obs.shape == (BEAMS + 4,) and lidar_act.shape == (2,)
    depth_obs, _ = spaces["pic4rl/GoToPoseDepth-v0"]
    assert isinstance(depth_obs, gym.spaces.Dict)
    assert depth_obs["depth"].shape == (1, 60, 80) and depth_obs["depth"].dtype == np.uint8
    vineyard_obs, _ = spaces["pic4rl/Vineyard-v0"]
    assert vineyard_obs.shape == (1, 60, 80)
    person_obs, person_act = spaces["pic4rl/PersonMonitoring-v0"]
    assert person_obs.shape == (BEAMS + 6,) and person_act.shape == (3,)  # + walking direction


def test_import_is_light() -> None:
    """``import pic4rl_bridge`` registers the ids without importing rclpy, MuJoCo or torch."""
    code = ("import sys, gymnasium, pic4rl_bridge\n"
            "print(sorted(m for m in ('rclpy', 'mujoco', 'torch') if m in sys.modules))\n"
            "print(sum(i.startswith('pic4rl/') for i in gymnasium.registry))\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True, cwd=REPO, timeout=60).stdout.split("\n")
    assert out[0] == "[]"
    assert out[1] == str(len(ENV_CONFIGS))


# --- determinism and rewards ------------------------------------------------------------------


def rollout(env: NavEnv, seed: int, actions: np.ndarray) -> tuple[list[np.ndarray], list[float]]:
    """Observations and rewards of one seeded episode under ``actions``."""
    obs, _ = env.reset(seed=seed)
    observations, rewards = [obs], []
    for action in actions:
        obs, reward, terminated, truncated, _ = env.step(action)
        observations.append(obs)
        rewards.append(reward)
        if terminated or truncated:
            break
    return observations, rewards


def test_same_seed_same_episode_other_seed_other_episode() -> None:
    """Two envs (and one env reset again) give identical observations and rewards for the
    same seed and actions; another seed gives another episode."""
    actions = np.random.default_rng(0).uniform(-1.0, 1.0, size=(12, 2)).astype(np.float32)
    first, second = NavEnv(LIDAR_CONFIG), NavEnv(LIDAR_CONFIG)
    try:
        obs_a, rew_a = rollout(first, 5, actions)
        obs_b, rew_b = rollout(second, 5, actions)
        obs_c, rew_c = rollout(first, 5, actions)
        obs_d, _ = rollout(second, 6, actions)
    finally:
        first.close()
        second.close()
    assert len(rew_a) == len(rew_b) == len(rew_c) > 0
    for a, b, c in zip(obs_a, obs_b, obs_c):
        assert np.array_equal(a, b) and np.array_equal(a, c)
    assert rew_a == rew_b == rew_c
    assert not np.array_equal(obs_a[0], obs_d[0])


def test_reward_is_the_sum_of_its_terms_and_distance_is_progress(arena: Path) -> None:
    """Every step: reward = sum of ``reward_terms``; the distance term is
    reward.distance × (d_{t-1} - d_t), with the goal distances the observations report."""
    scale = 3.0
    env = arena_env(arena, **{"reward.distance": scale, "reward.heading": 0.5,
                              "reward.step": -0.25})
    try:
        obs, info = env.reset(seed=2, options={"start": [-2.0, -1.0, 0.5], "goal": GOAL})
        assert info["start"] == [-2.0, -1.0, 0.5] and tuple(info["goal"]) == (0.0, 0.0)
        assert float(obs[BEAMS]) == pytest.approx(math.hypot(2.0, 1.0), abs=1e-6)
        previous = float(obs[BEAMS])
        progress = 0.0
        for k in range(15):
            action = np.array([0.5, 0.8 if k < 5 else -0.3], np.float32)
            obs, reward, terminated, truncated, info = env.step(action)
            terms = info["reward_terms"]
            assert set(terms) == {"distance", "heading", "step", "proximity", "goal", "collision"}
            assert reward == pytest.approx(sum(terms.values()), rel=1e-12, abs=1e-12)
            distance = float(obs[BEAMS])
            assert terms["distance"] == pytest.approx(scale * (previous - distance), abs=1e-5)
            assert terms["step"] == -0.25
            progress += previous - distance
            previous = distance
            assert not (terminated or truncated)
    finally:
        env.close()
    assert progress > 0.1  # the terms compared were not all zero


def test_time_limit_truncates_as_a_timeout(arena: Path) -> None:
    """A robot told to stand still reaches ``episode_max_steps``: truncated, not terminated,
    outcome timeout; stepping on is an error."""
    env = arena_env(arena, episode_max_steps=5)
    try:
        obs, _ = env.reset(seed=0, options={"start": START, "goal": GOAL})
        first_distance = float(obs[BEAMS])
        for step in range(1, 6):
            obs, _, terminated, truncated, info = env.step(STOP)
            assert terminated is False and info["step"] == step
            assert truncated is (step == 5)
            assert ("outcome" in info) is (step == 5)
        assert info["outcome"] == "timeout" and info["is_success"] is False
        assert float(obs[BEAMS]) == pytest.approx(first_distance, abs=1e-3)  # stood still
        with pytest.raises(BridgeError, match=r"step\(\) after the episode ended"):
            env.step(STOP)
    finally:
        env.close()


def test_driving_into_a_wall_is_a_collision(arena: Path) -> None:
    """Full speed at the east wall ends the episode as a collision with the -150 term."""
    env = arena_env(arena)
    try:
        env.reset(seed=0, options={"start": NEAR_WALL, "goal": [-4.0, 0.0]})
        for _ in range(100):
            _, reward, terminated, truncated, info = env.step(np.array([1.0, 0.0]))
            if terminated or truncated:
                break
        assert terminated is True and truncated is False
        assert info["outcome"] == "collision" and info["is_success"] is False
        assert info["collision"] is True and info["min_obstacle_m"] < 0.05
        assert info["reward_terms"]["collision"] == -150.0
        assert reward == pytest.approx(sum(info["reward_terms"].values()))
        with pytest.raises(BridgeError):
            env.step(np.array([1.0, 0.0]))
    finally:
        env.close()


def test_reaching_the_goal_is_a_success(arena: Path) -> None:
    """A proportional controller reaches the goal: terminated, outcome goal, +1000."""
    env = arena_env(arena)
    try:
        obs, _ = env.reset(seed=0, options={"start": START, "goal": GOAL})
        infos, rewards = drive_to_goal(env, obs)
    finally:
        env.close()
    last = infos[-1]
    assert last["outcome"] == "goal" and last["is_success"] is True
    assert last["reward_terms"]["goal"] == 1000.0 and last["reward_terms"]["collision"] == 0.0
    assert all("outcome" not in info for info in infos[:-1])
    assert sum(rewards) == pytest.approx(1000.0 + 2.0 - 0.4, abs=0.1)  # goal + progress


def test_step_before_any_reset_is_an_error() -> None:
    env = NavEnv(LIDAR_CONFIG)
    try:
        with pytest.raises(BridgeError, match=r"call reset\(\) first"):
            env.step(STOP)
    finally:
        env.close()


# --- bad resets -------------------------------------------------------------------------------


@pytest.mark.parametrize(("options", "message"), [
    ({"start": START, "speed": 1.0}, r"reset options: unknown key 'speed'"),
    ({"start": [1.0, 2.0]}, r"reset options: start: \[1\.0, 2\.0\] is invalid"),
    ({"start": [0.0, math.nan, 0.0]}, r"reset options: start: .* is invalid"),
    ({"goal": [1.0, 2.0, 3.0]}, r"reset options: goal: \[1\.0, 2\.0, 3\.0\] is invalid"),
    ({"goal": [math.inf, 0.0]}, r"reset options: goal: .* is invalid"),
    ({"start": 5}, r"reset options: start: 5 is invalid"),
    ({"goal": ["a", "b"]}, r"reset options: goal: .* is invalid"),
])
def test_bad_reset_options_are_config_errors(arena: Path, options: dict[str, Any],
                                             message: str) -> None:
    env = arena_env(arena)
    try:
        with pytest.raises(ConfigError, match=message):
            env.reset(seed=0, options=options)
    finally:
        env.close()


def test_a_start_inside_an_obstacle_is_rejected(arena: Path) -> None:
    """A given start inside the crate is not redrawn: ``EpisodeRejected`` names it; a good
    reset works afterwards."""
    env = arena_env(arena)
    try:
        with pytest.raises(EpisodeRejected, match=r"start_pose: \(3\.000, 3\.000\)"):
            env.reset(seed=0, options={"start": [3.0, 3.0, 0.0], "goal": GOAL})
        with pytest.raises(EpisodeRejected, match=r"goal: \(-3\.000, 3\.000\)"):
            env.reset(options={"start": START, "goal": [-3.0, 3.0]})
        obs, info = env.reset(options={"start": START, "goal": GOAL})
        assert info["start"] == START and float(obs[BEAMS]) == pytest.approx(2.0, abs=1e-6)
    finally:
        env.close()


# --- recording --------------------------------------------------------------------------------

PER_STEP_TOPICS = ("/clock", "/ground_truth", "/odom", "/tf", "/scan")


def topic_counts(bag: Path) -> dict[str, int]:
    with AnyReader([bag]) as reader:
        counts = {c.topic: 0 for c in reader.connections}
        for conn, _, _ in reader.messages():
            counts[conn.topic] += 1
    return counts


def expected_counts(steps: int) -> dict[str, int]:
    """The bag of an episode of ``steps`` steps with the default topics (LiDAR, no depth)."""
    return {**dict.fromkeys(PER_STEP_TOPICS, steps + 1), "/cmd_vel": steps, "/goal_pose": 1,
            "/plan": 1, "/tf_static": 1, "/episode/facts": 1, "/episode/outcome": 1}


def test_recorded_episodes_are_bags_the_metrics_judge(arena: Path, tmp_path: Path) -> None:
    """Two recorded episodes: the run's config loads back equal, each bag holds exactly the
    episode's messages, and the metrics find the goal episode a success along a straight
    path. A second env recording into the same run appends and overwrites nothing."""
    record = {"record.enabled": True, "record.bags_dir": str(tmp_path), "record.run": "r1",
              "goal_tolerance_m": 0.1}
    env = arena_env(arena, **record)
    try:
        obs, _ = env.reset(seed=3, options={"start": START, "goal": GOAL})
        infos, _ = drive_to_goal(env, obs)
        goal_steps = len(infos)
        assert infos[-1]["outcome"] == "goal"
        env.reset(options={"start": NEAR_WALL, "goal": [-4.0, 0.0]})
        for crash_steps in range(1, 101):
            *_, terminated, truncated, info = env.step(np.array([1.0, 0.0]))
            if terminated or truncated:
                break
        assert info["outcome"] == "collision"
    finally:
        env.close()

    run = tmp_path / "r1"
    loaded = load_env_config(run / "config.yaml")
    config = env.unwrapped.config
    assert loaded == config and loaded.sim_params == config.sim_params
    assert loaded.goal_tolerance_m == 0.1 and loaded.record.run == "r1"
    bags = sorted(run.glob("episode_*"))
    assert [b.name for b in bags] == ["episode_0000", "episode_0001"]
    assert topic_counts(bags[0]) == expected_counts(goal_steps)
    assert topic_counts(bags[1]) == expected_counts(crash_steps)

    frame = compute(bags).frame
    assert list(frame["error"]) == ["", ""]
    assert list(frame["outcome"]) == ["goal", "collision"]
    assert list(frame["success"]) == [1.0, 0.0]
    straight = math.dist(START[:2], GOAL) - 0.1  # stops within the tolerance
    assert frame["path_length_m"].iloc[0] == pytest.approx(straight, rel=0.1)

    config_text = (run / "config.yaml").read_bytes()
    first_bag = (bags[0] / "metadata.yaml").read_bytes()
    again = arena_env(arena, **record, **{"reward.goal": 500.0})
    try:
        again.reset(seed=4, options={"start": START, "goal": GOAL})
        for _ in range(3):
            again.step(STOP)
        again.reset(options={"start": START, "goal": GOAL})  # ends the first one unfinished
        *_, info = again.step(STOP)
    finally:
        again.close()
    assert sorted(b.name for b in run.glob("episode_*")) == [
        "episode_0000", "episode_0001", "episode_0002", "episode_0003"]
    assert (run / "config.yaml").read_bytes() == config_text
    assert (bags[0] / "metadata.yaml").read_bytes() == first_bag
    assert load_env_config(run / "config-2.yaml").reward.goal == 500.0
    unfinished = expected_counts(3)
    del unfinished["/episode/outcome"]  # cut short by the next reset: no outcome
    assert topic_counts(run / "episode_0002") == unfinished


def test_a_rejected_reset_leaves_no_bag(arena: Path, tmp_path: Path) -> None:
    """A reset the simulator refuses records nothing: the next episode's bag is the first."""
    env = arena_env(arena, **{"record.enabled": True, "record.bags_dir": str(tmp_path),
                              "record.run": "r"})
    try:
        with pytest.raises(EpisodeRejected):
            env.reset(seed=0, options={"start": [3.0, 3.0, 0.0], "goal": GOAL})
        env.reset(options={"start": START, "goal": GOAL})
        env.step(STOP)
    finally:
        env.close()
    assert sorted(b.name for b in (tmp_path / "r").glob("episode_*")) == ["episode_0000"]
