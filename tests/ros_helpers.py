"""ROS 2 isolation shared by the integration tests (tests/sim, tests/bridge).

Every test gets DDS domains of its own (a random base per session plus a counter, discovery
kept on localhost), sims run as real processes in their own process group and are always
stopped (``LIVE`` lists those running, for failure reports), and a test talks to them through
its own ``rclpy.Context`` on the same domain.
"""

from __future__ import annotations

import itertools
import os
import random
import signal
import subprocess
import sys
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import pytest
import rclpy
from rclpy.executors import SingleThreadedExecutor
from rclpy.parameter import Parameter
from rclpy.parameter_client import AsyncParameterClient
from rclpy.qos import QoSProfile
from world_helpers import walled_square_mjcf

_DOMAIN_BASE = random.SystemRandom().randrange(1, 101)
_DOMAINS = itertools.count()
LIVE: list[SimProcess] = []
_CLIENT_NAMES = itertools.count()

ARENA_MJCF = walled_square_mjcf(5.0, """
    <geom name="crate" type="box" pos="3 3 0.5" size="0.5 0.5 0.5"/>
    <geom name="post" type="cylinder" pos="-3 3 0.5" size="0.3 0.5"/>
""")
"""A 10 m walled square with a crate at (3, 3) and a post at (-3, 3): fast to start, and
known free space (the robot may drive from (-2, 0) along +x)."""


def next_domain() -> int:
    """A ROS domain id in [1, 101] that no other test of this session uses."""
    return 1 + (_DOMAIN_BASE + next(_DOMAINS)) % 101


def sim_env(domain: int, extra: dict[str, str] | None = None) -> dict[str, str]:
    env = dict(os.environ, ROS_DOMAIN_ID=str(domain), ROS_AUTOMATIC_DISCOVERY_RANGE="LOCALHOST")
    env.update(extra or {})
    return env


class SimProcess:
    """A sim started as its own process group; stdout and stderr go to ``log_path``."""

    def __init__(self, command: list[str], domain: int, log_path: Path,
                 env_extra: dict[str, str] | None = None) -> None:
        self.command, self.domain, self.log_path = command, domain, log_path
        self._log = log_path.open("wb")
        self.proc = subprocess.Popen(command, env=sim_env(domain, env_extra), stdout=self._log,
                                     stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL,
                                     start_new_session=True)
        LIVE.append(self)

    @property
    def output(self) -> str:
        return self.log_path.read_text(errors="replace")

    def wait(self, timeout_s: float) -> int:
        return self.proc.wait(timeout=timeout_s)

    def stop(self) -> int | None:
        """SIGINT (a clean shutdown), then SIGKILL to the whole group if it lingers."""
        if self.proc.poll() is None:
            os.killpg(self.proc.pid, signal.SIGINT)
            try:
                self.proc.wait(timeout=10)
            except subprocess.TimeoutExpired:
                os.killpg(self.proc.pid, signal.SIGKILL)
                self.proc.wait(timeout=10)
        self._log.close()
        if self in LIVE:
            LIVE.remove(self)
        return self.proc.returncode


def sim_command(*ros_args: str) -> list[str]:
    """The sim as ``python -m pic4rl_sim.node --ros-args ...``."""
    return [sys.executable, "-m", "pic4rl_sim.node", "--ros-args", *ros_args]


class RosClient:
    """A test's own context, node and executor on ``domain``."""

    def __init__(self, domain: int) -> None:
        self.context = rclpy.Context()
        rclpy.init(context=self.context, domain_id=domain)
        self.node = rclpy.create_node(f"sim_test_client_{next(_CLIENT_NAMES)}",
                                      context=self.context)
        self.executor = SingleThreadedExecutor(context=self.context)
        self.executor.add_node(self.node)
        self._param_clients: dict[str, AsyncParameterClient] = {}
        self._subscriptions: list[Any] = []

    def spin_until(self, predicate: Callable[[], bool], timeout_s: float = 10.0) -> bool:
        deadline = time.monotonic() + timeout_s
        while not predicate():
            if time.monotonic() > deadline:
                return False
            self.executor.spin_once(timeout_sec=0.02)
        return True

    def spin_for(self, seconds: float) -> None:
        self.spin_until(lambda: False, seconds)

    def collect(self, topic: str, msg_type: Any, qos: QoSProfile | int = 10,
                timeout_s: float = 10.0) -> list[Any]:
        """Every message received on ``topic`` from now on, in arrival order; returns once a
        publisher is matched (lockstep sims publish only when stepped: a message sent before
        the match would be lost)."""
        inbox: list[Any] = []
        sub = self.node.create_subscription(msg_type, topic, inbox.append, qos)
        self._subscriptions.append(sub)
        assert self.spin_until(lambda: sub.get_publisher_count() > 0, timeout_s), (
            f"no publisher on {topic}")
        return inbox

    def drop_subscriptions(self) -> None:
        for sub in self._subscriptions:
            self.node.destroy_subscription(sub)
        self._subscriptions.clear()

    def call(self, srv_type: Any, name: str, timeout_s: float = 10.0) -> Any:
        client = self.node.create_client(srv_type, name)
        try:
            assert client.wait_for_service(timeout_sec=timeout_s), f"no service {name}"
            future = client.call_async(srv_type.Request())
            assert self.spin_until(future.done, timeout_s), f"{name} did not answer"
            return future.result()
        finally:
            self.node.destroy_client(client)

    def set_parameters(self, node_name: str, values: dict[str, Any],
                       timeout_s: float = 10.0) -> list[Any]:
        """Set ``values`` on ``node_name`` through its parameter service; the results (each
        with ``successful`` and ``reason``). An empty list is sent as a double array."""
        client = self._param_clients.get(node_name)
        if client is None:
            client = self._param_clients[node_name] = AsyncParameterClient(self.node, node_name)
            assert client.wait_for_services(timeout_sec=timeout_s), f"no {node_name} params"
        params = [Parameter(k, Parameter.Type.DOUBLE_ARRAY, []) if v == []
                  else Parameter(k, value=v) for k, v in values.items()]
        future = client.set_parameters(params)
        assert self.spin_until(future.done, timeout_s), "set_parameters did not answer"
        return list(future.result().results)

    def close(self) -> None:
        self.executor.shutdown()
        self.node.destroy_node()
        self.context.try_shutdown()




@pytest.fixture
def ros_client() -> Iterator[Callable[[int], RosClient]]:
    """Clients on given domains; all are shut down afterwards."""
    clients: list[RosClient] = []

    def make(domain: int) -> RosClient:
        clients.append(RosClient(domain))
        return clients[-1]

    try:
        yield make
    finally:
        for client in clients:
            client.close()


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_makereport(item: pytest.Item, call: pytest.CallInfo[None]) -> Iterator[None]:
    """Attach the output of every sim still running to a failed test's report (imported by
    the conftests that start sims)."""
    outcome = yield
    report = outcome.get_result()
    if report.failed:
        for sim in list(LIVE):
            report.sections.append((f"sim {' '.join(sim.command[-6:])} output", sim.output))
