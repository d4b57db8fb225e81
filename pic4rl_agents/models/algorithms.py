"""The SB3 classes of the algorithm table (``pic4rl_agents.models.algorithm_table``), with
atomic saves and ε-greedy on the off-policy ones, and their networks.

``new_model`` turns a ``TrainConfig`` into a ready SB3 model for an env: ``MlpPolicy`` on
vector observations (LiDAR), ``MultiInputPolicy`` with ``DepthGoalExtractor`` on Dict ones
holding an image (depth + goal; SB3's own extractor on a Dict of vectors), ``CnnPolicy`` with
it on bare images (vineyard). ``load_model`` reads a
saved zip back with the same classes.
"""

from __future__ import annotations

import importlib
from collections.abc import Callable
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
from stable_baselines3.common.base_class import BaseAlgorithm
from stable_baselines3.common.noise import NormalActionNoise
from stable_baselines3.common.save_util import load_from_zip_file
from torch import nn

from pic4rl_agents.runs.config import TrainConfig
from pic4rl_agents.runs.rundir import trained_model
from pic4rl_base.atomic import replacing
from pic4rl_bridge.errors import ConfigError

from .algorithm_table import ALGORITHM_TABLE, AlgorithmEntry
from .action_noise import EpsilonGreedy
from .extractors import DepthGoalExtractor


class AtomicSave:
    """Mixin for an SB3 algorithm: ``save`` and ``save_replay_buffer`` to a path write a
    temporary file and rename it (``pic4rl_base.atomic``), so that a kill mid-save leaves the
    previous file, not a truncated one; SB3's callbacks (checkpoints, the best model) save
    through them too."""

    def save(self, path: Any, *args: Any, **kwargs: Any) -> None:
        if not isinstance(path, (str, Path)):
            super().save(path, *args, **kwargs)  # type: ignore[misc]
            return
        with replacing(_with_suffix(path, ".zip")) as tmp:
            super().save(tmp, *args, **kwargs)  # type: ignore[misc]

    def save_replay_buffer(self, path: Any) -> None:
        if not isinstance(path, (str, Path)):
            super().save_replay_buffer(path)  # type: ignore[misc]
            return
        with replacing(_with_suffix(path, ".pkl")) as tmp:
            super().save_replay_buffer(tmp)  # type: ignore[misc]


def _with_suffix(path: str | Path, suffix: str) -> Path:
    """Where SB3 writes ``path``: with ``suffix`` appended when it has none."""
    path = Path(path)
    return path if path.suffix else path.with_name(path.name + suffix)


def _subclass(entry: AlgorithmEntry) -> type[BaseAlgorithm]:
    """The entry's class with atomic saves, and the paper's ε-greedy when it is off-policy."""
    module, _, name = entry.cls.rpartition(".")
    base = getattr(importlib.import_module(module), name)
    mixins = (AtomicSave, EpsilonGreedy) if entry.off_policy else (AtomicSave,)
    doc = f"{entry.distribution}'s {name}" + (" with the paper's ε-greedy exploration."
                                              if entry.off_policy else ".")
    return type(name, (*mixins, base), {"__module__": __name__, "__doc__": doc})


#: The class of each algorithm of the table, by its name.
ALGORITHMS: dict[str, type[BaseAlgorithm]] = {
    name: _subclass(entry) for name, entry in ALGORITHM_TABLE.items()}

_ACTIVATIONS: dict[str, type[nn.Module]] = {"relu": nn.ReLU, "tanh": nn.Tanh, "elu": nn.ELU}


def algorithm_class(name: str) -> type[BaseAlgorithm]:
    if name not in ALGORITHMS:
        raise ConfigError(f"algorithm: {name!r} is not available; expected one of "
                          f"{', '.join(sorted(ALGORITHMS))}")
    return ALGORITHMS[name]


def _policy(config: TrainConfig, observation_space: gym.Space) -> tuple[str, dict[str, Any]]:
    p = config.policy
    critic = "qf" if config.off_policy else "vf"  # an on-policy actor-critic's value network
    kwargs: dict[str, Any] = {"net_arch": {"pi": list(p.net_arch), critic: list(p.critic_arch)},
                              "activation_fn": _ACTIVATIONS[p.activation]}
    if not config.off_policy:
        kwargs["log_std_init"] = p.log_std_init
    entries = (observation_space.spaces.values()
               if isinstance(observation_space, gym.spaces.Dict) else [observation_space])
    policy = "MultiInputPolicy" if isinstance(observation_space, gym.spaces.Dict) else "MlpPolicy"
    if any(len(s.shape or ()) == 3 for s in entries):  # an image: the CNN per image entry
        kwargs["features_extractor_class"] = DepthGoalExtractor
        kwargs["features_extractor_kwargs"] = {"channels": list(p.cnn_channels),
                                               "cnn_features": p.cnn_features}
        if config.off_policy:
            kwargs["share_features_extractor"] = p.share_features_extractor
        return ("CnnPolicy" if policy == "MlpPolicy" else policy), kwargs
    return policy, kwargs  # vectors only (a Dict: SB3's CombinedExtractor flattens each)


