"""The models: ``DepthGoalExtractor`` (a small CNN on the depth image beside the goal vector),
``new_model`` for every algorithm on the LiDAR env (``MlpPolicy``), the depth env
(``MultiInputPolicy`` with the extractor) and the vineyard's bare image (``CnnPolicy`` with
it), with the configured network sizes, each algorithm table entry's declared class and
off-policy flag, and ``load_model``'s round trip and errors."""

from __future__ import annotations

import importlib
import zipfile
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
import pytest
import torch
from agents_helpers import CONFIG, DEPTH_TD3, LIDAR_TD3, ROOT, TINY
from stable_baselines3.common.off_policy_algorithm import OffPolicyAlgorithm
from torch import nn

from pic4rl_agents.models.algorithm_table import ALGORITHM_TABLE
from pic4rl_agents.models.algorithms import (
    ALGORITHMS,
    AtomicSave,
    _policy,
    algorithm_class,
    new_model,
    load_model,
)
from pic4rl_agents.runs.config import load_run_config
from pic4rl_agents.runs.overrides import parse_overrides
from pic4rl_agents.training.envs import make_vec_env
from pic4rl_agents.models.action_noise import EpsilonGreedy
from pic4rl_agents.models.extractors import DepthGoalExtractor
from pic4rl_bridge.errors import ConfigError

VINEYARD = CONFIG / "env_vineyard_depth.yaml"  # a bare depth image, no goal vector
ALL = sorted(ALGORITHMS)  # the algorithm table's (sb3-contrib's TQC is in the rl extra)
ACTOR, CRITIC = [16, 8], [24]
CNN_CHANNELS, CNN_FEATURES = [4, 8], 12


def test_an_unknown_algorithm_is_refused() -> None:
    with pytest.raises(ConfigError, match=r"algorithm: 'nope' is not available; expected one of "
                                          + ", ".join(ALL) + "$"):
        algorithm_class("nope")


# --- the depth extractor ------------------------------------------------------------------------


@pytest.fixture(scope="module")
def envs() -> Iterator[dict[str, Any]]:
    """The in-process envs of the two TD3 training files (lidar: a Box of 40; depth: a Dict of
    a 1×30×40 uint8 image and the goal vector), vectorised as the trainer does."""
    made = {"lidar": make_vec_env(load_run_config([LIDAR_TD3]).env),
            "depth": make_vec_env(load_run_config([DEPTH_TD3]).env),
            "image": make_vec_env(load_run_config([VINEYARD]).env)}
    try:
        yield made
    finally:
        for env in made.values():
            env.close()


def test_the_depth_env_gives_an_image_and_a_goal_vector(envs: dict[str, Any]) -> None:
    space = envs["depth"].observation_space
    assert isinstance(space, gym.spaces.Dict) and set(space.spaces) == {"depth", "goal"}
    assert space["depth"].shape == (1, 30, 40) and space["depth"].dtype == np.uint8
    assert isinstance(envs["lidar"].observation_space, gym.spaces.Box)


def test_the_extractor_gives_cnn_features_and_the_goal_vector(envs: dict[str, Any]) -> None:
    space = envs["depth"].observation_space
    extractor = DepthGoalExtractor(space, channels=CNN_CHANNELS, cnn_features=CNN_FEATURES)
    goal_dim = space["goal"].shape[0]
    assert extractor.features_dim == CNN_FEATURES + goal_dim
    convs = [m for m in extractor.cnn if isinstance(m, nn.Conv2d)]
    assert [c.out_channels for c in convs] == CNN_CHANNELS
    assert [c.stride for c in convs] == [(2, 2)] * len(CNN_CHANNELS)
    space.seed(0)
    samples = [space.sample() for _ in range(5)]
    batch = {k: torch.as_tensor(np.stack([s[k] for s in samples])) for k in space.spaces}
    out = extractor(batch)
    assert out.shape == (5, CNN_FEATURES + goal_dim)
    assert torch.equal(out[:, CNN_FEATURES:], batch["goal"].float())  # the goal passes as it is
    assert torch.all(out[:, :CNN_FEATURES] >= 0)  # after the head's ReLU
    assert not torch.allclose(out[0, :CNN_FEATURES], out[1, :CNN_FEATURES])


