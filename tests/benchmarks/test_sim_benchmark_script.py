"""``benchmarks/sim_throughput.py`` runs end to end (real sim process) and ends with its figures.

Only the shape of the output is checked, never a speed: timings belong to the benchmark.
"""

from __future__ import annotations

import math

import pytest
from bench_helpers import read_results, run_benchmark

FIGURES = ("sim_engine_steps_per_s", "sim_bare_steps_per_s", "sim_engine_vs_bare_ratio",
           "sim_ros_lockstep_steps_per_s", "sim_ros_vs_engine_ratio", "sim_ros_real_time_factor",
           "sim_ros_lost_steps", "sim_ros_node_cpu_us_per_step", "sim_ros_client_cpu_us_per_step")


@pytest.mark.integration
def test_the_benchmark_ends_with_one_result_line_per_figure() -> None:
    done = run_benchmark("sim_throughput.py", "--steps", "40", "--repeat", "1")
    results = read_results(done.stdout, FIGURES)
    for name in FIGURES[:6]:
        assert math.isfinite(results[name]) and results[name] > 0, (name, results[name])
    assert results["sim_ros_lost_steps"] == 0
    # CPU per lockstep step: the client's (process_time) and the node's (/proc, 10 ms ticks)
    assert results["sim_ros_client_cpu_us_per_step"] > 0
    assert results["sim_ros_node_cpu_us_per_step"] >= 0
    engine, bare = results["sim_engine_steps_per_s"], results["sim_bare_steps_per_s"]
    assert results["sim_engine_vs_bare_ratio"] == pytest.approx(engine / bare, abs=0.01)
