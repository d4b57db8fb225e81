"""ROS 2 isolation for the sim's integration tests (helpers in tests/ros_helpers.py).

When a test fails, the output of each sim it used is attached to its report.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path

import pytest
from ros_helpers import (  # noqa: F401 - the ros_client fixture and the report hook are shared
    ARENA_MJCF,
    pytest_runtest_makereport,
    RosClient,
    SimProcess,
    next_domain,
    ros_client,
    sim_command,
)
from std_srvs.srv import Empty



@dataclass
class SharedSim:
    """A lockstep sim in the arena world, shared by a module's tests, and their client."""

    sim: SimProcess
    client: RosClient
    domain: int


@pytest.fixture(scope="session")
def arena_mjcf(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("worlds") / "arena.xml"
    path.write_text(ARENA_MJCF)
    return path


@pytest.fixture
def domain() -> int:
    return next_domain()


@pytest.fixture
def start_sim(tmp_path: Path) -> Iterator[Callable[..., SimProcess]]:
    """Start sims (``command``, ``domain``, optional extra environment); all are stopped
    afterwards."""
    started: list[SimProcess] = []

    def start(command: list[str], domain: int,
              env_extra: dict[str, str] | None = None) -> SimProcess:
        sim = SimProcess(command, domain, tmp_path / f"sim{len(started)}.log", env_extra)
        started.append(sim)
        return sim

    try:
        yield start
    finally:
        for sim in started:
            sim.stop()


@pytest.fixture(scope="module")
def _module_sim(arena_mjcf: Path, tmp_path_factory: pytest.TempPathFactory
                ) -> Iterator[SharedSim]:
    domain = next_domain()
    log = tmp_path_factory.mktemp("shared_sim") / "sim.log"
    sim = SimProcess(sim_command("-p", f"world:={arena_mjcf}", "-p", "robot:=jackal"), domain, log)
    client = None
    try:
        client = RosClient(domain)
        yield SharedSim(sim, client, domain)
    finally:
        if client is not None:
            client.close()
        sim.stop()


@pytest.fixture
def shared_sim(_module_sim: SharedSim) -> Iterator[SharedSim]:
    """The module's sim and its client; afterwards the test's subscriptions are dropped and
    the sim is put back to lockstep, unpaused, with sampled start and goal."""
    assert _module_sim.sim.proc.poll() is None, "the shared sim died"
    try:
        yield _module_sim
    finally:
        client = _module_sim.client
        client.drop_subscriptions()
        if _module_sim.sim.proc.poll() is None:
            client.call(Empty, "/unpause_physics")
            client.set_parameters("/sim", {"clock_mode": "lockstep", "start_pose": [],
                                           "goal": []})
