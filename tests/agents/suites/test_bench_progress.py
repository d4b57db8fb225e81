"""What ``pic4rl-bench`` shows while it runs: one progress bar that ends at its total (the
episodes run; a cell that failed for good takes its missing ones off), and pair sets named after
their file or seed."""

from __future__ import annotations

import re
from collections import Counter
from pathlib import Path

import pytest
import yaml

from pic4rl_agents.suites import cell as benchcell
from pic4rl_agents.suites import runner as bench
from pic4rl_agents.suites.suite import Cell, load_suite
from pic4rl_metrics.bags.inputs import METADATA

REPO = Path(__file__).resolve().parents[3]
PAIRS = REPO / "pic4rl_agents" / "data" / "goals_indoor_test.json"


def _suite(tmp_path: Path, **task: object) -> Path:
    (tmp_path / "env.yaml").write_text(yaml.safe_dump({
        "sim": {"ros__parameters": {"robot": "jackal", "world": "indoor", "world_variant": 0}},
        "nav_env": {"ros__parameters": {"task": "goToPose", "sensor": "lidar"}}}))
    (tmp_path / "suite.yaml").write_text(yaml.safe_dump({
        "suite": "s", "bags": "bags", "tasks": [{"name": "goto", "env": "env.yaml", **task}]}))
    return tmp_path / "suite.yaml"


class _StepPool:
    """A pool whose cells finish one episode per poll (a bag with its metadata.yaml) and are
    ready only at the poll that finishes their last: the driver sees each cell's last episode
    only as the cell ends. ``failing`` cells stop after one episode and fail."""

    name, workers = "steps", 2

    def __init__(self, root: Path, failing: tuple[str, ...] = ()) -> None:
        self.root, self.failing, self.polls = root, failing, Counter[str]()
        self.cells: dict[str, Cell] = {}

    def submit(self, cell: Cell) -> str:
        self.cells[cell.name] = cell
        return cell.name

    def ready(self, handles: list[str], timeout: float) -> list[str]:
        out = []
        for name in handles:
            cell = self.cells[name]
            last = 1 if name in self.failing else benchcell.expected_episodes(cell)
            bag = self.root / name / cell.agent / f"episode_{self.polls[name]:04d}"
            bag.mkdir(parents=True)
            (bag / METADATA).write_text("{}\n")
            self.polls[name] += 1
            if self.polls[name] == last:
                out.append(name)
        return out

    def error(self, handle: str, cell: Cell) -> str | None:
        return "RuntimeError: boom" if handle in self.failing else None

    def close(self, handles: list[str]) -> None:
        pass


def _last_bar(err: str) -> tuple[int, int, str]:
    """(n, total, postfix) of the bar's last drawing on stderr."""
    *_, last = (part for part in re.split(r"[\r\n]", err) if part.startswith("episodes:"))
    match = re.search(r"\| *(\d+)/(\d+) \[.*?(?:, (cells [^\]]*))?\]\s*$", last)
    assert match, last
    return int(match[1]), int(match[2]), match[3] or ""


def test_the_episode_bar_ends_at_the_episodes_run(tmp_path: Path,
                                                  capsys: pytest.CaptureFixture) -> None:
    suite = load_suite(_suite(tmp_path, baselines=["dwa", "proportional"],
                              pairs=[{"file": str(PAIRS), "episodes": 3}]))
    failed = bench.dispatch_cells(suite, _StepPool(suite.root), retries=0, progress=True)
    assert failed == {}
    run = sum(len(benchcell.state(suite.root, c).finished) for c in suite.cells)
    err = capsys.readouterr().err
    assert (run, _last_bar(err)) == (6, (6, 6, "cells 2/2"))
    assert "cells:" not in err  # one bar: nothing to interleave with


def test_a_cell_that_failed_for_good_takes_its_missing_episodes_off_the_total(
        tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    suite = load_suite(_suite(tmp_path, baselines=["dwa", "proportional"],
                              pairs=[{"file": str(PAIRS), "episodes": 3}]))
    bad = suite.cells[0].name
    failed = bench.dispatch_cells(suite, _StepPool(suite.root, failing=(bad,)), retries=0,
                                  progress=True)
    assert failed == {bad: "RuntimeError: boom"}
    assert _last_bar(capsys.readouterr().err) == (3 + 1, 3 + 1, "cells 2/2, 1 failed")


def test_pair_sets_are_named_after_their_file_or_seed(tmp_path: Path) -> None:
    suite = load_suite(_suite(tmp_path, baselines=["dwa"], seed=7, pairs=[
        "paper", {"file": str(PAIRS)}, {"random": 3, "kind": "any", "seed": 4},
        {"episodes": 2}]))
    assert [c.pairs.label for c in suite.cells] == [
        "paper", "file_goals_indoor_test", "random3_any_s4", "episodes2_s7"]
    assert suite.cells[-1].name == "goto-dwa-indoor0-jackal-episodes2_s7-r0"
