"""Training pairs that widen as the agent succeeds.

Arena-rosnav trains in stages and moves up a stage when the success rate passes a threshold
(down again when it falls below another). Here a stage is a pair filter that the env already
understands (``reset(options={"min_distance_m", "max_distance_m", "max_detour"})``): short,
nearly straight pairs first, the test kind's 4-8 m pairs with detours last. Each env of a
vector env keeps its own stage, judged on its own episodes.
"""

from __future__ import annotations

import logging
from collections import deque
from typing import Any

import gymnasium as gym

from pic4rl_agents.runs.config import CurriculumConfig

log = logging.getLogger(__name__)

#: The ``info`` key that carries the stage an ended episode was drawn from (monitor column).
STAGE_KEY = "curriculum_stage"


class Curriculum(gym.Wrapper):
    """``env`` (a ``NavEnv``, perhaps wrapped) with its pairs drawn from the current stage."""

    def __init__(self, env: gym.Env, config: CurriculumConfig) -> None:
        super().__init__(env)
        self.config = config
        self.stage = 0
        self.results: deque[bool] = deque(maxlen=config.window)

    @property
    def stages(self) -> int:
        return len(self.config.min_distance_m)

    def filters(self) -> dict[str, float]:
        c, i = self.config, self.stage
        return {"min_distance_m": c.min_distance_m[i], "max_distance_m": c.max_distance_m[i],
                "max_detour": c.max_detour[i]}

    def reset(self, *, seed: int | None = None,
              options: dict[str, Any] | None = None) -> tuple[Any, dict[str, Any]]:
        return self.env.reset(seed=seed, options={**self.filters(), **(options or {})})

    def step(self, action: Any) -> tuple[Any, float, bool, bool, dict[str, Any]]:
        obs, reward, terminated, truncated, info = self.env.step(action)
        if terminated or truncated:
            info[STAGE_KEY] = self.stage
            self._judge(bool(info.get("is_success", False)))
        return obs, reward, terminated, truncated, info

    def _judge(self, success: bool) -> None:
        """Record an episode; move a stage up or down once the stage's window is full."""
        self.results.append(success)
        if len(self.results) < self.config.window:
            return
        rate = sum(self.results) / len(self.results)
        if rate >= self.config.up and self.stage + 1 < self.stages:
            self.stage += 1
        elif rate <= self.config.down and self.stage > 0:
            self.stage -= 1
        else:
            return
        log.info("curriculum: success %.2f over %d episodes; stage %d: %s", rate,
                 len(self.results), self.stage, self.filters())
        self.results.clear()
