"""The SB3 algorithms by name, with ε-greedy on the off-policy ones, and their networks.

``build_model`` turns a ``TrainConfig`` into a ready SB3 model for an env: ``MlpPolicy`` on
vector observations (LiDAR), ``MultiInputPolicy`` with ``DepthGoalExtractor`` on Dict ones
(depth + goal), ``CnnPolicy`` with it on bare images (vineyard). ``load_model`` reads a
saved zip back with the same classes.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
import sb3_contrib
import stable_baselines3 as sb3
from stable_baselines3.common.base_class import BaseAlgorithm
from stable_baselines3.common.noise import NormalActionNoise
from stable_baselines3.common.save_util import load_from_zip_file
from torch import nn

from pic4rl_bridge.errors import ConfigError

from .config import TrainConfig
from .exploration import EpsilonGreedy
from .extractors import DepthGoalExtractor


class DDPG(EpsilonGreedy, sb3.DDPG):
    """SB3's DDPG with the paper's ε-greedy exploration."""


class TD3(EpsilonGreedy, sb3.TD3):
    """SB3's TD3 with the paper's ε-greedy exploration."""


class SAC(EpsilonGreedy, sb3.SAC):
    """SB3's SAC with the paper's ε-greedy exploration."""


class TQC(EpsilonGreedy, sb3_contrib.TQC):
    """sb3-contrib's TQC with the paper's ε-greedy exploration."""


PPO = sb3.PPO

ALGORITHMS: dict[str, type[BaseAlgorithm]] = {"ddpg": DDPG, "td3": TD3, "sac": SAC, "tqc": TQC,
                                              "ppo": PPO}

_ACTIVATIONS: dict[str, type[nn.Module]] = {"relu": nn.ReLU, "tanh": nn.Tanh, "elu": nn.ELU}


def algorithm_class(name: str) -> type[BaseAlgorithm]:
    if name not in ALGORITHMS:
        raise ConfigError(f"algorithm: {name!r} is not available; expected one of "
                          f"{', '.join(sorted(ALGORITHMS))}")
    return ALGORITHMS[name]


def _policy(config: TrainConfig, observation_space: gym.Space) -> tuple[str, dict[str, Any]]:
    p = config.policy
    critic = "vf" if config.algorithm == "ppo" else "qf"
    kwargs: dict[str, Any] = {"net_arch": {"pi": list(p.net_arch), critic: list(p.critic_arch)},
                              "activation_fn": _ACTIVATIONS[p.activation]}
    if config.algorithm == "ppo":
        kwargs["log_std_init"] = p.log_std_init
    image = isinstance(observation_space, gym.spaces.Box) and len(observation_space.shape) == 3
    if isinstance(observation_space, gym.spaces.Dict) or image:
        kwargs["features_extractor_class"] = DepthGoalExtractor
        kwargs["features_extractor_kwargs"] = {"channels": list(p.cnn_channels),
                                               "cnn_features": p.cnn_features}
        if config.off_policy:
            kwargs["share_features_extractor"] = p.share_features_extractor
        return ("CnnPolicy" if image else "MultiInputPolicy"), kwargs
    return "MlpPolicy", kwargs


def build_model(config: TrainConfig, env: Any, *, tensorboard_log: str | None = None,
                verbose: int = 0) -> BaseAlgorithm:
    """A new model of ``config.algorithm`` on ``env`` (a VecEnv), seeded with ``config.seed``."""
    cls = algorithm_class(config.algorithm)
    policy, policy_kwargs = _policy(config, env.observation_space)
    common: dict[str, Any] = {"learning_rate": config.learning_rate, "gamma": config.gamma,
                              "seed": config.seed, "device": config.device,
                              "policy_kwargs": policy_kwargs, "verbose": verbose,
                              "tensorboard_log": tensorboard_log}
    if config.off_policy:
        common.update(buffer_size=config.buffer_size, batch_size=config.batch_size,
                      learning_starts=config.learning_starts, tau=config.tau,
                      train_freq=config.train_freq, gradient_steps=config.gradient_steps)
        if config.algorithm in ("sac", "tqc"):
            ent = config.ent_coef
            common["ent_coef"] = ent if ent.startswith("auto") else float(ent)
        if config.algorithm in ("ddpg", "td3") and config.action_noise_std > 0:
            n = int(np.prod(env.action_space.shape))
            common["action_noise"] = NormalActionNoise(np.zeros(n),
                                                       np.full(n, config.action_noise_std))
    else:
        ppo = config.ppo
        common.update(batch_size=config.batch_size, n_steps=ppo.n_steps, n_epochs=ppo.n_epochs,
                      ent_coef=ppo.ent_coef, gae_lambda=ppo.gae_lambda,
                      clip_range=ppo.clip_range)
    model = cls(policy, env, **common)
    if isinstance(model, EpsilonGreedy):
        e = config.epsilon
        model.set_epsilon(e.initial, e.decay, e.min)
    return model


def load_model(path: str | Path, algorithm: str, *, env: Any = None,
               device: str = "cpu") -> BaseAlgorithm:
    """A saved model (SB3 zip) of ``algorithm``, attached to ``env`` when given."""
    path = Path(path)
    if not path.is_file():
        raise ConfigError(f"{path}: no such model file (expected an SB3 .zip)")
    cls = algorithm_class(algorithm)
    try:
        data, _, _ = load_from_zip_file(path, load_data=True, device="cpu")
    except (ValueError, KeyError, RuntimeError, OSError) as err:  # not an SB3 zip
        raise ConfigError(f"{path}: cannot load it as a {algorithm} model: {err}") from err
    policy = (data or {}).get("policy_class")
    known = tuple(cls.policy_aliases.values())
    if isinstance(policy, type) and not issubclass(policy, known):
        raise ConfigError(f"{path}: cannot load it as a {algorithm} model: it holds a "
                          f"{policy.__name__}, not one of {', '.join(k.__name__ for k in known)}"
                          "; pass the algorithm it was trained with")
    try:
        return cls.load(path, env=env, device=device)
    except (ValueError, KeyError, RuntimeError, TypeError, AttributeError) as err:
        raise ConfigError(f"{path}: cannot load it as a {algorithm} model: {err}") from err
