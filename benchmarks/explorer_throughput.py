"""The mapless explorer's control rate and what memory costs the env, side by side in one run.

goToPose with the Jackal's 360-beam LiDAR in the seeded ``indoor`` world
(``config/env_goto_lidar.yaml``, v in [0, 0.5] m/s, w in [-1, 1] rad/s), ``--episodes``
start-goal pairs of the ``paper`` kind drawn from ``--seed``, the explorer driving, at most
``--max-steps`` steps each:

- explorer steps/s: ``ExplorerController.command`` alone (marking, replanning, pursuit), and
  its plans per 100 steps and the mean time of a step that planned;
- env steps/s without memory, and with ``memory.enabled`` (the same actions replayed): what
  the 64 x 64 crop of the episode's grid costs each step.

Target (docs/performance.md): the explorer >= 100 control steps/s (ten times the 10 Hz
control loop). The last lines are ``RESULT <name> <value>``.

    .venv/bin/python benchmarks/explorer_throughput.py
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

from pic4rl_bridge.env import NavEnv
from pic4rl_bridge.baselines.explorer import ExplorerController

CONFIG = Path(__file__).resolve().parents[1] / "config" / "env_goto_lidar.yaml"
OVERRIDES = {"episodes.pair_kind": "paper", "episode_max_steps": 300, "max_linear_m_s": 0.5,
             "min_linear_m_s": 0.0, "max_angular_rad_s": 1.0}


def drive(episodes: int, seed: int, max_steps: int) -> tuple[list[list[np.ndarray]], dict]:
    """The explorer's episodes: each one's actions, and its timings and outcomes."""
    env = NavEnv(CONFIG, overrides={**OVERRIDES, "episode_max_steps": max_steps})
    explorer = ExplorerController(env.scenario.robot)
    actions: list[list[np.ndarray]] = []
    plan_s = other_s = 0.0
    planned = steps = 0
    outcomes = []
    for episode in range(episodes):
        env.reset(seed=seed) if episode == 0 else env.reset()
        explorer.reset()
        actions.append([])
        while True:
            plans = explorer.plans
            start = time.perf_counter()
            action = explorer.action(env.frame)
            took = time.perf_counter() - start
            if explorer.plans > plans:
                plan_s, planned = plan_s + took, planned + 1
            else:
                other_s += took
            steps += 1
            actions[-1].append(action)
            _, _, terminated, truncated, info = env.step(action)
            if terminated or truncated:
                outcomes.append(info["outcome"])
                break
    env.close()
    return actions, {"steps": steps, "plan_s": plan_s, "other_s": other_s,
                     "planned": planned, "outcomes": outcomes}


def replay(actions: list[list[np.ndarray]], seed: int, max_steps: int, memory: bool) -> float:
    """Seconds of ``env.step`` replaying ``actions`` (memory on or off)."""
    env = NavEnv(CONFIG, overrides={**OVERRIDES, "episode_max_steps": max_steps,
                                    "memory.enabled": memory})
    total = 0.0
    for episode, taken in enumerate(actions):
        env.reset(seed=seed) if episode == 0 else env.reset()
        for action in taken:
            start = time.perf_counter()
            _, _, terminated, truncated, _ = env.step(action)
            total += time.perf_counter() - start
            if terminated or truncated:
                break
    env.close()
    return total


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--episodes", type=int, default=10)
    parser.add_argument("--seed", type=int, default=7)
    parser.add_argument("--max-steps", type=int, default=300)
    args = parser.parse_args()
    actions, run = drive(args.episodes, args.seed, args.max_steps)
    steps = run["steps"]
    plain = replay(actions, args.seed, args.max_steps, memory=False)
    remembered = replay(actions, args.seed, args.max_steps, memory=True)
    explorer_s = run["plan_s"] + run["other_s"]
    print(f"{args.episodes} episodes, {steps} steps: outcomes {run['outcomes']}")
    print(f"RESULT explorer_steps_per_s {steps / explorer_s:.1f}")
    print(f"RESULT explorer_plans_per_100_steps {100 * run['planned'] / steps:.2f}")
    print(f"RESULT explorer_ms_per_planning_step {1000 * run['plan_s'] / max(run['planned'], 1):.2f}")
    print(f"RESULT explorer_ms_per_other_step "
          f"{1000 * run['other_s'] / max(steps - run['planned'], 1):.2f}")
    print(f"RESULT env_steps_per_s {steps / plain:.1f}")
    print(f"RESULT env_memory_steps_per_s {steps / remembered:.1f}")
    print(f"RESULT memory_step_cost_ratio {remembered / plain:.3f}")


if __name__ == "__main__":
    main()
