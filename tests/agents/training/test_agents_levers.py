"""Training levers: the curriculum (stages move up and down on the success rate, and each
stage's filters reach the env's pair sampling) and the wall-clock limit."""

from __future__ import annotations

import math
from typing import Any

import gymnasium as gym
import numpy as np
import pytest
from agents_helpers import CONFIG

from pic4rl_agents.runs.config import CurriculumConfig, TrainConfig, load_run_config
from pic4rl_agents.training.curriculum import STAGE_KEY, Curriculum
from pic4rl_bridge.errors import ConfigError

THREE = CurriculumConfig(min_distance_m=(1.0, 1.0, 4.0), max_distance_m=(3.0, 5.0, 8.0),
                         max_detour=(1.05, 1.15, 1.3), up=0.75, down=0.25, window=4)


class Scripted(gym.Env):
    """One-step episodes whose success is scripted; remembers each reset's options."""

    observation_space = gym.spaces.Box(0.0, 1.0, (1,), np.float32)
    action_space = gym.spaces.Box(-1.0, 1.0, (1,), np.float32)

    def __init__(self, outcomes: list[bool]) -> None:
        self.outcomes = list(outcomes)
        self.options: list[dict[str, Any]] = []

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None):
        self.options.append(dict(options or {}))
        return np.zeros(1, np.float32), {}

    def step(self, action):
        return np.zeros(1, np.float32), 0.0, True, False, {"is_success": self.outcomes.pop(0)}


def drive(env: Curriculum, episodes: int) -> list[int]:
    stages = []
    for _ in range(episodes):
        env.reset()
        *_, info = env.step(np.zeros(1, np.float32))
        stages.append(info[STAGE_KEY])
    return stages


def test_stages_move_up_at_the_up_rate_and_down_at_the_down_rate():
    # 3 of 4 succeed (0.75 = up): up; again: up to the last stage, which stays and judges
    # its last 4 episodes as they come; when 1 of the last 4 succeeded (0.25 = down): down.
    outcomes = [True, True, True, False] * 3 + [True, False, False, False]
    inner = Scripted(outcomes)
    stages = drive(Curriculum(inner, THREE), len(outcomes))
    assert stages == [0] * 4 + [1] * 4 + [2] * 7 + [1]
    env = Curriculum(Scripted([True, True, False, False] * 2), THREE)  # 0.5: stays
    assert drive(env, 8) == [0] * 8
    assert inner.options[0] == {"min_distance_m": 1.0, "max_distance_m": 3.0,
                                "max_detour": 1.05}
    assert inner.options[-2] == {"min_distance_m": 4.0, "max_distance_m": 8.0,
                                 "max_detour": 1.3}
    assert inner.options[-1]["max_distance_m"] == 5.0


def test_a_stage_is_judged_on_its_own_episodes():
    # After moving up, the window restarts: three more successes do not move it again.
    env = Curriculum(Scripted([True] * 7), THREE)
    assert drive(env, 7) == [0] * 4 + [1] * 3


def test_the_stage_filters_reach_the_env(tmp_path):
    run = load_run_config([CONFIG / "train_goto_lidar_td3.yaml"])
    from pic4rl_bridge.env import NavEnv

    env = Curriculum(NavEnv(run.env), THREE)
    try:
        for stage, (low, high) in enumerate([(1.0, 3.0), (1.0, 5.0), (4.0, 8.0)]):
            env.stage = stage
            for seed in range(3):
                _, info = env.reset(seed=seed) if seed == 0 else env.reset()
                start, goal = info["start"], info["goal"]
                assert low <= math.hypot(goal[0] - start[0], goal[1] - start[1]) <= high
    finally:
        env.close()


@pytest.mark.parametrize("params, key", [
    ({"curriculum.min_distance_m": [1.0], "curriculum.max_distance_m": []},
     "curriculum.max_distance_m"),
    ({"curriculum.min_distance_m": [3.0], "curriculum.max_distance_m": [2.0],
      "curriculum.max_detour": [1.2]}, "curriculum.max_distance_m"),
    ({"curriculum.min_distance_m": [1.0], "curriculum.max_distance_m": [2.0],
      "curriculum.max_detour": [0.9]}, "curriculum.max_detour"),
    ({"curriculum.up": 0.2, "curriculum.down": 0.5}, "curriculum.up"),
])
def test_bad_curricula_are_named(params, key):
    with pytest.raises(ConfigError, match=key.replace(".", r"\.")):
        TrainConfig().replace(**params)


def test_max_wall_s_stops_a_run_on_time(tmp_path):
    """A run with a step budget far beyond its time limit stops at the time limit, saved."""
    import time

    from agents_helpers import TINY

    from pic4rl_agents.training.train import main

    started = time.perf_counter()
    code = main(["--run", "timed", "-n", "1000000", "--no-progress", "--hyperparams", *TINY,
                 "max_wall_s:4", f"runs_dir:{tmp_path}", "eval.interval_steps:0",
                 "checkpoint.interval_steps:0", "--ros-args", "--params-file",
                 str(CONFIG / "train_goto_lidar_td3.yaml")])
    took = time.perf_counter() - started
    assert code == 0 and took < 60
    summary = (tmp_path / "timed" / "summary.yaml").read_text()
    assert "total_steps" in summary and (tmp_path / "timed" / "model.zip").is_file()
    steps = int(summary.split("total_steps:")[1].split()[0])
    assert 0 < steps < 1_000_000
