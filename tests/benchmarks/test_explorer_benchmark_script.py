"""``benchmarks/explorer_throughput.py`` runs end to end and ends with its figures.

Only the shape of the output is checked, never a speed: timings belong to the benchmark.
"""

from __future__ import annotations

import math

import pytest
from bench_helpers import read_results, run_benchmark

FIGURES = ("explorer_steps_per_s", "explorer_plans_per_100_steps",
           "explorer_ms_per_planning_step", "explorer_ms_per_other_step", "env_steps_per_s",
           "env_memory_steps_per_s", "memory_step_cost_ratio")


@pytest.mark.integration
def test_the_benchmark_ends_with_one_result_line_per_figure() -> None:
    done = run_benchmark("explorer_throughput.py", "--episodes", "1", "--max-steps", "20")
    results = read_results(done.stdout, FIGURES)
    assert all(math.isfinite(v) and v > 0 for v in results.values()), results
    assert results["memory_step_cost_ratio"] == pytest.approx(
        results["env_steps_per_s"] / results["env_memory_steps_per_s"], rel=0.01)
    assert results["explorer_plans_per_100_steps"] >= 100 / 20  # at least the first plan
