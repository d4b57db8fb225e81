"""Test episodes per second with the DWA baseline, in process and through ROS 2; DWA's own
control rate; the shortest-path search that judges every simulated episode.

One task (goToPose with the Jackal's 360-beam LiDAR in the seeded ``indoor`` world,
``config/env_goto_lidar.yaml``), ``--episodes`` start-goal pairs of the ``paper`` kind drawn
from ``--seed`` (the same pairs through both transports), each episode recorded to a sqlite3
bag as ``pic4rl-test`` records it, at most ``--max-steps`` steps:

- in-process episodes: ``NavEnv`` over the engine in this process, DWA driving;
- ROS 2 episodes: the same over the ``sim`` node in another process (lockstep);
- DWA alone: ``DwaController.command`` over the frames of those episodes, replayed, against
  the in-process env's own stepping rate (recording on, DWA's time excluded);
- shortest path: ``pic4rl_sim.engine.paths.shortest_path_length`` for the episodes' pairs, with a
  planner built for each (cold) and with the cached one (warm).

Episode loops run interleaved, best of ``--repeat``. Target (docs/performance.md): DWA
>= 1,000 control steps/s, so it is not the bottleneck. The last lines are
``RESULT <name> <value>``.

    .venv/bin/python benchmarks/eval_throughput.py
"""

from __future__ import annotations

import argparse
import os
import random
import sys
import tempfile
import time
from pathlib import Path
from typing import Any, NamedTuple

from _sim import start_sim, stop_sim
from pic4rl_bridge.baselines.registry import make_baseline
from pic4rl_bridge.baselines.dwa import DwaController
from pic4rl_bridge.env import NavEnv
from pic4rl_bridge.recording import make_env
from pic4rl_bridge.readings.frame import SensorFrame
from pic4rl_sim.engine import paths

CONFIG = Path(__file__).resolve().parents[1] / "config" / "env_goto_lidar.yaml"


class Run(NamedTuple):
    """One timed run of episodes: seconds in all, and of ``env.step`` alone; the outcomes,
    the pairs, the frames DWA saw."""

    seconds: float
    step_s: float
    outcomes: list[str]
    pairs: list[tuple[list[float], list[float]]]
    frames: list[SensorFrame]


def episodes(env: Any, dwa: DwaController, count: int, seed: int) -> Run:
    """Drive ``count`` episodes of ``env`` (recorded) from a seeded reset, as ``pic4rl-test``
    does."""
    run = Run(0.0, 0.0, [], [], [])
    step_s = 0.0
    start = time.perf_counter()
    for episode in range(count):
        _, info = env.reset(seed=seed if episode == 0 else None)
        run.pairs.append((info["start"], list(info["goal"])))
        dwa.reset()
        done = False
        while not done:
            frame = env.unwrapped.frame
            assert frame is not None
            action = dwa.action(frame)
            run.frames.append(frame)
            tick = time.perf_counter()
            _, _, terminated, truncated, info = env.step(action)
            step_s += time.perf_counter() - tick
            done = terminated or truncated
        run.outcomes.append(str(info["outcome"]))
    return run._replace(seconds=time.perf_counter() - start, step_s=step_s)


def replay(dwa: DwaController, frames: list[SensorFrame]) -> float:
    """Seconds for ``dwa.command`` over ``frames`` (the window centred anew each episode is
    not modelled: each frame continues from the last command)."""
    dwa.reset()
    start = time.perf_counter()
    for frame in frames:
        dwa.command(frame)
    return time.perf_counter() - start


def path_times(env: NavEnv, pairs: list[tuple[list[float], tuple[float, float]]],
               repeat: int) -> tuple[float, float]:
    """Mean seconds of one shortest-path query: with its planner (grid) built for it, and on
    a planner already built (each pair asked once: no cached answer)."""
    world = env.scenario.world
    assert world is not None
    radius = env.scenario.robot.footprint.bounding_radius_m
    cold = warm = float("inf")
    for _ in range(repeat):
        start = time.perf_counter()
        for s, g in pairs:
            paths.PathPlanner(world, robot_radius_m=radius).length(s[:2], g)
        cold = min(cold, (time.perf_counter() - start) / len(pairs))
        planner = paths.PathPlanner(world, robot_radius_m=radius)
        start = time.perf_counter()
        for s, g in pairs:
            planner.length(s[:2], g)
        warm = min(warm, (time.perf_counter() - start) / len(pairs))
    return cold, warm


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--episodes", type=int, default=5, help="episodes per timed run")
    parser.add_argument("--max-steps", type=int, default=400, help="steps per episode at most")
    parser.add_argument("--repeat", type=int, default=3, help="best of this many runs")
    parser.add_argument("--seed", type=int, default=7, help="the pairs' seed")
    args = parser.parse_args(argv)
    os.environ.setdefault("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")
    domain = random.randint(1, 100)
    sim = start_sim(domain, "--params-file", str(CONFIG))
    bags = tempfile.TemporaryDirectory(prefix="eval_throughput_")
    common = {"episode_max_steps": args.max_steps, "ros.domain_id": domain,
              "episodes.pair_kind": "paper", "record.enabled": True,
              "record.bags_dir": bags.name, "agent": "dwa"}
    envs = {"inprocess": make_env(CONFIG, overrides={**common, "record.run": "inprocess"}),
            "ros": make_env(CONFIG, transport="ros", overrides={**common, "record.run": "ros"})}
    dwa = {name: make_baseline("dwa", env.unwrapped.config, env.unwrapped.scenario.robot)
           for name, env in envs.items()}
    try:
        best = dict.fromkeys(envs, float("inf"))
        step_s, local = float("inf"), Run(0.0, 0.0, [], [], [])
        for round_ in range(args.repeat):
            for name, env in envs.items():
                run = episodes(env, dwa[name], args.episodes, args.seed)
                best[name] = min(best[name], run.seconds)
                if name == "inprocess":
                    step_s, local = min(step_s, run.step_s / len(run.frames)), run
                print(f"round {round_ + 1}/{args.repeat}: {name} {run.seconds:.2f} s, "
                      f"{len(run.frames)} steps, outcomes {run.outcomes}", file=sys.stderr)
        frames = local.frames
        control_s = min(replay(dwa["inprocess"], frames) for _ in range(args.repeat))
        cold_s, warm_s = path_times(envs["inprocess"].unwrapped, local.pairs, args.repeat)
    finally:
        for env in envs.values():
            env.close()
        stop_sim(sim)
        bags.cleanup()
    rate = {name: args.episodes / s for name, s in best.items()}
    dwa_rate = len(frames) / control_s
    print(f"RESULT eval_dwa_inprocess_episodes_per_s {rate['inprocess']:.3f}")
    print(f"RESULT eval_dwa_ros_episodes_per_s {rate['ros']:.3f}")
    print(f"RESULT eval_ros_vs_inprocess_ratio {rate['ros'] / rate['inprocess']:.2f}")
    print(f"RESULT eval_dwa_control_steps_per_s {dwa_rate:.0f}")
    print(f"RESULT eval_inprocess_env_steps_per_s {1.0 / step_s:.0f}")
    print(f"RESULT eval_dwa_vs_env_steps_ratio {dwa_rate * step_s:.2f}")
    print(f"RESULT eval_shortest_path_cold_ms {cold_s * 1e3:.1f}")
    print(f"RESULT eval_shortest_path_warm_ms {warm_s * 1e3:.2f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
