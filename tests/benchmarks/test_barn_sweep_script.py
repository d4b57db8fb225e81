"""``benchmarks/barn_sweep.py`` on 2 test worlds x 1 run ends with its figures, in process
and through sim nodes over ROS 2.

Only the shape of the output is checked, never a speed: timings belong to the benchmark.
"""

from __future__ import annotations

import math

import pytest
from bench_helpers import read_results, run_benchmark

FIGURES = tuple(f"barn_sweep_planner_{name}" for name in (
    "episodes", "seconds", "table_seconds", "episodes_per_s", "success"))


@pytest.mark.integration
def test_the_benchmark_ends_with_one_result_line_per_figure() -> None:
    done = run_benchmark("barn_sweep.py", "--worlds", "2", "--runs", "1", "--workers", "1")
    results = read_results(done.stdout, FIGURES)
    assert results["barn_sweep_planner_episodes"] == 2
    assert all(math.isfinite(v) and v > 0 for v in results.values()), results
    assert 0 <= results["barn_sweep_planner_success"] <= 1
    assert "BARN score" in done.stderr


@pytest.mark.integration
def test_through_sim_nodes_its_figures_are_named_ros() -> None:
    done = run_benchmark("barn_sweep.py", "--transport", "ros", "--worlds", "1", "--runs", "2",
                         "--workers", "1")
    names = tuple(n.replace("planner_", "planner_ros_") for n in FIGURES)
    results = read_results(done.stdout, names)
    assert results["barn_sweep_planner_ros_episodes"] == 2
    assert all(math.isfinite(v) and v > 0 for v in results.values()), results
