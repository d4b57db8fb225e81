"""The search space of ``pic4rl-tune``: hyperparameter samplers as RL Zoo's, each an Optuna
trial and the run's ``n_envs`` → dotted trainer parameters;
``pic4rl_agents.models.algorithm_table`` gives each algorithm its own (the pair samplers are
``pic4rl_sim.engine.sampling``'s).

``Fixing`` draws nothing for a parameter that ``--hyperparams`` fixes (the draws' seeds:
``pic4rl_agents.tune.settings.TrialSeeded``)."""

from __future__ import annotations

from typing import Any

#: Hidden layers of the actor and of each critic, by the sampler's name for them.
NET_ARCHS = {"small": [64, 64], "medium": [128, 128], "big": [256, 256]}
#: The trainer keys of a sampler's parameter whose name is not its key; ``DERIVED``: the
#: value is not the key's own (the key is computed from it).
KEYS = {"net_arch": ("policy.net_arch", "policy.critic_arch"),
        "gradient_steps_ratio": ("gradient_steps",), "epsilon_initial": ("epsilon.initial",),
        "n_steps": ("ppo.n_steps",), "n_epochs": ("ppo.n_epochs",),
        "ent_coef": ("ppo.ent_coef",), "gae_lambda": ("ppo.gae_lambda",),
        "clip_range": ("ppo.clip_range",), "activation": ("policy.activation",)}
DERIVED = ("net_arch", "gradient_steps_ratio")


class Fixing:
    """An Optuna trial as a sampler sees it: a parameter whose trainer keys are all in
    ``fixed`` is not drawn (the trial's params and ``trials.csv`` show only what was), and
    reads as the fixed value (a derived one as its first choice: the fixed key wins)."""

    def __init__(self, trial: Any, fixed: dict[str, Any]) -> None:
        self.trial, self.fixed = trial, fixed

    def _fixed(self, name: str, default: Any) -> tuple[bool, Any]:
        keys = KEYS.get(name, (name,))
        if not all(k in self.fixed for k in keys):
            return False, None
        return True, default if name in DERIVED else self.fixed[keys[0]]

    def suggest_categorical(self, name: str, choices: list[Any]) -> Any:
        fixed, value = self._fixed(name, choices[0])
        return value if fixed else self.trial.suggest_categorical(name, choices)

    def suggest_float(self, name: str, low: float, high: float, *, log: bool = False) -> float:
        fixed, value = self._fixed(name, low)
        return value if fixed else self.trial.suggest_float(name, low, high, log=log)


def _common(trial: Any) -> dict[str, Any]:
    arch = NET_ARCHS[trial.suggest_categorical("net_arch", list(NET_ARCHS))]
    return {"learning_rate": trial.suggest_float("learning_rate", 1e-5, 2e-3, log=True),
            "gamma": trial.suggest_categorical("gamma", [0.95, 0.98, 0.99, 0.995, 0.999]),
            "policy.net_arch": arch, "policy.critic_arch": arch}


def sample_off_policy(trial: Any, n_envs: int = 1) -> dict[str, Any]:
    """SAC and TQC (and the common part of TD3 and DDPG). ``gradient_steps`` is a fraction of
    ``train_freq``: the update-to-data ratio, the wall-clock lever (a gradient step costs
    more than an env step). ``n_envs`` bounds nothing here: the replay buffer holds every
    env's steps."""
    train_freq = trial.suggest_categorical("train_freq", [1, 2, 4, 8, 16, 32, 64])
    ratio = trial.suggest_categorical("gradient_steps_ratio", [0.25, 0.5, 1.0])
    return {**_common(trial),
            "batch_size": trial.suggest_categorical("batch_size", [64, 128, 256, 512]),
            "buffer_size": trial.suggest_categorical("buffer_size",
                                                     [50_000, 200_000, 1_000_000]),
            "learning_starts": trial.suggest_categorical("learning_starts",
                                                         [1_000, 5_000, 10_000]),
            "tau": trial.suggest_categorical("tau", [0.001, 0.005, 0.01, 0.02, 0.05]),
            "train_freq": train_freq,
            "gradient_steps": max(1, round(train_freq * ratio)),
            "epsilon.initial": trial.suggest_categorical("epsilon_initial", [0.0, 0.1, 0.2])}


def sample_td3(trial: Any, n_envs: int = 1) -> dict[str, Any]:
    """TD3 and DDPG: the off-policy parameters and the Gaussian action noise."""
    return {**sample_off_policy(trial),
            "action_noise_std": trial.suggest_float("action_noise_std", 0.0, 0.5)}


def sample_ppo(trial: Any, n_envs: int = 1) -> dict[str, Any]:
    """PPO; the minibatch is at most one rollout (``ppo.n_steps`` × ``n_envs``)."""
    n_steps = trial.suggest_categorical("n_steps", [128, 256, 512, 1024, 2048])
    batch = trial.suggest_categorical("batch_size", [32, 64, 128, 256, 512])
    return {**_common(trial), "epsilon.initial": 0.0,
            "batch_size": min(batch, n_steps * n_envs), "ppo.n_steps": n_steps,
            "ppo.n_epochs": trial.suggest_categorical("n_epochs", [1, 5, 10, 20]),
            "ppo.ent_coef": trial.suggest_float("ent_coef", 1e-8, 0.1, log=True),
            "ppo.gae_lambda": trial.suggest_categorical("gae_lambda", [0.9, 0.95, 0.98, 0.99]),
            "ppo.clip_range": trial.suggest_categorical("clip_range", [0.1, 0.2, 0.3]),
            "policy.activation": trial.suggest_categorical("activation", ["tanh", "relu"])}