def test_the_extractor_takes_a_bare_image_alone(envs: dict[str, Any]) -> None:
    space = envs["image"].observation_space
    assert isinstance(space, gym.spaces.Box) and len(space.shape) == 3
    extractor = DepthGoalExtractor(space, channels=CNN_CHANNELS, cnn_features=CNN_FEATURES)
    assert extractor.features_dim == CNN_FEATURES
    space.seed(0)
    batch = torch.as_tensor(np.stack([space.sample() for _ in range(3)]))
    out = extractor(batch)
    assert out.shape == (3, CNN_FEATURES) and torch.all(out >= 0)


def test_the_extractor_concatenates_every_vector_entry_by_name() -> None:
    space = gym.spaces.Dict({
        "depth": gym.spaces.Box(0, 255, (1, 24, 32), np.uint8),
        "zeta": gym.spaces.Box(-1, 1, (3,), np.float32),
        "alpha": gym.spaces.Box(-1, 1, (2,), np.float32),
    })
    extractor = DepthGoalExtractor(space, channels=[2], cnn_features=5)
    assert extractor.features_dim == 5 + 2 + 3
    batch = {"depth": torch.zeros(4, 1, 24, 32), "zeta": torch.full((4, 3), 0.5),
             "alpha": torch.full((4, 2), -0.25)}
    out = extractor(batch)
    assert out.shape == (4, 10)
    assert torch.equal(out[:, 5:7], batch["alpha"]) and torch.equal(out[:, 7:], batch["zeta"])


def test_the_cnn_extractor_only_where_an_observation_holds_an_image() -> None:
    """A Dict of vectors only (a new sensor's readings beside the goal) gets SB3's own
    multi-input policy, not the depth CNN, which needs an image entry."""
    config = train_config("td3")
    vectors = gym.spaces.Dict({"sonar": gym.spaces.Box(0, 1, (8,), np.float32),
                               "goal": gym.spaces.Box(-1, 1, (2,), np.float32)})
    policy, kwargs = _policy(config, vectors)
    assert policy == "MultiInputPolicy" and "features_extractor_class" not in kwargs
    with_image = gym.spaces.Dict({**vectors.spaces,
                                  "depth": gym.spaces.Box(0, 255, (1, 24, 32), np.uint8)})
    policy, kwargs = _policy(config, with_image)
    assert policy == "MultiInputPolicy" and kwargs["features_extractor_class"] is DepthGoalExtractor
    assert _policy(config, with_image["depth"])[0] == "CnnPolicy"
    assert _policy(config, vectors["sonar"])[0] == "MlpPolicy"


def test_every_image_entry_gets_its_own_cnn_depth_keeping_the_old_names() -> None:
    """Depth + memory + goal: two CNNs (depth's under ``cnn``/``head``, as saved models
    have them; memory's in ``more``), then the vector; memory alone takes ``cnn``."""
    space = gym.spaces.Dict({
        "memory": gym.spaces.Box(0, 255, (1, 32, 32), np.uint8),
        "depth": gym.spaces.Box(0, 255, (1, 24, 32), np.uint8),
        "goal": gym.spaces.Box(-1, 1, (4,), np.float32),
    })
    extractor = DepthGoalExtractor(space, channels=[2], cnn_features=5)
    assert extractor.image_keys == ["depth", "memory"] and extractor.features_dim == 5 + 5 + 4
    names = {name.split(".")[0] for name, _ in extractor.named_parameters()}
    assert names == {"cnn", "head", "more"}
    batch = {"memory": torch.zeros(2, 1, 32, 32), "depth": torch.ones(2, 1, 24, 32),
             "goal": torch.full((2, 4), 0.5)}
    out = extractor(batch)
    assert out.shape == (2, 14) and torch.equal(out[:, 10:], batch["goal"])
    with torch.no_grad():  # the memory's features are its own CNN's
        memory = extractor.more["memory"](batch["memory"])
    assert torch.equal(out[:, 5:10], memory)
    lidar = gym.spaces.Dict({"memory": space["memory"], "lidar": space["goal"]})
    alone = DepthGoalExtractor(lidar, channels=[2], cnn_features=5)
    assert alone.image_keys == ["memory"] and not len(alone.more)


