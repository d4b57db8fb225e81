"""The algorithms, each declared once: its SB3 class, whether it is off-policy, its search space
and the keyword groups ``new_model`` gives it. ``TrainConfig``'s ``Algorithm`` and
``OFF_POLICY``, ``pic4rl_agents.models.algorithms.ALGORITHMS`` and ``pic4rl-tune``'s sampler
read it.

Light on purpose: ``pic4rl_agents.runs.config`` imports it for ``--help`` and config checks, so a
class is named by its import path, imported only when a model is built or loaded.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from pic4rl_agents.tune.space import sample_off_policy, sample_ppo, sample_td3

#: A trial and the run's ``n_envs`` → dotted trainer parameters.
Sampler = Callable[..., dict[str, Any]]


@dataclass(frozen=True)
class AlgorithmEntry:
    cls: str  # "package.Class" of SB3 or sb3-contrib
    off_policy: bool  # a replay buffer; ε-greedy, imitation and shared CNNs apply
    sampler: Sampler  # pic4rl-tune's search space (pic4rl_agents.tune.space)
    #: ``new_model``'s keyword groups beyond every algorithm's and every off-policy one's:
    #: "action_noise" (Gaussian, ``action_noise_std``), "ent_coef" (SAC's entropy
    #: coefficient), "ppo" (the ``ppo.*`` section and ``batch_size``).
    kwargs: tuple[str, ...] = ()

    @property
    def distribution(self) -> str:
        """The package to install, as pip names it: ``stable-baselines3``, ``sb3-contrib``."""
        return self.cls.split(".")[0].replace("_", "-")


#: Every algorithm by its name in params files; the order is the one error messages list.
ALGORITHM_TABLE: dict[str, AlgorithmEntry] = {
    "ddpg": AlgorithmEntry("stable_baselines3.DDPG", True, sample_td3, ("action_noise",)),
    "td3": AlgorithmEntry("stable_baselines3.TD3", True, sample_td3, ("action_noise",)),
    "sac": AlgorithmEntry("stable_baselines3.SAC", True, sample_off_policy, ("ent_coef",)),
    "tqc": AlgorithmEntry("sb3_contrib.TQC", True, sample_off_policy, ("ent_coef",)),
    "ppo": AlgorithmEntry("stable_baselines3.PPO", False, sample_ppo, ("ppo",)),
}
