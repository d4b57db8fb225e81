"""Env steps per second: through ROS 2, in process, and the bare engine; recording on and off.

One run, one task (goToPose with the Jackal's 360-beam LiDAR in the seeded ``indoor`` world,
``config/env_goto_lidar.yaml``), the same actions everywhere (the robot turns on the spot, so
episodes last ``--steps`` steps and nothing but stepping is timed):

- bare engine: ``Engine.step`` + ``Engine.scan`` + ``Engine.wheel_odometry``, the floor;
- in-process env: ``NavEnv`` over the engine in this process, recording off and on;
- ROS 2 env: ``NavEnv`` over the ``sim`` node in another process (lockstep), recording off
  and on.

Loops run interleaved, best of ``--repeat``; recording writes sqlite3 bags to a temporary
directory. Targets (docs/performance.md): ROS-bridged env >= 0.5 x the in-process env,
recording overhead <= 10 %. The last lines are ``RESULT <name> <value>``; among them the CPU
per step of the env's process and of the sim node (least over the rounds), which a shared
machine's load moves less than the rates.

    .venv/bin/python benchmarks/env_throughput.py
"""

from __future__ import annotations

import argparse
import os
import random
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

import gymnasium as gym
import numpy as np
from _sim import cpu_s, start_sim, stop_sim

import pic4rl_bridge  # noqa: F401 - registers the envs
from pic4rl_sim.engine.core import Engine
from pic4rl_sim.engine.geometry import Twist2D

CONFIG = Path(__file__).resolve().parents[1] / "config" / "env_goto_lidar.yaml"
ENV_ID = "pic4rl/GoToPoseLidar-v0"
TURN = np.array([-1.0, 0.5], dtype=np.float32)  # v = 0, w = 0.5 rad/s: never ends early
SEED = 0


def env_loop(env: gym.Env, steps: int, cpu: dict[str, float] | None = None) -> float:
    """Seconds for one episode of ``steps`` steps (the reset not timed); ``cpu`` gets the
    CPU seconds of this process (``env``) and of the sim (``sim``, pid ``cpu["pid"]``) over
    the same steps."""
    env.reset(seed=SEED)
    own, sim = time.process_time(), cpu_s(int(cpu["pid"])) if cpu else 0.0
    start = time.perf_counter()
    for _ in range(steps):
        env.step(TURN)
    seconds = time.perf_counter() - start
    if cpu is not None:
        cpu["env"], cpu["sim"] = time.process_time() - own, cpu_s(int(cpu["pid"])) - sim
    return seconds


def bare_loop(engine: Engine, steps: int) -> float:
    engine.reset(seed=SEED)
    command = Twist2D(0.0, 0.0, 0.5)
    start = time.perf_counter()
    for _ in range(steps):
        engine.step(command)
        engine.scan()
        engine.wheel_odometry()
    return time.perf_counter() - start


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--steps", type=int, default=1000, help="steps per timed episode")
    parser.add_argument("--repeat", type=int, default=5, help="best of this many episodes")
    args = parser.parse_args(argv)
    os.environ.setdefault("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")
    domain = random.randint(1, 100)
    sim = start_sim(domain, "--params-file", str(CONFIG))
    bags = tempfile.TemporaryDirectory(prefix="env_throughput_")
    common = {"episode_max_steps": args.steps, "ros.domain_id": domain}
    record = {"record.enabled": True, "record.bags_dir": bags.name}
    envs = {
        "inprocess": gym.make(ENV_ID, config=CONFIG, overrides=common),
        "inprocess_rec": gym.make(ENV_ID, config=CONFIG,
                                  overrides={**common, **record, "record.run": "inprocess"}),
        "ros": gym.make(ENV_ID, config=CONFIG, transport="ros", overrides=common),
        "ros_rec": gym.make(ENV_ID, config=CONFIG, transport="ros",
                            overrides={**common, **record, "record.run": "ros"}),
    }
    engine = envs["inprocess"].unwrapped.transport.engine
    cpu = {name: {"pid": sim.pid} for name in envs}
    loops: dict[str, Callable[[], float]] = {
        name: (lambda env=env, name=name: env_loop(env, args.steps, cpu[name]))
        for name, env in envs.items()}
    loops["bare"] = lambda: bare_loop(engine, args.steps)
    try:
        best = dict.fromkeys(loops, float("inf"))
        least = {name: {"env": float("inf"), "sim": float("inf")} for name in envs}
        for round_ in range(args.repeat):
            for name, loop in loops.items():
                best[name] = min(best[name], loop())
                for side, seconds in cpu.get(name, {}).items():
                    if side != "pid":
                        least[name][side] = min(least[name][side], seconds)
            print(f"round {round_ + 1}/{args.repeat}: " + ", ".join(
                f"{n} {args.steps / t:.0f}/s" for n, t in best.items()), file=sys.stderr)
    finally:
        for env in envs.values():
            env.close()
        stop_sim(sim)
        bags.cleanup()
    rate = {name: args.steps / t for name, t in best.items()}
    print(f"RESULT env_bare_engine_steps_per_s {rate['bare']:.0f}")
    print(f"RESULT env_inprocess_steps_per_s {rate['inprocess']:.0f}")
    print(f"RESULT env_ros_steps_per_s {rate['ros']:.0f}")
    print(f"RESULT env_ros_vs_inprocess_ratio {rate['ros'] / rate['inprocess']:.2f}")
    print(f"RESULT env_inprocess_vs_bare_ratio {rate['inprocess'] / rate['bare']:.2f}")
    print(f"RESULT env_recording_overhead_inprocess "
          f"{rate['inprocess'] / rate['inprocess_rec'] - 1:.3f}")
    print(f"RESULT env_recording_overhead_ros {rate['ros'] / rate['ros_rec'] - 1:.3f}")
    # CPU per step (least over the rounds): the env's process and the sim node's.
    for name in ("inprocess", "ros"):
        print(f"RESULT env_{name}_cpu_us_per_step {1e6 * least[name]['env'] / args.steps:.0f}")
    print(f"RESULT env_ros_sim_cpu_us_per_step {1e6 * least['ros']['sim'] / args.steps:.0f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
