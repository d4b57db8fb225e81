"""SB3 callbacks of the trainer: a progress bar with the numbers a user watches, the reward
curve refreshed as training goes, and evaluation on the same episodes every time."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
from stable_baselines3.common.callbacks import BaseCallback, EvalCallback
from tqdm import tqdm

from .curves import save_reward_curve


class ProgressCallback(BaseCallback):
    """A tqdm bar over env steps: episodes done, mean reward and success rate of the last
    100 episodes (SB3's buffers), and ε where the algorithm has one."""

    def __init__(self, total_steps: int, *, desc: str = "training") -> None:
        super().__init__()
        self.total_steps = total_steps
        self.desc = desc
        self.bar: tqdm | None = None
        self.episodes = 0

    def _on_training_start(self) -> None:
        tty = sys.stderr.isatty()
        self.bar = tqdm(total=self.total_steps, initial=self.model.num_timesteps, unit="step",
                        desc=self.desc, dynamic_ncols=True, mininterval=0.5 if tty else 30.0)

    def _on_step(self) -> bool:
        assert self.bar is not None
        self.bar.update(self.model.num_timesteps - self.bar.n)
        dones = self.locals.get("dones")
        if dones is not None:
            self.episodes += int(np.sum(dones))
        if self.n_calls % 200 == 0:
            self.bar.set_postfix(self._postfix(), refresh=False)
        return True

    def _postfix(self) -> dict[str, str]:
        post = {"episodes": str(self.episodes)}
        rewards = [e["r"] for e in self.model.ep_info_buffer or []]
        if rewards:
            post["reward"] = f"{np.mean(rewards):.1f}"
        successes = list(self.model.ep_success_buffer or [])
        if successes:
            post["success"] = f"{100 * np.mean(successes):.0f}%"
        current = getattr(self.model, "current_epsilon", None)
        if current is not None and self.model.epsilon_initial > 0:
            post["eps"] = f"{current():.3f}"
        return post

    def _on_training_end(self) -> None:
        if self.bar is not None:
            self.bar.set_postfix(self._postfix())
            self.bar.close()


class RewardCurveCallback(BaseCallback):
    """Rewrite the reward curve PNG every ``every`` calls (and at the end)."""

    def __init__(self, monitor_dir: Path, out: Path, *, every: int, window: int,
                 title: str) -> None:
        super().__init__()
        self.monitor_dir, self.out, self.every = monitor_dir, out, max(every, 1)
        self.window, self.title = window, title

    def _on_step(self) -> bool:
        if self.n_calls % self.every == 0:
            self.save()
        return True

    def _on_training_end(self) -> None:
        self.save()

    def save(self) -> Path | None:
        return save_reward_curve(self.monitor_dir, self.out, window=self.window,
                                 title=self.title)


class SeededEvalCallback(EvalCallback):
    """SB3's ``EvalCallback`` with the eval env reseeded before each evaluation, so every
    evaluation judges the same start–goal pairs and the curve compares like with like."""

    def __init__(self, *args: object, eval_seed: int, **kwargs: object) -> None:
        super().__init__(*args, **kwargs)  # type: ignore[arg-type]
        self.eval_seed = eval_seed

    def _on_step(self) -> bool:
        if self.eval_freq > 0 and self.n_calls % self.eval_freq == 0:
            self.eval_env.seed(self.eval_seed)
        return super()._on_step()
