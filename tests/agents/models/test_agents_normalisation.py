"""The normalisation round trip: an agent trained with ``normalize_observations`` and a
``reward_scale`` is tested on the observations it learned from. For a short run of each
sensor's recipe, the env ``pic4rl-test`` builds from the run (``resolve_agents``, then
``NavEnv`` and ``Policy`` as ``drive_agent`` does) and the trainer's env (``make_vec_env`` from
the run's config.yaml, as ``Trainer.run`` builds it) drive the same pair with the agent's
actions: every observation is equal, scaled to [0, 1] (ranges, goal distance, depth once SB3
scales the image) or [-1, 1] (goal angle, last action), the agent acts the same on both, and
the learner's reward is ``reward_scale`` times the env's (what the bags keep).
"""

from __future__ import annotations

import contextlib
import io
import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import torch as th
from agents_helpers import DEPTH_TD3, LIDAR_TD3, SHORT_EPISODES, TINY
from stable_baselines3.common.preprocessing import preprocess_obs

from pic4rl_agents.testing import policies, tester

from pic4rl_agents.testing import plan as testplan

from pic4rl_agents.training import train
from pic4rl_agents.runs.config import load_run_config
from pic4rl_agents.training.envs import make_vec_env
from pic4rl_agents.launch.rosargs import split_ros_args
from pic4rl_bridge.env import NavEnv
from pic4rl_bridge.perception.observations import NORMALIZED_GOAL_DISTANCE_M

REWARD_SCALE = 0.01
STEPS = 100  # 50 of them after the warm-up: the networks have moved from their init
COMPARED_STEPS = 30


@pytest.fixture(scope="module", params=[LIDAR_TD3, DEPTH_TD3], ids=lambda p: p.stem)
def normalised_run(request: pytest.FixtureRequest,
                   tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A short in-process run of the recipe with normalised observations and scaled rewards."""
    runs = tmp_path_factory.mktemp("runs")
    err = io.StringIO()
    with contextlib.redirect_stderr(err):
        code = train.main([
            "--hyperparams", *TINY, f"reward_scale:{REWARD_SCALE}",
            "checkpoint.interval_steps:0", "eval.interval_steps:0", "eval.interval_s:0",
            "--env-kwargs", *SHORT_EPISODES, "normalize_observations:true",
            "-n", str(STEPS), "--run", "normalised", "--no-progress",
            "--ros-args", "--params-file", str(request.param), "-p", f"runs_dir:={runs}"])
    assert code == 0, err.getvalue()
    return runs / "normalised"


def agent_as_tested(run_dir: Path, bags: Path) -> testplan.AgentSpec:
    """The agent as ``pic4rl-test --agent RUN_DIR`` resolves it (its test env included)."""
    plain, ros = split_ros_args(["--agent", str(run_dir), "--bags", str(bags), "--run", "rt",
                                 "--no-progress"])
    plan = tester.build_plan(tester.build_parser().parse_args(plain), ros)
    [spec] = testplan.resolve_agents(plan, plan.bags_dir / "rt")
    return spec


def single(vec_obs: Any) -> Any:
    """Env 0's observation of a vector env's batch."""
    return ({k: v[0] for k, v in vec_obs.items()} if isinstance(vec_obs, dict)
            else vec_obs[0])


def assert_equal_obs(a: Any, b: Any) -> None:
    if isinstance(a, dict):
        assert a.keys() == b.keys()
        for key in a:
            np.testing.assert_array_equal(a[key], b[key], err_msg=key)
    else:
        np.testing.assert_array_equal(a, b)


def assert_scaled(obs: Any, env: NavEnv) -> None:
    """What the policy network sees (after SB3's preprocessing: a uint8 image / 255) lies in
    [0, 1] for ranges, depths and the goal distance, and in [-1, 1] for the goal angle and
    the last action."""
    space = env.observation_space
    assert space.contains(obs)
    batch = ({k: th.as_tensor(v[None]) for k, v in obs.items()} if isinstance(obs, dict)
             else th.as_tensor(obs[None]))
    seen = preprocess_obs(batch, space)
    goal = (seen["goal"] if isinstance(seen, dict) else seen[:, -4:])[0].numpy()
    unit = ([seen["depth"]] if isinstance(seen, dict) else [seen[:, :-4]]) + [goal[:1]]
    for values in unit:
        assert float(values.min()) >= 0.0 and float(values.max()) <= 1.0
    assert np.all(np.abs(goal[1:]) <= 1.0)


def test_the_tester_sees_and_does_what_the_trainer_did(normalised_run: Path,
                                                      tmp_path: Path) -> None:
    run = load_run_config([normalised_run / "config.yaml"])
    assert run.env.normalize_observations and run.train.reward_scale == REWARD_SCALE
    spec = agent_as_tested(normalised_run, tmp_path / "bags")
    assert spec.run.env.normalize_observations

    trainer_env = make_vec_env(run.env, seed=run.train.seed,
                               reward_scale=run.train.reward_scale,
                               curriculum=run.train.curriculum, vec_env=run.train.vec_env)
    test_env = NavEnv(spec.run.env)
    try:
        policy = policies.Driver(spec, test_env)  # refuses another observation space
        assert trainer_env.observation_space == test_env.observation_space
        obs, info = test_env.reset(seed=0)  # the first of the paper's test pairs
        # The trainer's env on that pair: reset through its wrappers (the monitor's episode
        # starts), then its NavEnv put on the pair (a curriculum's reset would draw one).
        trainer_env.reset()
        inner = trainer_env.envs[0].unwrapped
        trained_obs, trained_info = inner.reset(seed=run.train.seed, options={
            "start": info["start"], "goal": info["goal"], "seed": info["seed"]})
        assert (trained_info["start"], trained_info["goal"]) == (info["start"], info["goal"])
        assert_equal_obs(obs, trained_obs)
        distance = math.dist(info["start"][:2], info["goal"])
        goal = obs["goal"] if isinstance(obs, dict) else obs[-4:]
        assert goal[0] == pytest.approx(distance / NORMALIZED_GOAL_DISTANCE_M, abs=1e-6)

        for _ in range(COMPARED_STEPS):
            assert_scaled(obs, test_env)
            action = policy.act(obs, test_env)
            batch_obs = ({k: v[None] for k, v in trained_obs.items()}
                         if isinstance(trained_obs, dict) else trained_obs[None])
            trained_action, _ = policy.model.predict(batch_obs, deterministic=True)
            np.testing.assert_array_equal(trained_action[0], action)
            obs, reward, terminated, truncated, info = test_env.step(action)
            vec_obs, vec_reward, vec_done, vec_info = trainer_env.step(trained_action)
            trained_obs = (vec_info[0]["terminal_observation"] if vec_done[0]
                           else single(vec_obs))
            assert_equal_obs(obs, trained_obs)
            assert vec_reward[0] == pytest.approx(REWARD_SCALE * reward, rel=1e-5, abs=1e-9)
            assert bool(vec_done[0]) == (terminated or truncated)
            if terminated or truncated:
                break
    finally:
        trainer_env.close()
        test_env.close()
