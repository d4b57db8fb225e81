"""goToPose from several sensors at once (issue 40 item 1): ``sensors: [lidar, depth]`` gives a
Dict with each sensor's part as its one-sensor env gives it, beside ``goal``; ``sensors:
[lidar]`` is ``sensor: lidar`` (today's flat vector); bad lists are refused in one line; an
agent's settings cover every sensor it observes, and another sensor list is a conflict."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
import pytest

from pic4rl_bridge.config import EnvConfig, agent_conflicts, agent_keys
from pic4rl_bridge.env import NavEnv
from pic4rl_bridge.errors import ConfigError
from pic4rl_bridge.settings.tasks import EnvId, GoToPoseReward, TaskSpec
from pic4rl_bridge.tasks.goto import GoToPoseSensors

CONFIG = Path(__file__).resolve().parents[3] / "config" / "env_goto_lidar.yaml"
SIM = {"depth.enabled": True, "depth.width": 40, "depth.height": 30}
FUSED = {"sensors": ["lidar", "depth"], "depth.obs_width": 20, "depth.obs_height": 15}


def _episode(overrides: dict[str, Any], steps: int = 6) -> tuple[gym.Space[Any], list[Any]]:
    """The space and each observation of one seeded episode under fixed random actions."""
    env = NavEnv(str(CONFIG), sim=SIM, overrides={**FUSED, **overrides,
                                                   "episode_max_steps": steps})
    rng = np.random.default_rng(5)
    try:
        obs, _ = env.reset(seed=11)
        seen = [obs]
        for _ in range(steps - 1):
            obs, _, terminated, truncated, _ = env.step(
                rng.uniform(-1, 1, env.action_space.shape).astype(np.float32))
            seen.append(obs)
            if terminated or truncated:
                break
        return env.observation_space, seen
    finally:
        env.close()


def test_lidar_and_depth_give_a_dict_of_each_sensors_own_part() -> None:
    space, fused = _episode({})
    assert isinstance(space, gym.spaces.Dict) and set(space) == {"lidar", "depth", "goal"}
    assert space["lidar"].shape == (36,) and space["depth"].shape == (1, 15, 20)
    assert space["depth"].dtype == np.uint8 and space["goal"].shape == (4,)
    _, lidar = _episode({"sensors": []})
    _, depth = _episode({"sensors": [], "sensor": "depth"})
    assert len(fused) == len(lidar) == len(depth) >= 5
    for i, (f, v, d) in enumerate(zip(fused, lidar, depth)):
        assert space.contains(f), f"step {i} outside the space"
        np.testing.assert_array_equal(f["lidar"], v[:36], err_msg=f"lidar at step {i}")
        np.testing.assert_array_equal(f["goal"], v[36:], err_msg=f"goal at step {i}")
        np.testing.assert_array_equal(f["depth"], d["depth"], err_msg=f"depth at step {i}")
    assert len({f["depth"].tobytes() for f in fused}) > 1  # the camera sees the robot move


def test_one_sensor_in_the_list_is_todays_observation() -> None:
    listed_space, listed = _episode({"sensors": ["lidar"]})
    plain_space, plain = _episode({"sensors": []})
    assert listed_space == plain_space and isinstance(plain_space, gym.spaces.Box)
    for a, b in zip(listed, plain, strict=True):
        np.testing.assert_array_equal(a, b)


def test_normalised_history_and_memory_apply_to_the_lidar_part() -> None:
    space, fused = _episode({"normalize_observations": True, "lidar.history": 2,
                             "memory.enabled": True})
    assert set(space) == {"memory", "lidar", "depth", "goal"}
    assert space["lidar"].shape == (72,) and space["lidar"].high.max() == 1.0
    assert all(space.contains(o) for o in fused)
    np.testing.assert_array_equal(fused[0]["lidar"][:36], fused[0]["lidar"][36:])


@pytest.mark.parametrize(("params", "named"), [
    ({"sensors": ["lidar", "lidar"]}, "sensors"),
    ({"sensors": ["lidar", "radar"]}, "sensors"),  # no such sensor
    ({"sensors": ["depth"]}, "sensors"),  # sensor (lidar by default) must be among them
])
def test_a_bad_sensor_list_is_refused_in_one_line(params: dict[str, Any], named: str) -> None:
    with pytest.raises(ConfigError) as err:
        EnvConfig(**params)
    assert named in str(err.value) and "\n" not in str(err.value)


def test_an_agents_settings_cover_every_sensor_it_observes() -> None:
    fused = EnvConfig(sensors=("lidar", "depth"))
    keys = agent_keys(fused)
    assert "lidar.sectors" in keys and "depth.obs_width" in keys
    assert agent_conflicts(fused, EnvConfig()) == [
        ("sensors", ["lidar", "depth"], ["lidar"])]
    assert agent_conflicts(EnvConfig(), EnvConfig(sensors=("lidar",))) == []
    assert agent_conflicts(fused, EnvConfig(sensors=("lidar", "depth"), sensor="depth")) == []
    assert fused.sensor_label == "lidar+depth" and EnvConfig().sensor_label == "lidar"


def test_the_task_needs_each_sensors_reading() -> None:
    env = NavEnv(str(CONFIG), sim=SIM, overrides=FUSED)
    try:
        assert isinstance(env.task, GoToPoseSensors)
        assert {"goal", "scan", "depth"} <= env.task.required
    finally:
        env.close()


def test_the_registered_id_observes_both_and_an_entry_names_only_its_tasks_sensors() -> None:
    env = gym.make("pic4rl/GoToPoseLidarDepth-v0",
                   config=str(CONFIG.with_name("env_goto_lidar_depth.yaml")))
    try:
        assert env.unwrapped.config.observed == ("lidar", "depth")
        assert set(env.observation_space) == {"lidar", "depth", "goal"}
    finally:
        env.close()
    with pytest.raises(ConfigError, match="'sonar'"):
        TaskSpec("toy", (EnvId("pic4rl/Toy-v0", "lidar", sensors=("lidar", "sonar")),),
                 sensors=("lidar",), reward=GoToPoseReward, build="pic4rl_bridge.tasks.goto:build")
