"""``pic4rl-bench``: a benchmark suite (agents and baselines × worlds × robots × pair sets ×
repetitions, see ``pic4rl_agents.suites.suite``) run as cells, each one ``pic4rl-test`` run,
then one results table and a leaderboard per task from the bags.

    pic4rl-bench config/suite_table1.yaml                 # a local Ray, or a process pool
    pic4rl-bench config/suite_table1.yaml --address auto  # join a running Ray cluster

Each cell is a Ray task when Ray is installed (``pip install '.[cluster]'``), else a process
of a local pool (said on stderr). A finished cell is skipped on rerun; a cell whose worker died
or that raised is tried again, keeping its finished bags; one that fails ``1 + retries`` times
is a row ``failed: <error>`` of the table, and the exit code is 1.
"""

from __future__ import annotations

import argparse
import logging
import multiprocessing
import os
import signal
import sys
import time
from collections import Counter, deque
from collections.abc import Sequence
from multiprocessing.connection import wait
from pathlib import Path
from typing import Any

from pic4rl_base import atomic
from pic4rl_base.entry import entry_point
from pic4rl_bridge.errors import BridgeError, ConfigError

from . import cell as bench_cell
from .suite import Cell, Suite, load_suite
from .table import SuiteTable, write_results

log = logging.getLogger(__name__)
POLL_S = 0.5


def _one_line(err: BaseException) -> str:
    text = str(err).strip().splitlines()
    return f"{type(err).__name__}: {text[0]}" if text else f"{type(err).__name__} (no message)"


def _cell_process(cell: Cell, root: Path) -> None:
    """A pool worker: one attempt at one cell; its error, if any, in ``<cell>/cell.error``."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # the parent stops its workers itself
    try:
        bench_cell.drive_cell(cell, root)
    except Exception as err:  # noqa: BLE001 - any failure of a cell is reported, not raised
        atomic.write_text(bench_cell.cell_dir(root, cell) / bench_cell.ERROR, _one_line(err))
        os._exit(1)


def _ray_cell(cell: Cell, root: str) -> str | None:
    """A Ray task: one attempt at one cell; its error in one line, or None."""
    try:
        bench_cell.drive_cell(cell, Path(root))
    except Exception as err:  # noqa: BLE001 - returned to the driver, which retries
        return _one_line(err)
    return None


def _write_probe(root: str, name: str) -> str | None:
    """Write ``<root>/<name>`` (where this process runs); why it cannot, or None."""
    try:
        Path(root).mkdir(parents=True, exist_ok=True)
        atomic.write_text(Path(root) / name, name)
    except OSError as err:
        return f"{type(err).__name__}: {err.strerror or err}"
    return None


def check_bags(root: Path) -> None:
    """``ConfigError`` naming the folder and the reason when this machine cannot write the
    suite's bags folder, before any cell starts."""
    error = _write_probe(str(root), ".pic4rl-bench-probe")
    if error is not None:
        raise ConfigError(f"--bags: cannot write the suite's folder {root} ({error})")
    (root / ".pic4rl-bench-probe").unlink()


class LocalPool:
    """Cells as processes of this machine, ``workers`` at a time, forked from this one after
    it imported what the cells need (``cell.preload``): no worker imports them again."""

    name = "a local process pool"

    def __init__(self, root: Path, workers: int) -> None:
        self.root, self.workers = root, workers
        self._ctx = multiprocessing.get_context("fork")

    def submit(self, cell: Cell) -> Any:
        bench_cell.preload(cell)  # once per kind of cell: later ones find them imported
        proc = self._ctx.Process(target=_cell_process, args=(cell, self.root),
                                 name=f"cell-{cell.name}", daemon=True)
        proc.start()
        return proc

    def ready(self, handles: Sequence[Any], timeout: float) -> list[Any]:
        done = set(wait([h.sentinel for h in handles], timeout=timeout))
        return [h for h in handles if h.sentinel in done]

    def error(self, handle: Any, cell: Cell) -> str | None:
        handle.join()
        if handle.exitcode == 0:
            return None
        path = bench_cell.cell_dir(self.root, cell) / bench_cell.ERROR
        return path.read_text().strip() if path.is_file() and handle.exitcode == 1 else (
            f"worker died (exit code {handle.exitcode})")

    def close(self, handles: Sequence[Any]) -> None:
        for h in handles:
            h.kill()
            h.join()


