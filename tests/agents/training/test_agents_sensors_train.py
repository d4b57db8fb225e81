"""An agent of two sensors (issue 40 item 1): a short real SB3 run in process on goToPose with
``sensors: [lidar, depth]`` trains a ``MultiInputPolicy`` (the CNN on the depth image, the LiDAR
sectors and goal beside it), saves a model that loads and drives, and a config that carries the
list; a test env that observes other sensors is refused in one line."""

from __future__ import annotations

import contextlib
import io
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest
from agents_helpers import DEPTH_TD3, SHORT_EPISODES, TINY

from pic4rl_agents.launch.rosargs import split_ros_args
from pic4rl_agents.models.algorithms import load_model
from pic4rl_agents.models.extractors import DepthGoalExtractor
from pic4rl_agents.runs.config import load_run_config
from pic4rl_agents.testing import plan as testplan
from pic4rl_agents.testing import tester
from pic4rl_agents.training import train
from pic4rl_bridge.env import NavEnv
from pic4rl_bridge.errors import ConfigError

STEPS = 200  # 150 of them after TINY's warm-up (learning_starts 50): 150 gradient steps


@pytest.fixture(scope="module")
def fused_run(tmp_path_factory: pytest.TempPathFactory) -> Path:
    runs = tmp_path_factory.mktemp("runs")
    err = io.StringIO()
    with contextlib.redirect_stderr(err):
        code = train.main([
            "--hyperparams", *TINY, "checkpoint.interval_steps:0", "eval.interval_steps:0",
            "eval.interval_s:0", "--env-kwargs", *SHORT_EPISODES, "sensors:[lidar,depth]",
            "-n", str(STEPS), "--no-progress",
            "--ros-args", "--params-file", str(DEPTH_TD3), "-p", f"runs_dir:={runs}"])
    assert code == 0, err.getvalue()
    [run] = runs.iterdir()
    return run


def test_a_lidar_and_depth_agent_trains_saves_and_loads(fused_run: Path) -> None:
    run = load_run_config([fused_run / "config.yaml"])
    assert run.origin.startswith("sensor lidar+depth, from ")
    assert run.env.observed == ("lidar", "depth") and run.env.depth.obs_width == 40
    model = load_model(fused_run / "model.zip", "td3")
    assert model.num_timesteps >= STEPS and model._n_updates >= 100  # gradient steps taken
    space = model.observation_space
    assert isinstance(space, gym.spaces.Dict) and set(space) == {"lidar", "depth", "goal"}
    extractor = model.policy.actor.features_extractor
    assert isinstance(extractor, DepthGoalExtractor)
    assert extractor.image_keys == ["depth"] and extractor.vector_keys == ["goal", "lidar"]
    assert extractor.features_dim == 64 + 4 + 36  # policy.cnn_features of the recipe
    env = NavEnv(run.env)
    try:
        obs, _ = env.reset(seed=2)
        action, _ = model.predict(obs, deterministic=True)
        assert env.action_space.contains(np.asarray(action, np.float32))
        env.step(action)
    finally:
        env.close()


def test_a_test_env_of_other_sensors_is_refused_in_one_line(fused_run: Path,
                                                           tmp_path: Path) -> None:
    plain, ros = split_ros_args(["--agent", str(fused_run), "--bags", str(tmp_path), "--run",
                                 "rt", "--no-progress", "--env-kwargs", "sensor:lidar",
                                 "sensors:[lidar]"])
    plan = tester.build_plan(tester.build_parser().parse_args(plain), ros)
    with pytest.raises(ConfigError) as err:
        testplan.resolve_agents(plan, plan.bags_dir / "rt")
    message = str(err.value)
    assert "\n" not in message and "sensors:" in message
    assert "['lidar']" in message and "['lidar', 'depth']" in message