# --- new_model --------------------------------------------------------------------------------


def train_config(algorithm: str, **extra: Any) -> Any:
    train = parse_overrides(TINY, flag="--hyperparams")
    train.update({"algorithm": algorithm, "policy.net_arch": ACTOR, "policy.critic_arch": CRITIC,
                  "policy.cnn_channels": CNN_CHANNELS, "policy.cnn_features": CNN_FEATURES,
                  "ppo.n_steps": 64, **extra})
    if not ALGORITHM_TABLE[algorithm].off_policy:
        train["epsilon.initial"] = 0.0
    return load_run_config([LIDAR_TD3], train=train).train


def linear_sizes(module: nn.Module) -> list[int]:
    return [m.out_features for m in module.modules() if isinstance(m, nn.Linear)]


def actor_critic_hidden(model: Any) -> tuple[list[int], list[int]]:
    """The hidden layer sizes of the actor's and the critic's heads."""
    policy = model.policy
    if not isinstance(model, OffPolicyAlgorithm):  # an actor-critic: a value network
        return (linear_sizes(policy.mlp_extractor.policy_net),
                linear_sizes(policy.mlp_extractor.value_net))
    critic = linear_sizes(policy.critic.q_networks[0])[:-1]  # the last layer: Q (quantiles)
    if hasattr(policy.actor, "latent_pi"):  # SAC, TQC: a Gaussian head on latent_pi
        return linear_sizes(policy.actor.latent_pi), critic
    return linear_sizes(policy.actor.mu)[:-1], critic  # DDPG, TD3: mu ends with the action


@pytest.mark.parametrize("sensor", ["lidar", "depth", "image"])
@pytest.mark.parametrize("algorithm", ALL)
def test_build_model_follows_the_config(envs: dict[str, Any], algorithm: str,
                                        sensor: str) -> None:
    env = envs[sensor]
    config = train_config(algorithm)
    model = new_model(config, env)
    assert isinstance(model, ALGORITHMS[algorithm])
    alias = {"lidar": "MlpPolicy", "depth": "MultiInputPolicy", "image": "CnnPolicy"}[sensor]
    assert isinstance(model.policy, model.policy_aliases[alias])
    assert actor_critic_hidden(model) == (ACTOR, CRITIC)
    assert model.learning_rate == config.learning_rate and model.gamma == config.gamma
    assert model.seed == config.seed and model.batch_size == 32
    extractors = [m for m in model.policy.modules() if isinstance(m, DepthGoalExtractor)]
    if sensor == "lidar":
        assert not extractors
    else:
        assert extractors
        goal_dim = 4 if sensor == "depth" else 0
        assert all(e.features_dim == CNN_FEATURES + goal_dim for e in extractors)
        assert all([c.out_channels for c in e.cnn if isinstance(c, nn.Conv2d)] == CNN_CHANNELS
                   for e in extractors)
    if not ALGORITHM_TABLE[algorithm].off_policy:
        assert model.n_steps == 64 and not isinstance(model, EpsilonGreedy)
    else:
        assert model.learning_starts == 50 and model.buffer_size == 5000
        assert isinstance(model, EpsilonGreedy) and model.epsilon_initial == 0.2
    noise = "action_noise" in ALGORITHM_TABLE[algorithm].kwargs
    assert (model.action_noise is not None) == noise
    obs = env.reset()
    action, _ = model.predict(obs, deterministic=True)
    assert action.shape == (1, 2) and np.all(np.abs(action) <= 1.0)


@pytest.mark.parametrize("name", list(ALGORITHM_TABLE))
def test_every_table_entry_builds_its_declared_class_and_off_policy_kind(
        envs: dict[str, Any], name: str) -> None:
    entry = ALGORITHM_TABLE[name]
    module, _, class_name = entry.cls.rpartition(".")
    declared = getattr(importlib.import_module(module), class_name)
    config = train_config(name)
    model = new_model(config, envs["lidar"])
    assert isinstance(model, declared) and type(model).__name__ == class_name
    assert isinstance(model, AtomicSave)
    assert isinstance(model, OffPolicyAlgorithm) == entry.off_policy == config.off_policy
    assert isinstance(model, EpsilonGreedy) == entry.off_policy


