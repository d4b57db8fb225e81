"""``pic4rl-test --agent`` against a robot without a simulator (``transport: ros``,
``ros.sim_node: ""``): a real rclpy process is the robot and its operator. The agent's
training config carries a ``sim:`` section (indoor, variant 0); none of it reaches the bags:
no world, no shortest path, no straight line from a map, no ``sim:`` in the run's config, and
SPL's optimal path falls back to the start-goal distance."""

from __future__ import annotations

import math
import subprocess
import sys
from pathlib import Path

import pytest
import yaml
from agents_helpers import ROOT
from ros_helpers import SimProcess, sim_env

from pic4rl_metrics.tables.batch import compute

pytestmark = pytest.mark.integration

TD3_LIDAR = ROOT / "checkpoints" / "td3_lidar"
ROBOT = Path(__file__).resolve().parent / "plain_robot.py"
REAL = ["transport:ros", "ros.sim_node:", "ros.reset_service:", "ros.step_mode:rate",
        "ros.operator_timeout_s:60", "ros.timeout_s:60"]


def run_tester(argv: list[str], domain: int) -> tuple[int, str, str]:
    """``pic4rl-test argv`` as its own process, as a user runs it."""
    done = subprocess.run([sys.executable, "-m", "pic4rl_agents.testing.tester", *argv],
                          env=sim_env(domain), capture_output=True, text=True, timeout=300,
                          check=False)
    return done.returncode, done.stdout, done.stderr


def test_a_run_without_a_simulator_records_no_world_facts(tmp_path: Path, domain: int) -> None:
    robot = SimProcess([sys.executable, str(ROBOT)], domain, tmp_path / "robot.log")
    try:
        code, out, err = run_tester([
            "--agent", str(TD3_LIDAR), "--episodes", "2", "--bags", str(tmp_path / "bags"),
            "--run", "real", "--no-progress",
            "--env-kwargs", *REAL, "episode_max_steps:5"], domain)
    finally:
        robot.stop()
    assert code == 0, err + robot.output
    assert "episodes: 2 episodes without a simulator" in err
    assert "td3_lidar" in out
    run = tmp_path / "bags" / "real"
    config = yaml.safe_load((run / "td3_lidar" / "config.yaml").read_text())
    assert "sim" not in config and config["nav_env"]["ros__parameters"]["robot"] == "jackal"
    result = compute([run])
    assert not result.failed and len(result.episodes) == 2
    for episode, row in zip(result.episodes, result.results):
        facts = episode.facts
        assert facts.world in ("", None), facts.world
        assert facts.shortest_path_m is None and facts.straight_line_m is None
        assert facts.goal is not None
        straight = math.dist(facts.start[:2], facts.goal)
        assert row.metrics.optimal_path_m == pytest.approx(straight, abs=1e-6)


@pytest.mark.bad_input
@pytest.mark.parametrize(("flags", "kwargs", "given"), [
    (["--random", "3"], [], "--random 3"),
    ([], ["episodes.file:p.json"], "episodes.file p.json")])
def test_drawn_or_filed_pairs_are_refused_without_a_simulator(
        tmp_path: Path, flags: list[str], kwargs: list[str], given: str) -> None:
    """Only a simulator can put the robot at a start: one line, exit 2, nothing driven."""
    code, out, err = run_tester(["--agent", str(TD3_LIDAR), "--bags", str(tmp_path), *flags,
                                 "--env-kwargs", *REAL, *kwargs], domain=0)
    assert code == 2 and out == ""
    assert err.splitlines() == [
        f"pic4rl-test: {given}: a run without a simulator (transport ros, ros.sim_node '') "
        "cannot set starts and goals; the operator sends each goal on topics.goal"]
    assert not list(tmp_path.iterdir())
