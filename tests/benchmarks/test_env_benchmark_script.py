"""``benchmarks/env_throughput.py`` runs end to end (real sim process) and ends with its figures.

Only the shape of the output is checked, never a speed: timings belong to the benchmark.
"""

from __future__ import annotations

import math

import pytest
from bench_helpers import read_results, run_benchmark

FIGURES = ("env_bare_engine_steps_per_s", "env_inprocess_steps_per_s", "env_ros_steps_per_s",
           "env_ros_vs_inprocess_ratio", "env_inprocess_vs_bare_ratio",
           "env_recording_overhead_inprocess", "env_recording_overhead_ros",
           "env_inprocess_cpu_us_per_step", "env_ros_cpu_us_per_step",
           "env_ros_sim_cpu_us_per_step")


@pytest.mark.integration
def test_the_benchmark_ends_with_one_result_line_per_figure() -> None:
    done = run_benchmark("env_throughput.py", "--steps", "30", "--repeat", "1")
    results = read_results(done.stdout, FIGURES)
    for name in FIGURES[:5]:
        assert math.isfinite(results[name]) and results[name] > 0, (name, results[name])
    ros, local = results["env_ros_steps_per_s"], results["env_inprocess_steps_per_s"]
    assert results["env_ros_vs_inprocess_ratio"] == pytest.approx(ros / local, abs=0.01)
    assert all(math.isfinite(results[name]) for name in FIGURES[5:])
    # CPU per step of the env's process (process_time) and of the sim node (/proc, 10 ms ticks)
    assert results["env_inprocess_cpu_us_per_step"] > 0 and results["env_ros_cpu_us_per_step"] > 0
    assert results["env_ros_sim_cpu_us_per_step"] >= 0