class RayPool:
    """Cells as Ray tasks (one CPU each): a local Ray of ``workers`` CPUs, or the cluster at
    ``address``."""

    def __init__(self, root: Path, workers: int, address: str | None) -> None:
        import ray

        from pic4rl_agents.launch import raycluster

        self._ray = ray
        raycluster.init(address, num_cpus=None if address else workers,
                        include_dashboard=False, log_to_driver=False, ignore_reinit_error=True)
        self.root = root
        self.workers = 10**6 if address else workers  # a cluster schedules by its own CPUs
        self.name = f"Ray at {address}" if address else f"a local Ray of {workers} CPUs"
        self._task = ray.remote(num_cpus=1, max_retries=0)(_ray_cell)
        if address:
            self.check_nodes()

    def check_nodes(self, timeout_s: float = 120.0) -> None:
        """Every node of the cluster writes a file into the bags folder, and this machine
        sees each: the cells' bags are written where each runs, never shipped back.
        ``ConfigError`` naming the node otherwise."""
        from ray.util.scheduling_strategies import NodeAffinitySchedulingStrategy

        probe = self._ray.remote(num_cpus=0, max_retries=0)(_write_probe)
        nodes = [n for n in self._ray.nodes() if n["Alive"]]
        names = [f".pic4rl-bench-node-{n['NodeID'][:12]}" for n in nodes]
        try:
            errors = self._ray.get([probe.options(scheduling_strategy=(
                NodeAffinitySchedulingStrategy(n["NodeID"], soft=False))).remote(
                    str(self.root), name) for n, name in zip(nodes, names)], timeout=timeout_s)
        except self._ray.exceptions.RayError as err:
            raise ConfigError(f"--address: the cluster's {len(nodes)} nodes could not all "
                              f"check the bags folder ({_one_line(err)})") from None
        for node, name, error in zip(nodes, names, errors):
            where = f"node {node['NodeManagerAddress']} ({node['NodeID'][:12]})"
            if error is None and not (self.root / name).is_file():
                error = "what it wrote is not in this machine's folder"
            if error is not None:
                raise ConfigError(f"--bags {self.root}: {where} cannot write the bags folder "
                                  f"({error}); every node must see it at the same path (e.g. "
                                  "NFS)")
            (self.root / name).unlink()

    def submit(self, cell: Cell) -> Any:
        return self._task.remote(cell, str(self.root))

    def ready(self, handles: Sequence[Any], timeout: float) -> list[Any]:
        done, _ = self._ray.wait(list(handles), num_returns=len(handles), timeout=timeout)
        return done

    def error(self, handle: Any, cell: Cell) -> str | None:
        try:
            return self._ray.get(handle)
        except self._ray.exceptions.RayError as err:
            return f"worker died: {_one_line(err)}"

    def close(self, handles: Sequence[Any]) -> None:
        for h in handles:
            self._ray.cancel(h, force=True)
        self._ray.shutdown()


def make_pool(root: Path, *, workers: int, address: str | None, local: bool) -> Any:
    """Ray when installed (and not ``local``), else the process pool, said on stderr."""
    if not local:
        try:
            import ray  # noqa: F401
        except ImportError:
            if address:
                raise ConfigError("--address: Ray is not installed; pip install "
                                  "'.[cluster]'") from None
            print(f"pic4rl-bench: Ray is not installed; running the cells in a local process "
                  f"pool of {workers} workers", file=sys.stderr)
        else:
            return RayPool(root, workers, address)
    return LocalPool(root, workers)


