"""What one ``pic4rl-tune`` study is: its base run, the trials' budget and evaluations, and
where it is kept; each trial's run and the best one derive from the base (``RunConfig.replace``).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

from .config import RunConfig


@dataclass(frozen=True)
class TuneSettings:
    """One study: the base run, the trials' budget and evaluations, and where it is kept."""

    base: RunConfig
    fixed: dict[str, Any]  # trainer parameters every trial keeps (--hyperparams)
    study_name: str
    study_dir: Path
    storage: str
    max_steps: int
    trial_seconds: float  # 0: the trials are bounded by max_steps alone
    n_evaluations: int
    eval_episodes: int | None = None  # None: the base's eval.episodes
    objective: str = "success_rate"

    def trial_run(self, number: int, params: dict[str, Any]) -> RunConfig:
        """Trial ``number``'s run: the base with ``params``, this study's budget and
        evaluations, in process, without checkpoints (its final model is kept)."""
        train = {**params, "max_steps": self.max_steps, "run": f"trial_{number}",
                 "runs_dir": str(self.study_dir / "trials"), "checkpoint.interval_steps": 0,
                 "checkpoint.replay_buffer": False}
        if self.trial_seconds > 0:
            train.update({"eval.interval_s": self.trial_seconds / self.n_evaluations,
                          "eval.interval_steps": 0})
        else:
            train.update({"eval.interval_steps": max(self.max_steps // self.n_evaluations, 1),
                          "eval.interval_s": 0.0})
        if self.eval_episodes is not None:
            train["eval.episodes"] = self.eval_episodes
        return self.base.replace(train=train, env={"transport": "inprocess"})

    def best_run(self, hyperparams: dict[str, Any]) -> RunConfig:
        """The base run with the best trial's parameters: its own budget and evaluations."""
        return self.base.replace(train={**hyperparams, "run": f"{self.study_name}_best"})
