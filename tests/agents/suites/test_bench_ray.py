"""``pic4rl-bench`` on Ray: docs/bench.md's cluster recipe as written (a head and a second
node on this machine), and a wrong address or bags folder said in one line, exit code 2,
within a bounded time."""

from __future__ import annotations

import contextlib
import os
import re
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import time
from collections.abc import Iterator
from pathlib import Path

import pytest
import yaml

from pic4rl_agents.suites import runner as bench

REPO = Path(__file__).resolve().parents[3]
PAIRS = REPO / "pic4rl_agents" / "data" / "goals_indoor_test.json"
RAY = Path(sys.executable).with_name("ray")


def _suite(tmp_path: Path) -> Path:
    """Two baseline cells of one short episode each."""
    (tmp_path / "env.yaml").write_text(yaml.safe_dump({
        "sim": {"ros__parameters": {"robot": "jackal", "world": "indoor", "world_variant": 0}},
        "nav_env": {"ros__parameters": {"task": "goToPose", "sensor": "lidar",
                                        "episode_max_steps": 30}}}))
    (tmp_path / "suite.yaml").write_text(yaml.safe_dump({
        "suite": "two", "tasks": [{"name": "goto", "env": "env.yaml",
                                   "baselines": ["proportional", "dwa"],
                                   "pairs": [{"file": str(PAIRS), "episodes": 1}]}]}))
    return tmp_path / "suite.yaml"


@pytest.fixture
def silent_port() -> Iterator[int]:
    """A port that accepts connections and never answers (not a Ray head)."""
    server = socket.socket()
    server.bind(("127.0.0.1", 0))
    server.listen(16)
    try:
        yield server.getsockname()[1]
    finally:
        server.close()


@pytest.mark.bad_input
def test_a_wrong_address_or_bags_folder_is_one_line_and_exit_2(
        tmp_path: Path, silent_port: int, capsys: pytest.CaptureFixture[str]) -> None:
    pytest.importorskip("ray")
    suite = _suite(tmp_path)
    closed = socket.socket()
    closed.bind(("127.0.0.1", 0))  # bound, not listening: refused
    port = closed.getsockname()[1]
    assert bench.main([str(suite), "--address", f"127.0.0.1:{port}"]) == 2
    assert capsys.readouterr().err == (
        f"pic4rl-bench: --address 127.0.0.1:{port}: no Ray cluster there (Connection refused); "
        "is `ray start --head` running on that machine and port?\n")
    closed.close()
    (tmp_path / "file").write_text("")
    assert bench.main([str(suite), "--local", "--bags", str(tmp_path / "file" / "bags")]) == 2
    assert capsys.readouterr().err == (
        f"pic4rl-bench: --bags: cannot write the suite's folder {tmp_path}/file/bags/two "
        "(NotADirectoryError: Not a directory)\n")

    # A port that takes the connection and never answers: Ray would retry for minutes.
    code = ("import sys; from pic4rl_agents.launch import raycluster; "
            "from pic4rl_agents.suites import runner as bench; raycluster.JOIN_S = 3; "
            f"sys.exit(bench.main([{str(suite)!r}, '--address', '127.0.0.1:{silent_port}']))")
    start = time.monotonic()
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          timeout=120, env={**os.environ, "PYTHONPATH": str(REPO)})
    assert done.returncode == 2 and time.monotonic() - start < 60
    assert done.stderr.splitlines()[-1] == (
        f"pic4rl-bench: --address 127.0.0.1:{silent_port}: no Ray cluster answered within 3 s; "
        "is it a Ray head's port (ray start --head --port)?")


def _start(args: list[str], env: dict[str, str], log: Path) -> subprocess.Popen[bytes]:
    return subprocess.Popen([str(RAY), "start", *args, "--block"], env=env,
                            stdout=log.open("wb"), stderr=subprocess.STDOUT,
                            start_new_session=True)


def _stop(proc: subprocess.Popen[bytes]) -> None:
    """The ``ray start --block`` and all it started (its process group), not ``ray stop``
    (which would stop every Ray of this machine)."""
    for sig in (signal.SIGTERM, signal.SIGKILL):
        with contextlib.suppress(ProcessLookupError):
            os.killpg(proc.pid, sig)
        with contextlib.suppress(subprocess.TimeoutExpired):
            proc.wait(timeout=20)
            return


@pytest.mark.heavy
@pytest.mark.ray
def test_the_cluster_recipe_runs_a_suite_on_two_nodes(tmp_path: Path) -> None:
    """docs/bench.md's three commands (each node of one CPU and in a temp dir of its own,
    ``--block`` so that the test stops exactly what it started): the bags folder is checked from both nodes, then the two
    cells run on the nodes' two CPUs."""
    pytest.importorskip("ray")
    probe = socket.socket()
    probe.bind(("", 0))
    port = probe.getsockname()[1]
    probe.close()
    env = {**os.environ, "PYTHONPATH": str(REPO), "RAY_USAGE_STATS_ENABLED": "0"}
    token = {**env, "RAY_AUTH_MODE": "token"}
    # Its own temp dir (short: Ray's socket paths), so that no other Ray on this machine
    # finds this cluster as "the current one" (/tmp/ray/ray_current_cluster), then or after.
    own = ["--num-cpus", "1", "--temp-dir", tempfile.mkdtemp(prefix="ray", dir="/tmp")]
    head = _start(["--head", "--port", str(port), *own], env, tmp_path / "head.log")
    nodes = [head]
    try:
        deadline = time.monotonic() + 120
        while not (found := re.search(r"ray start --address='([^']+)'",
                                      (tmp_path / "head.log").read_text())):
            assert time.monotonic() < deadline and head.poll() is None, (
                tmp_path / "head.log").read_text()
            time.sleep(0.2)
        address = found.group(1)
        nodes.append(_start(["--address", address, *own], token, tmp_path / "node.log"))
        status = ""
        while status.count("node_") < 2:  # both nodes joined
            assert time.monotonic() < deadline, status
            status = subprocess.run([str(RAY), "status", "--address", address], env=token,
                                    capture_output=True, text=True, timeout=60).stdout
            time.sleep(0.5)
        done = subprocess.run([str(RAY.with_name("pic4rl-bench")), str(_suite(tmp_path)),
                               "--address", address, "--bags", str(tmp_path / "bags"),
                               "--no-progress"], env=token, capture_output=True, text=True,
                              timeout=300)
    finally:
        for node in reversed(nodes):
            _stop(node)
        shutil.rmtree(own[-1], ignore_errors=True)
    assert done.returncode == 0, done.stderr
    assert done.stdout.count("| goto |") == 2 and "failed" not in done.stdout
    assert f"cells on Ray at {address}" in done.stderr
