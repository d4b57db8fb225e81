"""The training's progress bar: which phase runs (cloning, a DAgger round, the critic's
warm-up, RL), and an ETA from whichever budget ends the run first, ``max_steps`` or
``max_wall_s`` (``binding_budget``, a pure function of the step count and the clock)."""

from __future__ import annotations

import math
import sys
import time
from dataclasses import dataclass

import numpy as np
from stable_baselines3.common.callbacks import BaseCallback
from tqdm import tqdm

#: The phase of a run without imitation, and of every run after it.
RL = "RL"


@dataclass(frozen=True)
class Budget:
    """Where a run stands against its budgets. ``binding``: the budget that ends it first
    (``max_steps`` or ``max_wall_s``); ``total_steps``: the env steps it will have then (at
    the current speed when the clock binds); ``fraction``: the share of the binding budget
    spent; ``eta_s``: seconds left (None: unknown, no speed yet)."""

    binding: str
    total_steps: int
    fraction: float
    eta_s: float | None


def binding_budget(steps: int, max_steps: int, elapsed_s: float, max_wall_s: float = 0.0,
                   steps_per_s: float = 0.0) -> Budget:
    """The budget that ends the run first: ``max_steps`` env steps at ``steps_per_s`` (0:
    not known yet), or ``max_wall_s`` seconds of the session (0: none), ``elapsed_s`` of it
    spent."""
    steps_left = max(max_steps - steps, 0)
    eta_steps = steps_left / steps_per_s if steps_per_s > 0 else math.inf
    if max_wall_s > 0:
        eta_wall = max(max_wall_s - elapsed_s, 0.0)
        if eta_wall < eta_steps:
            total = (min(round(steps + steps_per_s * eta_wall), max_steps) if steps_per_s > 0
                     else max_steps)
            return Budget("max_wall_s", total, min(elapsed_s / max_wall_s, 1.0), eta_wall)
    return Budget("max_steps", max_steps, min(steps / max_steps, 1.0) if max_steps else 1.0,
                  eta_steps if math.isfinite(eta_steps) else None)


class ProgressCallback(BaseCallback):
    """A tqdm bar over env steps whose total is the steps the run will have when its binding
    budget ends (``binding_budget`` at tqdm's recent speed, every 50 steps), so that tqdm's
    ETA is that budget's; its description
    names the phase (``set_phase``; ``RL`` unless imitation says otherwise), its postfix the
    episodes done, mean reward and success rate of the last 100 episodes (SB3's buffers),
    ε where the algorithm has one, and the binding budget."""

    def __init__(self, total_steps: int, *, desc: str = "training", max_wall_s: float = 0.0,
                 started: float | None = None) -> None:
        """``started``: the session's start (``time.perf_counter()``), the clock of
        ``max_wall_s``; default: the first training start."""
        super().__init__()
        self.total_steps = total_steps
        self.desc = desc
        self.max_wall_s = max_wall_s
        self.started = started
        self.phase = RL
        self.bar: tqdm | None = None
        self.episodes = 0
        self._opened = (0.0, 0)  # when the bar opened, and the steps then

    def set_phase(self, phase: str) -> None:
        """Name the phase now running in the bar's description (shown at once)."""
        self.phase = phase
        if self.bar is not None:
            self.bar.set_description(self._description(), refresh=True)

    def _description(self) -> str:
        return f"{self.desc} [{self.phase}]"

    def _on_training_start(self) -> None:
        if self.started is None:
            self.started = time.perf_counter()
        tty = sys.stderr.isatty()
        self.bar = tqdm(total=self.total_steps, initial=self.model.num_timesteps, unit="step",
                        desc=self._description(), dynamic_ncols=True,
                        mininterval=0.5 if tty else 30.0)
        self._opened = (time.perf_counter(), self.model.num_timesteps)

    def steps_per_s(self) -> float:
        """The recent speed (tqdm's smoothed rate), else the mean since the bar opened."""
        assert self.bar is not None
        rate = self.bar.format_dict.get("rate")
        if rate:
            return float(rate)
        opened_s, opened_steps = self._opened
        took = time.perf_counter() - opened_s
        return (self.model.num_timesteps - opened_steps) / took if took > 0 else 0.0

    def budget(self) -> Budget:
        assert self.started is not None
        return binding_budget(self.model.num_timesteps, self.total_steps,
                              time.perf_counter() - self.started, self.max_wall_s,
                              self.steps_per_s())

    def _on_step(self) -> bool:
        assert self.bar is not None
        dones = self.locals.get("dones")
        if dones is not None:
            self.episodes += int(np.sum(dones))
        self.bar.update(self.model.num_timesteps - self.bar.n)
        if self.n_calls % 50 == 1:  # the first step, then every 50: tqdm's ETA is the budget's
            self.bar.total = max(self.budget().total_steps, self.bar.n + 1)
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
        post["ends"] = ("max_steps" if self.budget().binding == "max_steps"
                        else f"max_wall_s {self.max_wall_s:g} s")
        return post

    def _on_training_end(self) -> None:
        if self.bar is not None:
            if self.budget().fraction >= 1.0:  # the run's end, not imitation's or a stop's
                self.bar.total = self.bar.n
            self.bar.set_postfix(self._postfix())
            self.bar.close()
            self.bar = None
        self.phase = RL  # imitation's bar closes; RL's opens after it
