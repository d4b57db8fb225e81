"""``pic4rl-test`` against a robot that is not pic4rl-sim (``tests/bridge/fake_robot.py``, its
own process), as a user drives a real one: a LiDAR that dies mid-episode is said in one line
and the episode is aborted, out of the success rate; a missing sensor is named with the QoS
its publishers offer and a real robot's hint, not "start pic4rl-sim"."""

from __future__ import annotations

import math
import os
import subprocess
import sys
from pathlib import Path

import pytest
from ros_helpers import SimProcess, next_domain, sim_env

pytestmark = pytest.mark.integration

ROOT = Path(__file__).resolve().parents[3]
ROBOT = ROOT / "tests" / "bridge" / "fake_robot.py"
SCAN = f"scan:{-math.pi!r}:{2 * math.pi / 360!r}:360"
REAL_ROBOT = """nav_env:
  ros__parameters:
    task: goToPose
    sensor: lidar
    transport: ros
    robot: jackal
    max_linear_m_s: 0.4
    ros.sim_node: ""
    ros.reset_service: ""
    ros.step_mode: rate
    ros.timeout_s: 3.0
"""


def run_tester(tmp_path: Path, robot_args: list[str], *params: str) -> tuple[int, str]:
    """``pic4rl-test --baseline proportional --episodes 1`` (a params file with no ``sim:``
    section) beside ``fake_robot.py ROBOT_ARGS``; its exit code and stderr."""
    domain = next_domain()
    config = tmp_path / "real_robot.yaml"
    config.write_text(REAL_ROBOT)
    robot = SimProcess([sys.executable, str(ROBOT), *robot_args], domain, tmp_path / "robot.log")
    try:
        done = subprocess.run(
            [sys.executable, "-m", "pic4rl_agents.testing.tester", "--baseline", "proportional",
             "--episodes", "1", "--bags", str(tmp_path / "bags"), "--run", "real",
             "--no-progress", "--ros-args", "--params-file", str(config), *params],
            cwd=ROOT, env={**sim_env(domain), "PYTHONPATH": os.environ.get("PYTHONPATH", "")},
            capture_output=True, text=True, timeout=120)
    finally:
        robot.stop()
    return done.returncode, done.stderr


def test_a_lidar_that_dies_mid_episode_is_one_line_and_an_aborted_episode(tmp_path: Path):
    code, err = run_tester(tmp_path, ["--scan", SCAN, "--silence-after", "10"])
    assert code == 0, err
    said = [line for line in err.splitlines() if "aborted" in line and "/scan" in line]
    assert len(said) == 1, err
    assert said[0].startswith("episode 0 aborted, the robot stopped: topic /scan: no message "
                              "for "), said[0]
    (bag,) = (tmp_path / "bags" / "real" / "proportional").glob("episode_*")
    from pic4rl_metrics.tables.batch import compute

    row = compute([bag]).frame.to_dict("records")[0]
    assert row["outcome"] == "aborted" and math.isnan(row["success"])


@pytest.mark.bad_input
def test_a_missing_sensor_names_it_with_its_qos_and_a_real_robots_hint(tmp_path: Path):
    code, err = run_tester(tmp_path, ["--scan", SCAN], "-p", "ros.sensor_qos:=reliable")
    assert code == 2
    lines = err.splitlines()
    (said,) = [line for line in lines if line.startswith("pic4rl-test: ")]
    assert said == ("pic4rl-test: topic /scan (topics.scan; 1 publisher(s) offering best "
                    "effort, volatile: none matches this env's reliable subscription "
                    "(ros.sensor_qos: best_effort for a sensor)): nothing within 3 s")
    hint = lines[lines.index(said) + 1]
    assert hint.startswith("  Is the robot publishing in ROS domain") and "topics." in hint
    assert "pic4rl-sim" not in err and "/odom" not in err
