"""``benchmarks/sim_throughput.py`` runs end to end (real sim process) and ends with its figures.

Only the shape of the output is checked, never a speed: timings belong to the benchmark.
"""

from __future__ import annotations

import math
import os
import subprocess
import sys
from pathlib import Path

import pytest

SCRIPT = Path(__file__).resolve().parents[2] / "benchmarks" / "sim_throughput.py"
FIGURES = ("sim_engine_steps_per_s", "sim_bare_steps_per_s", "sim_engine_vs_bare_ratio",
           "sim_ros_lockstep_steps_per_s", "sim_ros_vs_engine_ratio", "sim_ros_real_time_factor",
           "sim_ros_lost_steps")


@pytest.mark.integration
def test_the_benchmark_ends_with_one_result_line_per_figure() -> None:
    env = dict(os.environ, ROS_AUTOMATIC_DISCOVERY_RANGE="LOCALHOST")
    done = subprocess.run([sys.executable, str(SCRIPT), "--steps", "40", "--repeat", "1"],
                          capture_output=True, text=True, timeout=300, env=env, check=False)
    assert done.returncode == 0, done.stderr
    lines = done.stdout.rstrip("\n").splitlines()
    tail = lines[-len(FIGURES):]
    assert all(line.startswith("RESULT ") for line in tail), done.stdout
    results = {name: float(value) for _, name, value in (line.split() for line in tail)}
    assert tuple(results) == FIGURES
    for name in FIGURES[:-1]:
        assert math.isfinite(results[name]) and results[name] > 0, (name, results[name])
    assert results["sim_ros_lost_steps"] == 0
    engine, bare = results["sim_engine_steps_per_s"], results["sim_bare_steps_per_s"]
    assert results["sim_engine_vs_bare_ratio"] == pytest.approx(engine / bare, abs=0.01)
