"""What one ``pic4rl-tune`` study is: its base run, the trials' budget and evaluations, and
where it is kept; each trial's run and the best one derive from the base (``RunConfig.replace``);
and how its trials are seeded: ``TrialSeeded``, TPE seeded from the study's seed and the
trial's number (which the storage gives out once), so a resumed study, or machines sharing
one, draw new parameters.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import optuna

from pic4rl_agents.models.algorithm_table import ALGORITHM_TABLE
from pic4rl_agents.runs.config import RunConfig

log = logging.getLogger(__name__)


class TrialSeeded(optuna.samplers.BaseSampler):
    """TPE whose draws for trial n come from seed ``seed + n``: a fresh ``TPESampler`` per
    trial (TPE keeps no state but its random generator; the history is the study's)."""

    def __init__(self, seed: int, n_startup_trials: int) -> None:
        self.seed, self.n_startup_trials = seed, n_startup_trials
        self._tpe = self._for(0)

    def _for(self, number: int) -> optuna.samplers.TPESampler:
        return optuna.samplers.TPESampler(n_startup_trials=self.n_startup_trials,
                                          seed=self.seed + number)

    def before_trial(self, study: Any, trial: Any) -> None:
        self._tpe = self._for(trial.number)
        self._tpe.before_trial(study, trial)

    def infer_relative_search_space(self, study: Any, trial: Any) -> dict[str, Any]:
        return self._tpe.infer_relative_search_space(study, trial)

    def sample_relative(self, study: Any, trial: Any, space: dict[str, Any]) -> dict[str, Any]:
        return self._tpe.sample_relative(study, trial, space)

    def sample_independent(self, study: Any, trial: Any, name: str, distribution: Any) -> Any:
        return self._tpe.sample_independent(study, trial, name, distribution)

    def after_trial(self, study: Any, trial: Any, state: Any, values: Any) -> None:
        self._tpe.after_trial(study, trial, state, values)


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
        evaluations, in process, without checkpoints (its final model is kept). A
        ``learning_starts`` at or above the budget is warned: the trial would never learn."""
        starts = params.get("learning_starts")
        entry = ALGORITHM_TABLE.get(str(params.get("algorithm", self.base.train.algorithm)))
        if entry and entry.off_policy and isinstance(starts, int) and starts >= self.max_steps:
            log.warning("trial %d: learning_starts %d is not below its budget of %d steps: it "
                        "never updates its policy (fix it with --hyperparams "
                        "learning_starts:N, or raise --max-steps)", number, starts,
                        self.max_steps)
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
