"""One agent's BARN sweep, timed: the challenge's 50 test worlds x 10 runs (500 episodes) of
``config/suite_barn.yaml`` through ``pic4rl-bench``'s own machinery in process (the
``inprocess`` transport, cells on a local pool of ``--workers`` processes), every episode
recorded to a bag, then BARN's table from the bags alone. The official harness (ROS 1, Gazebo,
real time) needs hours for the same sweep.

    .venv/bin/python benchmarks/barn_sweep.py                    # the planner, 500 episodes
    .venv/bin/python benchmarks/barn_sweep.py --agent dwa --worlds 10 --runs 2
    .venv/bin/python benchmarks/barn_sweep.py --agent explorer   # the mapless explorer
    .venv/bin/python benchmarks/barn_sweep.py --agent barn_td3_explorer  # the learned agents
    .venv/bin/python benchmarks/barn_sweep.py --agent barn_td3_memory
    .venv/bin/python benchmarks/barn_sweep.py --runs 1 --set --bags bags/barn_untuned
    .venv/bin/python benchmarks/barn_sweep.py --transport ros --worlds 5 --runs 2  # sim nodes

``--transport ros`` drives each cell's own sim node over ROS 2 (in its own ROS domain), as
``config/suite_barn_demo.yaml`` does; its RESULT names end in ``_ros``.
``--set KEY=VALUE ...`` replaces the env file's ``baselines:`` section (its tuned settings)
with these (none: the baselines' defaults); ``--bags DIR`` keeps the bags and the results
files (``DIR/barn/results.md``) instead of a temporary folder.

Targets (docs/performance.md, issue 29): the 500 episodes in <= 3 min on this 2-core machine
in process, and in <= 15 min through the sim nodes over ROS 2. The table
is printed on stderr; the last lines are ``RESULT <name> <value>``: the wall-clock seconds of
the sweep (cells and table), of its results pass (table, report, figures), episodes per second
and the success rate.
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
import tempfile
import time
from pathlib import Path

import yaml

from pic4rl_agents.suites import runner as bench
from pic4rl_agents.suites import table as benchtable
from pic4rl_agents.suites.suite import PairSet, load_suite

SUITE = Path(__file__).resolve().parents[1] / "config" / "suite_barn.yaml"


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--agent", default="planner",
                        choices=("planner", "dwa", "explorer", "barn_td3_explorer",
                                 "barn_td3_memory"),
                        help="a baseline, or a shipped learned agent (checkpoints/)")
    parser.add_argument("--worlds", type=int, default=50, help="the first N test worlds")
    parser.add_argument("--runs", type=int, default=10, help="runs per world")
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--transport", choices=("inprocess", "ros"), default="inprocess",
                        help="ros: each cell drives its own sim node over ROS 2")
    parser.add_argument("--set", nargs="*", metavar="KEY=VALUE",
                        help="the baselines' settings instead of the env file's")
    parser.add_argument("--bags", help="keep the bags and results here")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory(prefix="barn_sweep_") as scratch:
        suite = load_suite(SUITE, bags_dir=args.bags or scratch)
        env = suite.cells[0].env
        if args.set is not None:
            data = yaml.safe_load(Path(env).read_text())
            data["baselines"] = {"ros__parameters": {
                k: yaml.safe_load(v) for k, v in (item.split("=", 1) for item in args.set)}}
            env = str(Path(scratch) / "env_barn.yaml")
            Path(env).write_text(yaml.safe_dump(data))
        pairs = PairSet(f"env{args.runs}", episodes=args.runs)
        cells = [dataclasses.replace(c, pairs=pairs, env=env, transport=args.transport,
                                     name=c.name.replace(c.pairs.label, pairs.label))
                 for c in suite.cells if c.agent == args.agent][:args.worlds]
        suite = dataclasses.replace(suite, cells=tuple(cells))
        episodes = len(cells) * args.runs
        start = time.perf_counter()  # bench.bench_suite's steps, the results pass timed apart
        bench.check_bags(suite.root)
        pool = bench.make_pool(suite.root, workers=args.workers, address=None, local=True)
        failed = bench.dispatch_cells(suite, pool, retries=suite.retries, progress=False)
        cells_s = time.perf_counter() - start
        table = benchtable.write_results(suite, failed)
        total = time.perf_counter() - start
        table_s = total - cells_s
    sys.stderr.write("\n".join(
        " | ".join(str(v) for v in row) for row in (table.header, *table.rows)) + "\n")
    cells = dict(zip(table.header, table.rows[0]))
    k, n = (int(v) for v in str(cells["success"]).split("/"))
    name = f"barn_sweep_{args.agent}" + ("_ros" if args.transport == "ros" else "")
    print(f"RESULT {name}_episodes {episodes}")
    print(f"RESULT {name}_seconds {total:.1f}")
    print(f"RESULT {name}_table_seconds {table_s:.1f}")
    print(f"RESULT {name}_episodes_per_s {episodes / total:.2f}")
    print(f"RESULT {name}_success {k / n:.3f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