def test_td3_action_noise_has_the_configured_std(envs: dict[str, Any]) -> None:
    model = new_model(train_config("td3", action_noise_std=0.3), envs["lidar"])
    np.testing.assert_array_equal(model.action_noise._sigma, [0.3, 0.3])
    assert new_model(train_config("td3", action_noise_std=0.0), envs["lidar"]).action_noise \
        is None


@pytest.mark.parametrize("share", [False, True])
@pytest.mark.parametrize("algorithm", ["td3", "sac"])
def test_actor_and_critic_share_the_cnn_only_when_asked(envs: dict[str, Any], algorithm: str,
                                                        share: bool) -> None:
    model = new_model(train_config(algorithm, **{"policy.share_features_extractor": share}),
                        envs["depth"])
    actor, critic = model.policy.actor, model.policy.critic
    assert isinstance(actor.features_extractor, DepthGoalExtractor)
    assert (critic.features_extractor is actor.features_extractor) is share


def test_the_activation_follows_the_config(envs: dict[str, Any]) -> None:
    model = new_model(train_config("sac", **{"policy.activation": "tanh"}), envs["lidar"])
    kinds = {type(m) for m in model.policy.actor.latent_pi.modules()}
    assert nn.Tanh in kinds and nn.ReLU not in kinds


# --- load_model ---------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def saved_td3(envs: dict[str, Any], tmp_path_factory: pytest.TempPathFactory) -> Path:
    model = new_model(train_config("td3"), envs["lidar"])
    model.num_timesteps = 42
    path = tmp_path_factory.mktemp("models") / "td3.zip"
    model.save(path)
    return path


def test_a_saved_model_loads_back_the_same(envs: dict[str, Any], saved_td3: Path) -> None:
    model = load_model(saved_td3, "td3", env=envs["lidar"])
    assert isinstance(model, ALGORITHMS["td3"]) and model.num_timesteps == 42
    assert model.epsilon_initial == 0.2  # the schedule is saved with the model
    again = new_model(train_config("td3"), envs["lidar"])  # same seed: same initial weights
    for a, b in zip(model.policy.parameters(), again.policy.parameters()):
        assert torch.equal(a, b)
    bare = load_model(saved_td3, "td3")
    assert bare.observation_space == envs["lidar"].observation_space


def test_a_missing_model_file_is_named(tmp_path: Path) -> None:
    with pytest.raises(ConfigError, match=rf"{tmp_path / 'nope.zip'}: no such model file"):
        load_model(tmp_path / "nope.zip", "td3")
    with pytest.raises(ConfigError, match="no such model file"):
        load_model(tmp_path, "td3")  # a directory is no model file


def test_a_file_that_is_no_model_is_named(tmp_path: Path) -> None:
    bad = tmp_path / "model.zip"
    bad.write_text("not a zip")
    with pytest.raises(ConfigError, match=rf"{bad}: cannot load it as a td3 model"):
        load_model(bad, "td3")


def test_a_model_of_another_algorithm_is_refused_when_attached_to_an_env(
        envs: dict[str, Any], saved_td3: Path) -> None:
    with pytest.raises(ConfigError, match=rf"{saved_td3}: cannot load it as a sac model"):
        load_model(saved_td3, "sac", env=envs["lidar"])


@pytest.mark.parametrize("algorithm", ["ppo", "sac"])
def test_a_model_of_another_algorithm_is_refused(saved_td3: Path, algorithm: str) -> None:
    with pytest.raises(ConfigError, match=rf"{saved_td3}: cannot load it as a {algorithm}"):
        load_model(saved_td3, algorithm)


def test_a_depth_model_saved_before_the_sub_packages_loads_with_its_extractor() -> None:
    """SB3 pickles ``policy_kwargs`` by reference: the shipped depth checkpoints name
    ``pic4rl_agents.extractors.DepthGoalExtractor``, the path before ``models/`` existed."""
    model_zip = ROOT / "checkpoints" / "td3_depth" / "model.zip"
    assert b"pic4rl_agents.extractors" in zipfile.ZipFile(model_zip).read("data")
    model = load_model(model_zip, "td3")
    assert isinstance(model.policy.actor.features_extractor, DepthGoalExtractor)
