"""A ROS 2 stack as the agent, lockstep: how many times faster than real time it runs.

The example node (``examples/ros_gap_follower_node.py``, plain rclpy) drives the sim node
through ``pic4rl-run stack``'s driver (``pic4rl_agents.stack.driver.drive_stack``, recording
on, ``restart: never``), on the paper's 5 indoor pairs (``config/env_goto_lidar.yaml``) and on
10 BARN worlds, one episode each (``config/env_barn.yaml``; a run per world, as a suite's
cells). The ratio is simulated time (steps × the control period) over wall time, twice: over
the whole runs (the sim's and the node's start-ups included) and over the episodes alone
(``reset`` to the last step; each run's first reset left out: it waits for the sim to be
up). Where an episode step's wall time goes, in the driving process: waiting for the stack's
``cmd_vel`` (the stack's compute and a hop each way), the sim's step (the forwarded command to
the next full frame), the env (observation, reward), and between steps (the recording
wrapper, the loop). ``--profile FILE`` also writes the driving process's cProfile of the
pairs' run. Target: >= 50 x real time. The last lines are ``RESULT <name> <value>``.

    .venv/bin/python benchmarks/stack_throughput.py
"""

from __future__ import annotations

import argparse
import cProfile
import os
import pstats
import sys
import tempfile
import time
from collections import defaultdict
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import yaml

from pic4rl_agents.launch.simproc import domain_lease
from pic4rl_agents.stack import driver
from pic4rl_agents.stack.spec import stack_spec
from pic4rl_bridge.transports.ros_transport import RosTransport

ROOT = Path(__file__).resolve().parents[1]
PAIRS = ROOT / "pic4rl_agents" / "data" / "goals_indoor_test.json"
NODE = ROOT / "examples" / "ros_gap_follower_node.py"
BARN_WORLDS = tuple(range(0, 300, 30))  # 10 of BARN's 300 worlds
TARGET = 50.0


class Clock:
    """Wall seconds spent in the patched methods, the episodes' wall seconds (each from its
    reset's start to its last step's end, the recorder's work between included), their steps
    and sim seconds."""

    def __init__(self) -> None:
        self.seconds: dict[str, float] = defaultdict(float)
        self.steps = 0
        self.sim_s = 0.0
        self.episodes_s = 0.0
        self.first_resets_s = 0.0  # each run's first reset: it waits for the sim to be up
        self.first = True  # the next reset is a run's first
        self._start: float | None = None
        self._end = 0.0

    def wrap(self, owner: type, name: str, key: str,
             after: Callable[[Any], None] | None = None,
             before: Callable[[], None] | None = None) -> Callable[[], None]:
        original = getattr(owner, name)

        def timed(obj: Any, *args: Any, **kwargs: Any) -> Any:
            if before is not None:
                before()
            start = time.perf_counter()
            try:
                return original(obj, *args, **kwargs)
            finally:
                self.seconds[key] += time.perf_counter() - start
                if after is not None:
                    after(obj)

        setattr(owner, name, timed)
        return lambda: setattr(owner, name, original)

    def count_step(self, env: Any) -> None:
        self.steps += 1
        self.sim_s += env.scenario.robot.control_dt_s
        self._end = time.perf_counter()

    def episode_starts(self) -> None:
        self.episode_ends()
        self._start = time.perf_counter()

    def reset_done(self, env: Any) -> None:
        if self.first and self._start is not None:
            self.first_resets_s += time.perf_counter() - self._start
        self.first = False

    def episode_ends(self) -> None:
        if self._start is not None:
            self.episodes_s += self._end - self._start
        self._start = None


@contextmanager
def timing() -> Iterator[Clock]:
    clock = Clock()
    undo = [clock.wrap(driver.StackEnv, "step", "env_step", clock.count_step),
            clock.wrap(driver.StackEnv, "reset", "reset", clock.reset_done,
                       before=clock.episode_starts),
            clock.wrap(driver.StackTransport, "step", "transport_step"),
            clock.wrap(RosTransport, "step", "sim_step")]
    try:
        yield clock
    finally:
        clock.episode_ends()
        for restore in undo:
            restore()


def _env(config: str, folder: Path, max_steps: int, variant: int | None) -> str:
    """``config`` with episodes of at most ``max_steps`` (in world ``variant``) in ``folder``."""
    data = yaml.safe_load((ROOT / "config" / config).read_text())
    data["nav_env"]["ros__parameters"]["episode_max_steps"] = max_steps
    if variant is not None:
        data["sim"]["ros__parameters"]["world_variant"] = variant
    (folder / config).write_text(yaml.safe_dump(data))
    return str(folder / config)


