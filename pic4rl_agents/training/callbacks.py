"""SB3 callbacks of the trainer (the progress bar is ``progress``'s): the reward
curve refreshed as training goes, checkpoints that a kill cannot leave half-written,
evaluation on the same episodes every time (against env steps and the clock), and an early
stop on an evaluation's success or the clock."""

from __future__ import annotations

import contextlib
import csv
import io
import logging
import signal
import threading
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
from stable_baselines3.common.callbacks import BaseCallback, CheckpointCallback, EvalCallback
from stable_baselines3.common.vec_env import VecEnv

from pic4rl_agents.runs.rundir import EVALUATIONS
from pic4rl_base import atomic
from pic4rl_metrics.contract import OUTCOMES, Outcome

from .curves import save_reward_curve

log = logging.getLogger(__name__)


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


class Checkpoints(CheckpointCallback):
    """SB3's checkpoints with the replay buffer saved before the model, each file written
    whole (``algorithms.AtomicSave``): a checkpoint's model exists only once its buffer does,
    so a kill between the two leaves no checkpoint that has lost its experience."""

    def _on_step(self) -> bool:
        if self.n_calls % self.save_freq == 0:
            if self.save_replay_buffer and getattr(self.model, "replay_buffer", None) is not None:
                self.model.save_replay_buffer(  # type: ignore[attr-defined]
                    self._checkpoint_path("replay_buffer_", extension="pkl"))
            self.model.save(self._checkpoint_path(extension="zip"))
        return True


