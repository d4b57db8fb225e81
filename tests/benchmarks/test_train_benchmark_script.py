"""``benchmarks/train_throughput.py --quick`` trains in process and through real sim processes,
one env and two, and ends with its figures.

Only the shape of the output is checked, never a speed: timings belong to the benchmark. One
off-policy and one on-policy algorithm keep it short (each algorithm adds a sim and three models);
the benchmark's default run covers all four.
"""

from __future__ import annotations

import math
import os
import random
import subprocess
import sys
from pathlib import Path

import pytest

SCRIPT = Path(__file__).resolve().parents[2] / "benchmarks" / "train_throughput.py"
ALGORITHMS = ("td3", "ppo")


@pytest.mark.integration
@pytest.mark.slow
def test_the_quick_benchmark_prints_positive_figures_for_each_algorithm_asked() -> None:
    domain = random.SystemRandom().randint(1, 100)
    env = dict(os.environ, ROS_AUTOMATIC_DISCOVERY_RANGE="LOCALHOST")
    done = subprocess.run([sys.executable, str(SCRIPT), "--quick", "--domain", str(domain),
                           "--algorithms", *ALGORITHMS, "--nenvs2-ros", "td3"],
                          capture_output=True, text=True, timeout=180, env=env, check=False)
    assert done.returncode == 0, done.stderr[-4000:]
    lines = [line.split() for line in done.stdout.splitlines() if line.startswith("RESULT ")]
    assert lines, done.stdout
    assert all(len(parts) == 3 for parts in lines), lines
    results = {name: float(value) for _, name, value in lines}
    assert len(results) == len(lines), "a figure printed twice"
    for name, value in results.items():
        assert math.isfinite(value) and value > 0, (name, value)
    for algorithm in ALGORITHMS:
        for figure in ("inprocess_steps_per_s", "ros_steps_per_s", "ros_over_inprocess",
                       "nenvs2_inprocess_steps_per_s", "nenvs2_over_1_inprocess"):
            assert f"train_{algorithm}_{figure}" in results, (algorithm, figure, done.stdout)
    assert "train_td3_nenvs2_over_1_ros" in results
    assert "train_ppo_nenvs2_over_1_ros" not in results  # only where asked
    assert not any(name.startswith(("train_ddpg_", "train_sac_")) for name in results)
    td3 = {key: results[f"train_td3_{key}"] for key in
           ("ros_steps_per_s", "inprocess_steps_per_s", "ros_over_inprocess")}
    assert td3["ros_over_inprocess"] == pytest.approx(
        td3["ros_steps_per_s"] / td3["inprocess_steps_per_s"], rel=0.02, abs=0.01)
    assert done.stdout.rstrip("\n").splitlines()[-1].startswith("RESULT ")
