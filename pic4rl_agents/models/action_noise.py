"""The paper's ε-greedy action noise with exponential decay, for SB3's off-policy algorithms.

TF2RL, which PIC4rl-gym trained with, had only a random warm-up; the paper added ε-greedy so
exploration never stops: after ``learning_starts``, each env's action is replaced by a uniform
random one with probability ε_t = max(ε_min, ε_0 · γ_ε^t), t counting env steps since the
warm-up ended. SB3 has the warm-up (``learning_starts``) but no ε-greedy, so the mixin below
wraps ``OffPolicyAlgorithm._sample_action``: the one place SB3 picks exploratory actions.
The schedule's three numbers are plain attributes, saved in the model's zip, so a resumed run
continues the same schedule.
"""

from __future__ import annotations

from typing import Any

import numpy as np


def epsilon_at(step: int, initial: float, decay: float, minimum: float) -> float:
    """ε after ``step`` env steps past the warm-up: ``max(minimum, initial · decay^step)``."""
    if initial <= 0.0:
        return 0.0
    return max(minimum, initial * decay ** max(step, 0))


class EpsilonGreedy:
    """Mixin for an SB3 ``OffPolicyAlgorithm``: ε-greedy on top of its own exploration (action
    noise for DDPG/TD3, the stochastic policy for SAC). Logs ``rollout/epsilon``."""

    epsilon_initial: float = 0.0
    epsilon_decay: float = 1.0
    epsilon_min: float = 0.0

    def set_epsilon(self, initial: float, decay: float, minimum: float) -> None:
        self.epsilon_initial, self.epsilon_decay, self.epsilon_min = initial, decay, minimum

    def current_epsilon(self) -> float:
        learning_starts = self.learning_starts  # type: ignore[attr-defined]
        step = self.num_timesteps - learning_starts  # type: ignore[attr-defined]
        if step < 0:
            return 0.0  # the warm-up is random anyway
        return epsilon_at(step, self.epsilon_initial, self.epsilon_decay, self.epsilon_min)

    def _sample_action(self, learning_starts: int, action_noise: Any = None,
                       n_envs: int = 1) -> tuple[np.ndarray, np.ndarray]:
        action, buffer_action = super()._sample_action(  # type: ignore[misc]
            learning_starts, action_noise, n_envs)
        eps = self.current_epsilon()
        self.logger.record("rollout/epsilon", eps)  # type: ignore[attr-defined]
        if eps > 0.0:
            explore = np.random.random(n_envs) < eps  # SB3 seeds numpy's global generator
            if explore.any():
                space = self.action_space  # type: ignore[attr-defined]
                random = np.array([space.sample() for _ in range(n_envs)], dtype=action.dtype)
                scaled = self.policy.scale_action(random)  # type: ignore[attr-defined]
                buffer_action = np.where(explore[:, None], scaled, buffer_action)
                action = np.where(explore[:, None], random, action)
        return action, buffer_action