class SeededEvalCallback(EvalCallback):
    """SB3's ``EvalCallback`` on the same episodes every time (the eval env is reseeded before
    each evaluation), due every ``interval_steps`` env steps or every ``interval_s`` seconds of
    training, whichever comes first. Each evaluation is a row of ``<log_path>/evaluations.csv``
    (``CSV_COLUMNS``) and logs ``time/wall_s`` and ``time/train_wall_s`` beside SB3's
    ``eval/*``, so runs compare against env steps and against the clock.

    Two clocks, both from ``clock_start`` (``time.perf_counter()``; default: the start of
    training): ``wall_s`` excludes nothing; ``train_wall_s`` excludes the evaluations
    themselves (the policy rollouts, the best-model save, ``callback_after_eval``), so it does
    not depend on how often or how long one evaluates. A row's clocks and steps are those at
    the start of its evaluation, when the evaluated policy was current."""

    def __init__(self, eval_env: VecEnv, *, eval_seed: int, log_path: str,
                 interval_steps: int = 0, interval_s: float = 0.0, n_envs: int = 1,
                 clock_start: float | None = None, **kwargs: Any) -> None:
        if interval_steps <= 0 and interval_s <= 0:
            raise ValueError("SeededEvalCallback: interval_steps or interval_s must be > 0")
        # eval_freq 1: SB3's _on_step evaluates whenever it is called; _on_step below decides.
        super().__init__(eval_env, eval_freq=1, log_path=log_path, **kwargs)
        self.eval_seed = eval_seed
        self.every_calls = max(interval_steps // n_envs, 1) if interval_steps > 0 else 0
        self.interval_s = interval_s
        self.clock_start = clock_start
        self.csv_path = Path(log_path) / EVALUATIONS
        self.eval_s = 0.0  # seconds spent evaluating so far
        self.last_row: dict[str, float] = {}
        self.best_row: dict[str, float] = {}  # the first evaluation with the best success rate
        self._last_due_s = 0.0
        self._outcomes: list[str] = []
        self._successes: list[bool] = []  # the latest evaluation's episodes' is_success

    def _init_callback(self) -> None:
        super()._init_callback()
        if self.clock_start is None:
            self.clock_start = time.perf_counter()
        self._last_due_s = self.train_wall_s()  # the first one interval_s into training

    @property
    def last_success_rate(self) -> float:
        """The success rate of the latest evaluation (0 before the first)."""
        return float(np.mean(self._successes)) if self._successes else 0.0

    def train_wall_s(self, now: float | None = None) -> float:
        """Seconds since ``clock_start`` minus the time spent evaluating."""
        assert self.clock_start is not None  # set by _init_callback
        return (time.perf_counter() if now is None else now) - self.clock_start - self.eval_s

    def _on_step(self) -> bool:
        now = time.perf_counter()
        train_s = self.train_wall_s(now)
        by_steps = self.every_calls > 0 and self.n_calls % self.every_calls == 0
        by_time = self.interval_s > 0 and train_s - self._last_due_s >= self.interval_s
        if not (by_steps or by_time):
            return True
        return self._evaluate(now)

    def evaluate_saved(self, *, refitted: bool = False) -> bool:
        """At the end of training, evaluate the model once more unless this session's last
        evaluation judged it as it is now: no evaluation yet, training after the last one, or
        an actor ``refitted`` after it (imitation cut short by a budget). The last row of
        ``evaluations.csv``, and so ``summary.yaml``, then judge the saved model.
        ``callback_after_eval`` is not called (training is over). True when it evaluated."""
        self.num_timesteps = self.model.num_timesteps
        if self.last_row.get("steps") == self.num_timesteps and not refitted:
            return False
        log.info("evaluating the model as saved, at %d steps", self.num_timesteps)
        after, self.callback = self.callback, None
        try:
            self._evaluate(time.perf_counter())
        finally:
            self.callback = after
        return True

    def _evaluate(self, now: float) -> bool:
        """Evaluate now (``now``: ``time.perf_counter()``): one row, SB3's logs, the best
        model; what ``callback_after_eval`` says (False: stop training)."""
        train_s = self.train_wall_s(now)
        self._last_due_s = train_s
        assert self.clock_start is not None
        wall_s = now - self.clock_start
        self.logger.record("time/wall_s", wall_s)
        self.logger.record("time/train_wall_s", train_s)
        self.eval_env.seed(self.eval_seed)
        self._outcomes, self._successes = [], []
        self.last_row = {"steps": self.num_timesteps, "wall_s": wall_s, "train_wall_s": train_s}
        try:
            keep_going = super()._on_step()
        finally:
            took = time.perf_counter() - now
            self.eval_s += took
        self._write_row(took)
        return keep_going

    def _log_success_callback(self, locals_: dict[str, Any], globals_: dict[str, Any]) -> None:
        # SB3's hook for each evaluation step (what it gives ``evaluate_policy``); the rate is
        # counted here, as SB3 counts its own, rather than read from its private buffer.
        super()._log_success_callback(locals_, globals_)
        if locals_["done"]:
            info = locals_["info"]
            self._outcomes.append(str(info.get("outcome", "")))
            if info.get("is_success") is not None:
                self._successes.append(bool(info["is_success"]))

    def _write_row(self, eval_s: float) -> None:
        rewards, lengths = self.evaluations_results[-1], self.evaluations_length[-1]
        n = len(rewards)
        row = {**self.last_row, "eval_s": eval_s, "episodes": n,
               "success_rate": self.last_success_rate,
               "mean_reward": float(np.mean(rewards)), "mean_length": float(np.mean(lengths))}
        for outcome in OUTCOME_COLUMNS:
            row[f"{outcome}_rate"] = self._outcomes.count(outcome) / n if n else 0.0
        self.last_row = row
        if not self.best_row or row["success_rate"] > self.best_row["success_rate"]:
            self.best_row = row
        log.info("%s", evaluation_line(row, self.best_row))
        text = io.StringIO(newline="")
        writer = csv.DictWriter(text, fieldnames=CSV_COLUMNS)
        if self.csv_path.exists():
            text.write(self.csv_path.read_text())
        else:
            writer.writeheader()
        writer.writerow({k: (round(v, 3) if isinstance(v, float) else v)
                         for k, v in row.items()})
        atomic.write_text(self.csv_path, text.getvalue())  # a kill leaves no half row


#: Outcomes counted in their own column of ``evaluations.csv`` (a goal is ``success_rate``).
OUTCOME_COLUMNS = tuple(o for o in OUTCOMES if o != Outcome.GOAL.value)
#: The columns of ``evaluations.csv``: one row per evaluation.
CSV_COLUMNS = ("steps", "wall_s", "train_wall_s", "eval_s", "episodes", "success_rate",
               "mean_reward", "mean_length", *(f"{o}_rate" for o in OUTCOME_COLUMNS))


def evaluation_line(row: dict[str, Any], best: dict[str, Any]) -> str:
    """One evaluation in words, from its ``evaluations.csv`` row and the best one so far (by
    success rate): ``eval at 2,000 steps (1.5 min): success 3/5 (60%), collisions 1,
    timeouts 1; best 60% at 2,000 steps``."""
    n = int(row["episodes"])
    always = ("collision", "timeout")
    counts = [f"{o}{'s' if o in always else ''} {round(row[f'{o}_rate'] * n)}"
              for o in OUTCOME_COLUMNS if row[f"{o}_rate"] or o in always]
    return (f"eval at {int(row['steps']):,} steps ({row['wall_s'] / 60:.1f} min): success "
            f"{round(row['success_rate'] * n)}/{n} ({100 * row['success_rate']:.0f}%), "
            f"{', '.join(counts)}; best {100 * best['success_rate']:.0f}% at "
            f"{int(best['steps']):,} steps")


class WallClockLimit(BaseCallback):
    """Ends training once ``limit_s`` seconds have passed since ``start`` (a
    ``time.perf_counter()`` reading): training for a time budget rather than a step count."""

    def __init__(self, limit_s: float, start: float) -> None:
        super().__init__()
        self.limit_s, self.start = limit_s, start

    def _on_step(self) -> bool:
        return not self.over()

    def over(self) -> bool:
        """Whether the budget is spent (also read between the imitation's critic updates,
        which are no env steps)."""
        return time.perf_counter() - self.start >= self.limit_s


@contextlib.contextmanager
def stop_on_signal(stop: threading.Event) -> Iterator[None]:
    """Ctrl-C and SIGTERM (``pic4rl-run`` stopping us, a cluster's scheduler) end training the
    way Ctrl-C does: the model and replay buffer are saved first. The signal sets ``stop``
    and raises ``KeyboardInterrupt``; Python drops an exception raised while a weakref
    callback or ``__del__`` runs (drawing the reward curve makes many), so ``StopWhenSet``
    ends training at the next step from the flag as well. Setting the SIGINT handler also
    undoes the ignored SIGINT that a process started in the background by a shell inherits."""
    def handler(signum: int, frame: object) -> None:
        stop.set()
        raise KeyboardInterrupt

    previous = {s: signal.signal(s, handler) for s in (signal.SIGTERM, signal.SIGINT)}
    try:
        yield
    finally:
        for signum, old in previous.items():
            signal.signal(signum, old)


class StopWhenSet(BaseCallback):
    """Ends training at the next step once ``event`` is set: a stop signal that Python could
    not raise as ``KeyboardInterrupt`` (see ``stop_on_signal``) still stops."""

    def __init__(self, event: threading.Event) -> None:
        super().__init__()
        self.event = event

    def _on_step(self) -> bool:
        return not self.event.is_set()


class StopAfterEval(BaseCallback):
    """``callback_after_eval`` of a ``SeededEvalCallback``: ends training once an evaluation
    reaches ``success_rate`` or the training clock passes ``budget_s`` (either may be None)."""

    def __init__(self, *, success_rate: float | None = None,
                 budget_s: float | None = None) -> None:
        super().__init__()
        self.success_rate, self.budget_s = success_rate, budget_s
        self.reached = False

    def _on_step(self) -> bool:
        parent = self.parent
        assert isinstance(parent, SeededEvalCallback)
        self.reached = (self.success_rate is not None
                        and parent.last_success_rate >= self.success_rate)
        over = self.budget_s is not None and parent.last_row["train_wall_s"] >= self.budget_s
        return not (self.reached or over)


def evaluate_saved(callbacks: list[BaseCallback], stop: threading.Event,
                   refitted: bool = False) -> bool:
    """At the end of training, ``SeededEvalCallback.evaluate_saved`` of the evaluation among
    ``callbacks`` (none: nothing), under ``stop_on_signal`` as training is; False when a
    signal stopped it (the row is then not written)."""
    with stop_on_signal(stop):
        try:
            for evaluation in callbacks:
                if isinstance(evaluation, SeededEvalCallback):
                    evaluation.evaluate_saved(refitted=refitted)
        except BaseException as err:
            if not stopped_by_signal(err, stop):
                raise
    return not stop.is_set()


def stopped_by_signal(err: BaseException, stop: threading.Event) -> bool:
    """Whether ``err`` is ``stop_on_signal``'s interrupt: the ``KeyboardInterrupt``,
    or, when it lands inside an extension (rclpy deserializing a message), the error that
    extension turns it into, chained from it."""
    if isinstance(err, KeyboardInterrupt):
        return True
    return stop.is_set() and isinstance(err.__cause__ or err.__context__, KeyboardInterrupt)
