"""The paper's ε-greedy exploration: ε_t = max(min, initial · decay^t) with t the env steps
since the warm-up, on real SB3 models built by ``new_model`` on the in-process LiDAR env:
no ε during the warm-up, the schedule after it, uniform random actions when ε is 1, exactly
the algorithm's own exploration when ε is 0, and ``rollout/epsilon`` in a run's progress.csv."""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any

import numpy as np
import pandas as pd
import pytest
import torch
from agents_helpers import LIDAR_TD3, TINY, TrainedRun
from stable_baselines3.common.logger import configure

from pic4rl_agents.models.algorithm_table import ALGORITHM_TABLE
from pic4rl_agents.models.algorithms import ALGORITHMS, new_model
from pic4rl_agents.runs.config import load_run_config
from pic4rl_agents.runs.overrides import parse_overrides
from pic4rl_agents.training.envs import make_vec_env
from pic4rl_agents.models.action_noise import EpsilonGreedy, epsilon_at

OFF_POLICY = sorted(name for name in ALGORITHMS if ALGORITHM_TABLE[name].off_policy)
LEARNING_STARTS = 100
SAMPLES = 1000


# --- the schedule alone -------------------------------------------------------------------------


@pytest.mark.parametrize(("step", "initial", "decay", "minimum"), [
    (0, 0.2, 0.99995, 0.01), (1, 0.2, 0.99995, 0.01), (14_000, 0.2, 0.99995, 0.01),
    (10, 1.0, 0.5, 0.0), (3, 0.8, 0.9, 0.1), (0, 1.0, 1.0, 0.0), (10**6, 0.5, 1.0, 0.0),
])
def test_epsilon_follows_the_formula(step: int, initial: float, decay: float,
                                     minimum: float) -> None:
    assert epsilon_at(step, initial, decay, minimum) == pytest.approx(
        max(minimum, initial * decay**step), rel=1e-12)


def test_epsilon_halves_about_every_14k_steps_with_the_shipped_decay() -> None:
    """config/train_*.yaml: 0.2 · 0.99995^t (the comment there: halves every ~14k steps)."""
    assert epsilon_at(13_863, 0.2, 0.99995, 0.01) == pytest.approx(0.1, rel=1e-3)


def test_epsilon_stops_at_its_floor_and_never_rises() -> None:
    values = [epsilon_at(t, 0.5, 0.9, 0.05) for t in range(200)]
    assert values[0] == 0.5
    assert all(a >= b for a, b in zip(values, values[1:]))
    assert min(values) == 0.05 and values[-1] == 0.05
    assert values[10] == pytest.approx(0.5 * 0.9**10)


def test_epsilon_is_zero_when_disabled_even_with_a_floor() -> None:
    assert epsilon_at(0, 0.0, 0.9, 0.3) == 0.0
    assert epsilon_at(1000, 0.0, 1.0, 1.0) == 0.0


def test_a_negative_step_counts_as_the_first() -> None:
    assert epsilon_at(-5, 0.3, 0.5, 0.0) == 0.3


# --- on real models -----------------------------------------------------------------------------


@pytest.fixture(scope="module")
def lidar_env() -> Iterator[Any]:
    """The in-process env of config/train_goto_lidar_td3.yaml, vectorised as the trainer does."""
    env = make_vec_env(load_run_config([LIDAR_TD3]).env, seed=0)
    try:
        yield env
    finally:
        env.close()


def make_model(env: Any, algorithm: str, **epsilon: float) -> Any:
    """A tiny ``algorithm`` model on ``env`` with the given ``epsilon.*`` values, its last
    observation set and a logger without output, ready for ``_sample_action``."""
    train = parse_overrides(TINY, flag="--hyperparams")
    train.update({"algorithm": algorithm, "learning_starts": LEARNING_STARTS,
                  **{f"epsilon.{k}": v for k, v in epsilon.items()}})
    model = new_model(load_run_config([LIDAR_TD3], train=train).train, env)
    model._last_obs = env.reset()
    model.set_logger(configure(None, []))
    return model