def _run(env: str, overrides: dict[str, Any], episodes: int, folder: Path) -> tuple[
        list[str], float]:
    stack = stack_spec({"command": f"{sys.executable} {NODE}", "name": "gap_node",
                        "restart": "never"}, "benchmark")
    start = time.perf_counter()
    with domain_lease() as domain:
        outcomes = driver.drive_stack(
            stack, env, overrides={"record.enabled": True, "record.bags_dir": str(folder),
                                   "record.run": "gap_node", **overrides},
            episodes=episodes, seed=0, domain=domain, cwd=ROOT, sim_file=folder / "sim.yaml")
    return outcomes, time.perf_counter() - start


def measure(name: str, runs: list[tuple[str, int | None, dict[str, Any], int]], max_steps: int,
            profile: str = "") -> dict[str, float]:
    """The runs' ratios and where an episode step's time went (µs a step); a run: its config
    file, world variant, env overrides and episodes."""
    profiler = cProfile.Profile() if profile else None
    wall, outcomes = 0.0, []
    with timing() as clock, tempfile.TemporaryDirectory(prefix="stack-bench-") as tmp:
        if profiler is not None:
            profiler.enable()
        for k, (config, variant, overrides, episodes) in enumerate(runs):
            folder = Path(tmp) / f"run{k}"
            folder.mkdir()
            env = _env(config, folder, max_steps, variant)
            clock.first = True
            done, seconds = _run(env, overrides, episodes, folder)
            outcomes += done
            wall += seconds
        if profiler is not None:
            profiler.disable()
            profiler.dump_stats(profile)
    s = clock.seconds
    episodes_s = clock.episodes_s - clock.first_resets_s
    per = 1e6 / max(clock.steps, 1)
    out = {"steps": clock.steps, "sim_s": clock.sim_s, "wall_s": wall,
           "episodes_wall_s": episodes_s, "ratio_whole": clock.sim_s / wall,
           "ratio_episodes": clock.sim_s / episodes_s,
           "stack_wait_us": (s["transport_step"] - s["sim_step"]) * per,
           "sim_step_us": s["sim_step"] * per,
           "env_us": (s["env_step"] - s["transport_step"]) * per,
           "between_us": (episodes_s - s["env_step"] - s["reset"] + clock.first_resets_s) * per,
           "reset_s": s["reset"] - clock.first_resets_s, "startup_s": wall - episodes_s}
    print(f"{name}: {len(outcomes)} episodes ({', '.join(sorted(set(outcomes)))}), "
          f"{clock.steps} steps = {clock.sim_s:.1f} s simulated in {wall:.1f} s wall "
          f"({episodes_s:.1f} s in episodes, {out['reset_s']:.1f} s of it in resets; "
          f"{out['startup_s']:.1f} s starting and stopping, each run's first reset included)")
    print(f"  sim time / wall time: {out['ratio_whole']:.1f} x whole runs, "
          f"{out['ratio_episodes']:.1f} x episodes alone (target {TARGET:g} x)")
    print(f"  a step: {out['stack_wait_us']:.0f} µs waiting for the stack's cmd_vel, "
          f"{out['sim_step_us']:.0f} µs the sim's step, {out['env_us']:.0f} µs the env, "
          f"{out['between_us']:.0f} µs between steps (the recorder, the loop)")
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--max-steps", type=int, default=500, help="per episode")
    parser.add_argument("--profile", default="", help="cProfile of the pairs' run to FILE")
    args = parser.parse_args()
    os.environ.setdefault("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")
    pairs = measure("paper pairs", [("env_goto_lidar.yaml", None, {
        "episodes.file": str(PAIRS), "episodes.ordered": True}, 5)], args.max_steps,
        args.profile)
    barn = measure("BARN worlds", [("env_barn.yaml", v, {}, 1) for v in BARN_WORLDS],
                   args.max_steps)
    if args.profile:
        pstats.Stats(args.profile).sort_stats("tottime").print_stats(12)
    for name, out in (("pairs", pairs), ("barn", barn)):
        for key in ("ratio_whole", "ratio_episodes", "stack_wait_us", "sim_step_us", "env_us",
                    "between_us"):
            print(f"RESULT stack_{name}_{key} {out[key]:.1f}")


if __name__ == "__main__":
    main()
