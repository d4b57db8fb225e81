"""Fixtures of the agents' tests: one short in-process training run that the train,
exploration and tester tests read (copy it before changing it: the whole session shares it),
a DDS domain per integration test (``tests/ros_helpers.py``, whose report hook is shared), and
``pic4rl-run`` launchers that are always stopped.
Constants and helpers are in ``agents_helpers.py``.
"""

from __future__ import annotations

import contextlib
import io
from collections.abc import Callable, Iterator
from pathlib import Path

import pytest
from agents_helpers import (
    CHECKPOINT_STEPS,
    EVAL_STEPS,
    LIDAR_TD3,
    SHORT_EPISODES,
    TINY,
    TRAINED_STEPS,
    Launcher,
    TrainedRun,
)
from ros_helpers import (  # noqa: F401 - the report hook is shared
    next_domain,
    pytest_runtest_makereport,
)


@pytest.fixture(scope="session")
def trained_run(tmp_path_factory: pytest.TempPathFactory) -> TrainedRun:
    """``pic4rl-train`` in process on config/train_goto_lidar_td3.yaml: TD3, tiny nets, 300
    steps, checkpoints every 100 with replay buffers, an evaluation every 150, ε-greedy as
    shipped (0.2, decaying), TensorBoard on, episodes of at most 60 steps."""
    from pic4rl_agents.training import train

    runs = tmp_path_factory.mktemp("runs")
    stderr = io.StringIO()
    with contextlib.redirect_stderr(stderr):
        code = train.main([
            "--hyperparams", *TINY, "tensorboard:true",
            f"checkpoint.interval_steps:{CHECKPOINT_STEPS}",
            f"eval.interval_steps:{EVAL_STEPS}",
            "--env-kwargs", *SHORT_EPISODES,
            "-n", str(TRAINED_STEPS), "--run", "td3_tiny", "--no-progress",
            "--ros-args", "--params-file", str(LIDAR_TD3), "-p", f"runs_dir:={runs}"])
    return TrainedRun(runs / "td3_tiny", code, stderr.getvalue())


@pytest.fixture
def domain() -> int:
    return next_domain()


@pytest.fixture
def launch(tmp_path: Path) -> Iterator[Callable[..., Launcher]]:
    """Start ``pic4rl-run ARGS`` on a fresh domain; afterwards the launcher and anything it
    left behind (found by the tag) are stopped."""
    started: list[Launcher] = []

    def start(*args: str, domain: int | None = None) -> Launcher:
        log = tmp_path / f"launcher{len(started)}.log"
        started.append(Launcher.start(list(args), log,
                                      next_domain() if domain is None else domain))
        return started[-1]

    try:
        yield start
    finally:
        for launcher in started:
            launcher.stop()