def sample(model: Any, n: int, *, at_step: int) -> tuple[np.ndarray, np.ndarray]:
    """``n`` exploratory actions (and their buffer versions) with the model at ``at_step``."""
    model.num_timesteps = at_step
    pairs = [model._sample_action(model.learning_starts, model.action_noise, 1)
             for _ in range(n)]
    return (np.concatenate([a for a, _ in pairs]), np.concatenate([b for _, b in pairs]))


def test_the_env_acts_in_the_normalised_box(lidar_env: Any) -> None:
    """The assertions below read actions as normalised: [-1, 1] in each dimension."""
    space = lidar_env.action_space
    assert space.shape == (2,)
    assert np.all(space.low == -1.0) and np.all(space.high == 1.0)


@pytest.mark.parametrize("algorithm", OFF_POLICY)
def test_current_epsilon_is_zero_in_the_warm_up_then_follows_the_schedule(
        lidar_env: Any, algorithm: str) -> None:
    model = make_model(lidar_env, algorithm, initial=0.6, decay=0.99, min=0.05)
    assert isinstance(model, EpsilonGreedy)
    assert (model.epsilon_initial, model.epsilon_decay, model.epsilon_min) == (0.6, 0.99, 0.05)
    for steps in (0, 1, LEARNING_STARTS - 1):
        model.num_timesteps = steps
        assert model.current_epsilon() == 0.0
    for steps in (LEARNING_STARTS, LEARNING_STARTS + 1, LEARNING_STARTS + 50, 10_000):
        model.num_timesteps = steps
        expected = max(0.05, 0.6 * 0.99 ** (steps - LEARNING_STARTS))
        assert model.current_epsilon() == pytest.approx(expected, rel=1e-12)
    model.num_timesteps = LEARNING_STARTS
    assert model.current_epsilon() == 0.6


@pytest.mark.parametrize("algorithm", OFF_POLICY)
def test_with_epsilon_one_every_action_is_a_uniform_random_one(lidar_env: Any,
                                                               algorithm: str) -> None:
    """ε = 1 (no decay) after the warm-up: each action is the action space's own uniform
    sample (the very same draws), spread over [-1, 1] with mean 0 and std 1/√3, unlike the
    policy's; the replay buffer gets the same actions (scaled, here the identity)."""
    model = make_model(lidar_env, algorithm, initial=1.0, decay=1.0, min=0.0)
    model.action_space.seed(123)
    expected = np.array([model.action_space.sample() for _ in range(SAMPLES)])
    model.action_space.seed(123)
    actions, buffer = sample(model, SAMPLES, at_step=LEARNING_STARTS + 500)
    np.testing.assert_array_equal(actions, expected)
    np.testing.assert_allclose(buffer, model.policy.scale_action(actions), atol=1e-7)
    assert model.logger.name_to_value["rollout/epsilon"] == 1.0
    assert np.all(np.abs(actions) <= 1.0)
    assert np.all(np.abs(actions.mean(axis=0)) < 0.08)
    assert np.all(np.abs(actions.std(axis=0) - 1 / np.sqrt(3)) < 0.04)
    assert np.all(actions.min(axis=0) < -0.95) and np.all(actions.max(axis=0) > 0.95)
    greedy, _ = model.predict(model._last_obs, deterministic=True)
    assert not np.any(np.all(np.isclose(actions, greedy, atol=1e-3), axis=1))


