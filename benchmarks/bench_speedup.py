"""``pic4rl-bench`` on this machine: a suite of 8 cells run by 2 local workers against 1.

The suite: DWA and proportional on goToPose with the Jackal's LiDAR in the indoor world
(``config/env_goto_lidar.yaml``, episodes of at most ``--max-steps`` steps), 4 pair sets of
``--episodes`` pairs each (the paper's indoor pairs, and random ``paper`` pairs from 3
seeds): 8 cells. Each run starts from an empty bags folder and includes the results pass;
the local process pool is used (``--local``), since Ray's own start-up would be timed too.
Per-cell cost (1 worker's time / 8) feeds docs/performance.md's scale estimate. Target: 2
workers >= 1.7x 1 worker. The last lines are ``RESULT <name> <value>``.

    .venv/bin/python benchmarks/bench_speedup.py
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

import yaml

from pic4rl_agents.suites.runner import bench_suite
from pic4rl_agents.suites.suite import load_suite

ROOT = Path(__file__).resolve().parents[1]
CONFIG = ROOT / "config" / "env_goto_lidar.yaml"
PAIRS = ROOT / "pic4rl_agents" / "data" / "goals_indoor_test.json"


def _suite(folder: Path, *, episodes: int, max_steps: int) -> Path:
    env = yaml.safe_load(CONFIG.read_text())
    env["nav_env"]["ros__parameters"]["episode_max_steps"] = max_steps
    (folder / "env.yaml").write_text(yaml.safe_dump(env))
    pairs = [{"file": str(PAIRS), "episodes": episodes}] + [
        {"random": episodes, "kind": "paper", "seed": s} for s in (1, 2, 3)]
    suite = {"suite": "speedup", "bags": str(folder / "bags"), "tasks": [
        {"name": "goto", "env": "env.yaml", "baselines": ["dwa", "proportional"],
         "pairs": pairs}]}
    (folder / "suite.yaml").write_text(yaml.safe_dump(suite))
    return folder / "suite.yaml"


def _time(workers: int, args: argparse.Namespace) -> tuple[float, int]:
    with tempfile.TemporaryDirectory(prefix="bench-speedup-") as tmp:
        suite = load_suite(_suite(Path(tmp), episodes=args.episodes, max_steps=args.max_steps))
        assert len(suite.cells) == 8
        start = time.perf_counter()
        table = bench_suite(suite, workers=workers, local=True, progress=False)
        seconds = time.perf_counter() - start
        assert all(r[-1] == "ok" for r in table.rows), table.rows
        return seconds, sum(int(r[table.header.index("n")]) for r in table.rows)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--episodes", type=int, default=3, help="episodes per cell")
    parser.add_argument("--max-steps", type=int, default=150)
    parser.add_argument("--repeat", type=int, default=2, help="best of (interleaved)")
    args = parser.parse_args()
    best = {1: float("inf"), 2: float("inf")}
    for _ in range(args.repeat):
        for workers in (1, 2):
            seconds, n = _time(workers, args)
            best[workers] = min(best[workers], seconds)
            print(f"{workers} worker(s): {seconds:.2f} s for 8 cells, {n} episodes")
    ratio = best[1] / best[2]
    print(f"RESULT bench_1_worker_s {best[1]:.2f}")
    print(f"RESULT bench_2_workers_s {best[2]:.2f}")
    print(f"RESULT bench_per_cell_s {best[1] / 8:.2f}")
    print(f"RESULT bench_speedup_2_workers {ratio:.2f}")


if __name__ == "__main__":
    main()
