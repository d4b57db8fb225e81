"""``benchmarks/env_throughput.py`` runs end to end (real sim process) and ends with its figures.

Only the shape of the output is checked, never a speed: timings belong to the benchmark.
"""

from __future__ import annotations

import math
import os
import subprocess
import sys
from pathlib import Path

import pytest

SCRIPT = Path(__file__).resolve().parents[2] / "benchmarks" / "env_throughput.py"
FIGURES = ("env_bare_engine_steps_per_s", "env_inprocess_steps_per_s", "env_ros_steps_per_s",
           "env_ros_vs_inprocess_ratio", "env_inprocess_vs_bare_ratio",
           "env_recording_overhead_inprocess", "env_recording_overhead_ros")


@pytest.mark.integration
def test_the_benchmark_ends_with_one_result_line_per_figure() -> None:
    env = dict(os.environ, ROS_AUTOMATIC_DISCOVERY_RANGE="LOCALHOST")
    done = subprocess.run([sys.executable, str(SCRIPT), "--steps", "30", "--repeat", "1"],
                          capture_output=True, text=True, timeout=300, env=env, check=False)
    assert done.returncode == 0, done.stderr
    tail = done.stdout.rstrip("\n").splitlines()[-len(FIGURES):]
    assert all(line.startswith("RESULT ") for line in tail), done.stdout
    results = {name: float(value) for _, name, value in (line.split() for line in tail)}
    assert tuple(results) == FIGURES
    for name in FIGURES[:5]:
        assert math.isfinite(results[name]) and results[name] > 0, (name, results[name])
    ros, local = results["env_ros_steps_per_s"], results["env_inprocess_steps_per_s"]
    assert results["env_ros_vs_inprocess_ratio"] == pytest.approx(ros / local, abs=0.01)
    assert all(math.isfinite(results[name]) for name in FIGURES[5:])