@pytest.mark.parametrize("algorithm", OFF_POLICY)
def test_with_epsilon_zero_actions_are_the_algorithms_own(lidar_env: Any,
                                                          algorithm: str) -> None:
    """ε = 0: exactly SB3's exploration (policy plus noise for DDPG/TD3, the stochastic
    policy for SAC/TQC) for the same random state; nothing is replaced."""
    model = make_model(lidar_env, algorithm, initial=0.0)
    model.num_timesteps = LEARNING_STARTS + 10
    base = super(EpsilonGreedy, model)._sample_action  # SB3's OffPolicyAlgorithm's
    for seed in range(20):
        np.random.seed(seed)
        torch.manual_seed(seed)
        ours = model._sample_action(model.learning_starts, model.action_noise, 1)
        np.random.seed(seed)
        torch.manual_seed(seed)
        theirs = base(model.learning_starts, model.action_noise, 1)
        np.testing.assert_array_equal(ours[0], theirs[0])
        np.testing.assert_array_equal(ours[1], theirs[1])
    assert model.logger.name_to_value["rollout/epsilon"] == 0.0


def test_td3_exploration_without_epsilon_stays_near_the_policy(lidar_env: Any) -> None:
    """The counterpart of the uniform test: TD3's own exploration is its policy plus
    N(0, 0.2) noise (action_noise_std of the shipped file), far narrower than uniform."""
    model = make_model(lidar_env, "td3", initial=0.0)
    greedy, _ = model.predict(model._last_obs, deterministic=True)
    actions, _ = sample(model, SAMPLES, at_step=LEARNING_STARTS + 500)
    assert np.all(actions.std(axis=0) < 0.3)
    assert np.all(np.abs(np.median(actions, axis=0) - greedy[0]) < 0.1)


def test_epsilon_replaces_about_that_share_of_actions_and_keeps_the_rest(
        lidar_env: Any) -> None:
    """ε = 0.5 without action noise: about half the actions are random; the others are the
    deterministic policy's, untouched."""
    model = make_model(lidar_env, "td3", initial=0.5, decay=1.0, min=0.0)
    model.action_noise = None
    greedy, _ = model.predict(model._last_obs, deterministic=True)
    np.random.seed(0)
    actions, _ = sample(model, SAMPLES, at_step=LEARNING_STARTS)
    kept = np.all(actions == greedy, axis=1)
    assert 0.4 < 1 - kept.mean() < 0.6
    assert model.logger.name_to_value["rollout/epsilon"] == 0.5


def test_the_warm_up_is_uniform_whatever_epsilon(lidar_env: Any) -> None:
    model = make_model(lidar_env, "td3", initial=0.0)
    model.action_noise = None
    actions, _ = sample(model, 300, at_step=LEARNING_STARTS - 1)
    assert np.all(actions.std(axis=0) > 0.45)
    assert model.logger.name_to_value["rollout/epsilon"] == 0.0


def test_ppo_has_no_epsilon(lidar_env: Any) -> None:
    train = parse_overrides(TINY, flag="--hyperparams")
    train.update({"algorithm": "ppo", "epsilon.initial": 0.0, "ppo.n_steps": 64})
    model = new_model(load_run_config([LIDAR_TD3], train=train).train, lidar_env)
    assert not isinstance(model, EpsilonGreedy)


# --- in a training run --------------------------------------------------------------------------


def test_a_training_run_logs_epsilon_along_the_schedule(trained_run: TrainedRun) -> None:
    """The session's 300-step TD3 run (learning_starts 50, the shipped ε: 0.2 · 0.99995^t,
    floor 0.01) logs ``rollout/epsilon`` in logs/0/progress.csv: at each logged step the ε of
    the last action sampled before it."""
    assert trained_run.code == 0, trained_run.stderr
    progress = pd.read_csv(trained_run.run_dir / "logs" / "0" / "progress.csv")
    assert "rollout/epsilon" in progress.columns
    rows = progress.dropna(subset=["rollout/epsilon"])
    assert len(rows) >= 2
    for steps, eps in zip(rows["time/total_timesteps"], rows["rollout/epsilon"]):
        since = int(steps) - 50
        assert since > 0
        assert epsilon_at(since, 0.2, 0.99995, 0.01) - 1e-12 <= eps
        assert eps <= epsilon_at(since - 1, 0.2, 0.99995, 0.01) + 1e-12
        assert 0.19 < eps < 0.2