def new_model(config: TrainConfig, env: Any, *, tensorboard_log: str | None = None,
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
    for group in ALGORITHM_TABLE[config.algorithm].kwargs:
        common.update(_KWARG_GROUPS[group](config, env))
    model = cls(policy, env, **common)
    if isinstance(model, EpsilonGreedy):
        e = config.epsilon
        model.set_epsilon(e.initial, e.decay, e.min)
    if config.trained_agent:
        _start_from(model, config, env)
    return model


def _start_from(model: BaseAlgorithm, config: TrainConfig, env: Any) -> None:
    """``config.trained_agent``'s networks and optimiser states in ``model``, which keeps its
    own hyperparameters, seed and (empty) replay buffer: fine-tuning a trained agent on a new
    env, as RL Zoo's ``--trained-agent``."""
    path = trained_model(config.trained_agent, where="trainer.trained_agent")
    where = f"trainer.trained_agent: {path}"
    _check_saved(path, config.algorithm, env, model=where, env_from="this run's env")
    try:
        model.set_parameters(str(path), exact_match=True, device=config.device)
    except (ValueError, KeyError, RuntimeError) as err:
        raise ConfigError(f"{where}: its networks do not fit this run's policy "
                          f"(policy.net_arch, policy.critic_arch): {err}") from err


def _action_noise(config: TrainConfig, env: Any) -> dict[str, Any]:
    if config.action_noise_std <= 0:
        return {}
    n = int(np.prod(env.action_space.shape))
    return {"action_noise": NormalActionNoise(np.zeros(n), np.full(n, config.action_noise_std))}


def _ent_coef(config: TrainConfig, env: Any) -> dict[str, Any]:
    ent = config.ent_coef
    return {"ent_coef": ent if ent.startswith("auto") else float(ent)}


def _ppo(config: TrainConfig, env: Any) -> dict[str, Any]:
    ppo = config.ppo
    return {"batch_size": config.batch_size, "n_steps": ppo.n_steps, "n_epochs": ppo.n_epochs,
            "ent_coef": ppo.ent_coef, "gae_lambda": ppo.gae_lambda,
            "clip_range": ppo.clip_range}


#: The keyword groups an ``AlgorithmEntry`` names: a config and an env → keyword arguments.
_KWARG_GROUPS: dict[str, Callable[[TrainConfig, Any], dict[str, Any]]] = {
    "action_noise": _action_noise, "ent_coef": _ent_coef, "ppo": _ppo}


def load_model(path: str | Path, algorithm: str, *, env: Any = None, device: str = "cpu",
               trained: str = "", env_from: str = "the env") -> BaseAlgorithm:
    """A saved model (SB3 zip) of ``algorithm``, attached to ``env`` when given; a model whose
    spaces differ from ``env``'s is a one-line error saying where each came from (``trained``:
    the model's config, ``env_from``: the env's)."""
    path = Path(path)
    _check_saved(path, algorithm, env, model=f"{path}{f' ({trained})' if trained else ''}",
                env_from=env_from)
    try:
        return algorithm_class(algorithm).load(path, env=env, device=device)
    except (ValueError, KeyError, RuntimeError, TypeError, AttributeError) as err:
        raise ConfigError(f"{path}: cannot load it as a {algorithm} model: {err}") from err


def _check_saved(path: Path, algorithm: str, env: Any, *, model: str, env_from: str) -> None:
    """``ConfigError`` in one line unless ``path`` is an SB3 zip of ``algorithm`` whose
    spaces are ``env``'s (when given)."""
    if not path.is_file():
        raise ConfigError(f"{path}: no such model file (expected an SB3 .zip)")
    cls = algorithm_class(algorithm)
    try:
        data, _, _ = load_from_zip_file(path, load_data=True, device="cpu")
    except (ValueError, KeyError, RuntimeError, OSError) as err:  # not an SB3 zip
        raise ConfigError(f"{path}: cannot load it as a {algorithm} model: {err}") from err
    data = data or {}
    policy = data.get("policy_class")
    known = tuple(cls.policy_aliases.values())
    if isinstance(policy, type) and not issubclass(policy, known):
        raise ConfigError(f"{path}: cannot load it as a {algorithm} model: it holds a "
                          f"{policy.__name__}, not one of {', '.join(k.__name__ for k in known)}"
                          "; pass the algorithm it was trained with")
    if env is not None and "observation_space" in data:
        check_spaces(data["observation_space"], data.get("action_space"), env, model=model,
                     env_from=env_from)


def describe_space(space: gym.Space) -> str:
    """A space in one short line: a Box's shape and bounds, a Dict's per key."""
    if isinstance(space, gym.spaces.Dict):
        return "Dict(" + ", ".join(f"{k}: {describe_space(v)}" for k, v in space.items()) + ")"
    if isinstance(space, gym.spaces.Box):
        shape = "x".join(str(n) for n in space.shape)
        return f"Box({shape}) in [{float(np.min(space.low)):g}, {float(np.max(space.high)):g}]"
    return " ".join(str(space).split())


def check_spaces(observation: gym.Space, action: gym.Space | None, env: Any, *, model: str,
                 env_from: str) -> None:
    """``ConfigError`` in one line when the model's observation (or action) space is not
    ``env``'s: ``model`` and ``env_from`` say which model and env, and where each came from."""
    for kind, trained, given in (("observation", observation, env.observation_space),
                                 ("action", action, env.action_space)):
        if trained is None or trained == given:
            continue
        mine, theirs = describe_space(trained), describe_space(given)
        if mine == theirs:
            mine, theirs = f"{mine} (bounds differ per element)", theirs
        raise ConfigError(f"{model} was trained on the {kind} space {mine} but {env_from} "
                          f"gives {theirs}; use the sensor and settings it was trained with")
