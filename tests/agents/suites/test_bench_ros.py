"""``transport: ros`` suites side by side: each cell holds a ROS domain of its own (never the
user's), and a worker SIGKILLed mid-cell takes its sim with it (leaving no temporary folder);
the retry finishes the cell."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
import yaml

from pic4rl_agents.launch import simproc

pytestmark = pytest.mark.integration
REPO = Path(__file__).resolve().parents[3]
PAIRS = REPO / "pic4rl_agents" / "data" / "goals_indoor_test.json"


def _suite(folder: Path, name: str) -> Path:
    """A suite of one ros cell: the proportional baseline, 6 episodes of at most 300 steps."""
    folder.mkdir()
    (folder / "env.yaml").write_text(yaml.safe_dump({
        "sim": {"ros__parameters": {"robot": "jackal", "world": "indoor", "world_variant": 0}},
        "nav_env": {"ros__parameters": {"task": "goToPose", "sensor": "lidar",
                                        "episode_max_steps": 300}}}))
    (folder / "suite.yaml").write_text(yaml.safe_dump({
        "suite": name, "bags": "bags", "transport": "ros", "retries": 1, "tasks": [
            {"name": "goto", "env": "env.yaml", "baselines": ["proportional"],
             "pairs": [{"file": str(PAIRS), "episodes": 6}]}]}))
    return folder / "suite.yaml"


def _children(pid: int) -> list[int]:
    path = Path(f"/proc/{pid}/task/{pid}/children")
    return [int(p) for p in path.read_text().split()] if path.exists() else []


def _alive(pid: int) -> bool:
    try:
        return Path(f"/proc/{pid}/stat").read_text().split(") ")[1][0] != "Z"
    except (FileNotFoundError, IndexError):
        return False


def _domain_of(pid: int) -> int:
    env = dict(item.split("=", 1) for item in
               Path(f"/proc/{pid}/environ").read_text().split("\0") if "=" in item)
    return int(env["ROS_DOMAIN_ID"])


@pytest.mark.heavy
def test_two_ros_suites_hold_their_own_domains_and_a_killed_worker_takes_its_sim(
        tmp_path: Path, domain: int) -> None:
    (tmp_path / "tmp").mkdir()
    env = {**os.environ, "PYTHONPATH": str(REPO), "ROS_DOMAIN_ID": str(domain),
           "ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST", "TMPDIR": str(tmp_path / "tmp")}
    procs = [subprocess.Popen([sys.executable, "-m", "pic4rl_agents.suites.runner",
                               str(_suite(tmp_path / name, name)), "--local", "--workers", "1",
                               "--no-progress"], env=env, stdout=subprocess.PIPE,
                              stderr=subprocess.PIPE, text=True) for name in ("a", "b")]
    try:
        sims: dict[int, int] = {}  # the worker's pid: its sim's, both suites' at once
        deadline = time.monotonic() + 120
        while len(sims) < 2:
            assert time.monotonic() < deadline and all(p.poll() is None for p in procs), [
                p.communicate() for p in procs]
            sims = {w: s for p in procs for w in _children(p.pid) for s in _children(w)
                    if "pic4rl_sim.node" in Path(f"/proc/{s}/cmdline").read_text()}
            time.sleep(0.05)
        domains = {_domain_of(s) for s in sims.values()}
        assert len(domains) == 2 and domain not in domains
        assert domains <= set(simproc.DOMAIN_IDS)

        worker_a = next(w for w in sims if w in _children(procs[0].pid))
        os.kill(worker_a, signal.SIGKILL)
        gone = time.monotonic() + 5
        while _alive(sims[worker_a]):
            assert time.monotonic() < gone, "the killed worker's sim is still running"
            time.sleep(0.05)
        outputs = [p.communicate(timeout=240) for p in procs]
    finally:
        for p in procs:
            p.kill()
    assert [p.returncode for p in procs] == [0, 0], outputs
    assert "attempt 1 failed (worker died (exit code -9)); trying again" in outputs[0][1]
    for out, _ in outputs:
        assert "| goto | proportional |" in out and "| 6 |" in out
    assert not list((tmp_path / "tmp").glob("pic4rl-bench-*"))  # no temporary folder left


def test_a_lease_skips_held_domains_and_the_users_own(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("ROS_DOMAIN_ID", "100")
    with simproc.domain_lease(base=100) as first, simproc.domain_lease() as second:
        assert first != 100 and second not in (first, 100)
        assert {first, second} <= set(simproc.DOMAIN_IDS)
    with simproc.domain_lease(base=100) as again:  # released: free again
        assert again == first