def dispatch_cells(suite: Suite, pool: Any, *, retries: int, progress: bool) -> dict[str, str]:
    """Run every unfinished cell of ``suite`` on ``pool``, retrying each failed one up to
    ``retries`` times; the errors of the cells that failed for good, by name. One progress
    bar (on stderr) counts the finished episodes, the cells in its postfix; a cell that failed
    for good takes its missing episodes off the total, so the bar ends at its total."""
    from tqdm import tqdm

    root = suite.root
    todo = deque(c for c in suite.cells if not bench_cell.state(root, c).done)
    expected = {c.name: bench_cell.expected_episodes(c) for c in suite.cells}
    counted = {c.name: expected[c.name] for c in suite.cells if c not in todo}
    ended = len(counted)
    bar = tqdm(total=sum(expected.values()), initial=sum(counted.values()), desc="episodes",
               unit="episode", disable=not progress, dynamic_ncols=True)
    running: dict[Any, Cell] = {}
    attempts: Counter[str] = Counter()
    failed: dict[str, str] = {}

    def count(cell: Cell) -> int:
        """Add ``cell``'s newly finished episodes to the bar; how many it has."""
        done = len(bench_cell.state(root, cell).finished)
        bar.update(done - counted.get(cell.name, 0))
        counted[cell.name] = done
        return done

    try:
        while todo or running:
            while todo and len(running) < pool.workers:
                cell = todo.popleft()
                attempts[cell.name] += 1
                running[pool.submit(cell)] = cell
            for handle in pool.ready(list(running), POLL_S):
                cell = running.pop(handle)
                error = pool.error(handle, cell)
                done = count(cell)  # its last episodes too, before it leaves the running
                if error is not None and attempts[cell.name] <= retries:
                    log.warning("%s: attempt %d failed (%s); trying again", cell.name,
                                attempts[cell.name], error)
                    todo.append(cell)
                    continue
                if error is not None:
                    failed[cell.name] = error
                    bar.total -= max(expected[cell.name] - done, 0)
                ended += 1
            for cell in running.values():
                count(cell)
            bar.set_postfix_str(f"cells {ended}/{len(suite.cells)}"
                                + (f", {len(failed)} failed" if failed else ""))
    finally:
        pool.close(list(running))
        bar.close()
    return failed


def bench_suite(suite: Suite, *, workers: int = 1, address: str | None = None,
              local: bool = False, retries: int | None = None,
              progress: bool = True) -> SuiteTable:
    """Run ``suite``'s unfinished cells and write its results; its table."""
    check_bags(suite.root)
    pool = make_pool(suite.root, workers=workers, address=address, local=local)
    log.info("%d cells on %s", len(suite.cells), pool.name)
    failed = dispatch_cells(suite, pool, retries=suite.retries if retries is None else retries,
                       progress=progress)
    return write_results(suite, failed)


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="pic4rl-bench", description=__doc__.split("\n\n")[0])
    parser.add_argument("suite", help="the suite file (YAML)")
    parser.add_argument("--bags", help="bags directory (default: the suite's 'bags', or bags)")
    parser.add_argument("--workers", type=int, default=os.cpu_count() or 1,
                        help="cells at a time on this machine (default: its cores)")
    parser.add_argument("--address", help="a Ray cluster to join (e.g. auto, or HOST:6379)")
    parser.add_argument("--local", action="store_true",
                        help="a local process pool even when Ray is installed")
    parser.add_argument("--retries", type=int, help="override the suite's retries")
    parser.add_argument("--no-progress", action="store_true")
    return parser


@entry_point("pic4rl-bench", BridgeError,
             interrupted="interrupted; finished episodes are kept, a rerun resumes")
def main(argv: Sequence[str] | None = None) -> int:
    """Run the suite; print its table (markdown); exit 1 if a cell failed, 2 for bad input."""
    from pic4rl_agents.runs.console import console_logging

    args = build_parser().parse_args(argv)
    if args.workers < 1:
        raise ConfigError(f"--workers {args.workers}: expected a positive number")
    suite = load_suite(args.suite, bags_dir=args.bags)
    with console_logging(__name__):
        start = time.monotonic()
        table = bench_suite(suite, workers=args.workers, address=args.address,
                            local=args.local, retries=args.retries,
                            progress=not args.no_progress)
    sys.stdout.write((suite.root / "results.md").read_text())
    for error in table.bag_errors:
        print(f"error: {error}", file=sys.stderr)
    print(f"results: {', '.join(str(f) for f in table.files)} "
          f"({time.monotonic() - start:.1f} s)", file=sys.stderr)
    bad = any(r[-1] != "ok" for r in table.rows) or bool(table.bag_errors)
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
