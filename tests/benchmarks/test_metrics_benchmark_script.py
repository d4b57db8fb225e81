"""``benchmarks/metrics_throughput.py`` runs end to end on tiny bags and ends with its figures.

Only the shape of the output is checked, never a speed: timings belong to the benchmark,
measured side by side in one run, not to unit tests.
"""

from __future__ import annotations

import importlib.util
import math
import sys
from pathlib import Path
from types import ModuleType

import pytest
from bench_helpers import read_results

from pic4rl_metrics.synthetic.synthetic import straight_line, write_episode_bag

SCRIPT = Path(__file__).resolve().parents[2] / "benchmarks" / "metrics_throughput.py"
FIGURES = (
    "bags", "messages", "metrics_msgs_per_s", "rosbags_read_msgs_per_s",
    "metrics_vs_rosbags_ratio",
)  # fmt: skip


@pytest.fixture(scope="module")
def bench() -> ModuleType:
    spec = importlib.util.spec_from_file_location("metrics_throughput", SCRIPT)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # dataclasses look their module up
    spec.loader.exec_module(module)
    return module


def _results(stdout: str) -> dict[str, float]:
    """The trailing ``RESULT <name> <value>`` lines, which must end the output."""
    figures = read_results(stdout, FIGURES)
    assert all(math.isfinite(v) and v > 0 for v in figures.values()), figures
    return figures


def test_synthetic_run_ends_with_parseable_figures(bench: ModuleType, capsys) -> None:
    assert bench.main(["--episodes", "2", "--duration", "5", "--repeat", "1", "--no-real"]) == 0
    out = capsys.readouterr()
    figures = _results(out.out)
    assert figures["bags"] == 2
    # Per bag: 101 poses at 20 Hz on /ground_truth, /odom and /cmd_vel, 51 scans (10 Hz),
    # goal, facts and outcome.
    assert figures["messages"] == 2 * (3 * 101 + 51 + 3)
    assert "real-robot bags: no" in out.out
    assert "run 1/1: metrics" in out.err and "run 1/1: rosbags" in out.err


def test_given_bags_replace_the_synthetic_set(bench: ModuleType, capsys, tmp_path: Path) -> None:
    bag = write_episode_bag(tmp_path / "one", straight_line(0.5, 2.0))
    assert bench.main(["--bags", str(bag), "--repeat", "2"]) == 0
    figures = _results(capsys.readouterr().out)
    assert figures["bags"] == 1
    assert figures["messages"] == 3 * 21  # /ground_truth, /odom, /cmd_vel at 10 Hz


def test_a_path_with_no_bag_is_an_error(bench: ModuleType, capsys, tmp_path: Path) -> None:
    assert bench.main(["--bags", str(tmp_path / "missing")]) == 1
    assert "no such file or directory" in capsys.readouterr().err
