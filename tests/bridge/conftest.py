"""ROS 2 isolation for the bridge's integration tests (helpers in tests/ros_helpers.py): each
test gets its own DDS domain and sim processes that are always stopped; a failing test's report
carries the output of each sim it started."""

from __future__ import annotations

from collections.abc import Callable, Iterator
from pathlib import Path

import pytest
from ros_helpers import (  # noqa: F401 - the ros_client fixture and the report hook are shared
    ARENA_MJCF,
    pytest_runtest_makereport,
    SimProcess,
    next_domain,
    ros_client,
    sim_command,
)


@pytest.fixture
def domain() -> int:
    return next_domain()


@pytest.fixture
def arena(tmp_path: Path) -> Path:
    """A 10 m walled square with a crate at (3, 3) and a post at (-3, 3)."""
    path = tmp_path / "arena.xml"
    path.write_text(ARENA_MJCF)
    return path


@pytest.fixture
def start_sim(tmp_path: Path) -> Iterator[Callable[..., SimProcess]]:
    """Start ``pic4rl-sim --ros-args ARGS`` on ``domain``; every sim is stopped afterwards."""
    started: list[SimProcess] = []

    def start(domain: int, *ros_args: str) -> SimProcess:
        sim = SimProcess(sim_command(*ros_args), domain, tmp_path / f"sim{len(started)}.log")
        started.append(sim)
        return sim

    try:
        yield start
    finally:
        for sim in started:
            sim.stop()
