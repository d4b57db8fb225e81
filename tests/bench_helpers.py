"""What the benchmark scripts' tests share: running a script as the user does, and the
``RESULT <name> <value>`` lines that must end its output. Free of ROS (tests/metrics uses it)."""

from __future__ import annotations

import os
import subprocess
import sys
from collections.abc import Sequence
from pathlib import Path

BENCHMARKS = Path(__file__).resolve().parents[1] / "benchmarks"


def run_benchmark(script: str, *args: str) -> subprocess.CompletedProcess[str]:
    """``benchmarks/<script> *args`` run to its end (ROS discovery kept on localhost); it must
    exit 0."""
    env = dict(os.environ, ROS_AUTOMATIC_DISCOVERY_RANGE="LOCALHOST")
    done = subprocess.run([sys.executable, str(BENCHMARKS / script), *args], capture_output=True,
                          text=True, timeout=300, env=env, check=False)
    assert done.returncode == 0, done.stderr
    return done


def read_results(stdout: str, figures: Sequence[str]) -> dict[str, float]:
    """The ``RESULT`` lines ending ``stdout``: one per figure, in the order of ``figures``."""
    tail = stdout.rstrip("\n").splitlines()[-len(figures):]
    assert all(line.startswith("RESULT ") for line in tail), stdout
    found = {name: float(value) for _, name, value in (line.split() for line in tail)}
    assert tuple(found) == tuple(figures), found
    return found
