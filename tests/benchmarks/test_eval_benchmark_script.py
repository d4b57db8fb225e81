"""``benchmarks/eval_throughput.py`` runs end to end (real sim process) and ends with its figures.

Only the shape of the output is checked, never a speed: timings belong to the benchmark.
"""

from __future__ import annotations

import math

import pytest
from bench_helpers import read_results, run_benchmark

FIGURES = ("eval_dwa_inprocess_episodes_per_s", "eval_dwa_ros_episodes_per_s",
           "eval_ros_vs_inprocess_ratio", "eval_dwa_control_steps_per_s",
           "eval_inprocess_env_steps_per_s", "eval_dwa_vs_env_steps_ratio",
           "eval_shortest_path_cold_ms", "eval_shortest_path_warm_ms")


@pytest.mark.integration
def test_the_benchmark_ends_with_one_result_line_per_figure() -> None:
    done = run_benchmark("eval_throughput.py", "--episodes", "1", "--max-steps", "10",
                         "--repeat", "1")
    results = read_results(done.stdout, FIGURES)
    assert all(math.isfinite(v) and v > 0 for v in results.values()), results
    ros = results["eval_dwa_ros_episodes_per_s"]
    local = results["eval_dwa_inprocess_episodes_per_s"]
    assert results["eval_ros_vs_inprocess_ratio"] == pytest.approx(ros / local, abs=0.01)
    # The same pairs through both transports: the sim is deterministic, so the same outcomes.
    rounds = [line for line in done.stderr.splitlines() if line.startswith("round ")]
    assert len(rounds) == 2 and rounds[0].split("outcomes")[1] == rounds[1].split("outcomes")[1]
