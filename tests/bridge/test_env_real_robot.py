"""The env over ROS 2 against a robot that is not pic4rl-sim (``fake_robot.py``, its own
process): scans published in other geometries observed alike, a scan that dies mid-episode
stopping the robot and aborting the episode, and a missing sensor named with its QoS."""

from __future__ import annotations

import math
import re
import sys
import time
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest
from nav_msgs.msg import Odometry
from rclpy.qos import QoSProfile, ReliabilityPolicy
from ros_helpers import SimProcess
from sensor_msgs.msg import LaserScan

from pic4rl_bridge.errors import TransportError
from pic4rl_bridge.recording import make_env
from pic4rl_metrics.tables.batch import compute

pytestmark = pytest.mark.integration

ROBOT = Path(__file__).with_name("fake_robot.py")
FULL = f"scan:{-math.pi!r}:{2 * math.pi / 360!r}:360"
ZERO_TO_TWO_PI = f"scan_b:0.0:{2 * math.pi / 360!r}:360"
HOKUYO = f"scan_c:{-0.75 * math.pi!r}:{1.5 * math.pi / 1080!r}:1081"


@pytest.fixture
def robot(tmp_path: Path):
    """Start ``fake_robot.py ARGS`` on a domain; stopped afterwards."""
    started: list[SimProcess] = []

    def start(domain: int, *args: str) -> SimProcess:
        proc = SimProcess([sys.executable, str(ROBOT), *args], domain,
                          tmp_path / f"robot{len(started)}.log")
        started.append(proc)
        return proc

    try:
        yield start
    finally:
        for proc in started:
            proc.stop()


def real_robot_env(domain: int, **overrides: object) -> gym.Env:
    """goToPose from LiDAR on a real robot's terms: no sim node, no reset service (the
    operator's goal starts an episode), rate stepping; recorded when ``record.enabled``."""
    return make_env({"task": "goToPose", "sensor": "lidar", "robot": "jackal"}, transport="ros",
                    overrides={"ros.domain_id": domain, "ros.sim_node": "",
                               "ros.reset_service": "", "ros.step_mode": "rate",
                               "ros.timeout_s": 10.0, "ros.operator_timeout_s": 20.0,
                               **overrides})


def test_scans_published_in_other_geometries_give_the_same_observation(domain, robot):
    """One world through 0..2pi and 270-degree (1081 beams) scans reads as through -pi..pi:
    the same sectors where they overlap, no return beyond the 270 degrees."""
    robot(domain, "--scan", FULL, "--scan", ZERO_TO_TWO_PI, "--scan", HOKUYO)
    observed = {}
    for topic in ("scan", "scan_b", "scan_c"):
        env = real_robot_env(domain, **{"topics.scan": topic, "ros.node_name": f"env_{topic}"})
        try:
            obs, _ = env.reset()
            observed[topic] = obs[:36]
        finally:
            env.close()
    full = observed["scan"]
    # the posts at 35 (seen across 40 degrees from the LiDAR 0.12 m ahead), -65 and 175 degrees
    assert full[21] < 1.0 and full[11] < 2.0 and full[35] < 1.7
    assert np.count_nonzero(full < 4.8) == 4
    np.testing.assert_allclose(observed["scan_b"], full, atol=1e-4)
    # 4 beams a degree find each sector's minimum a little nearer (by < 2 mm here)
    np.testing.assert_allclose(observed["scan_c"][5:31], full[5:31], atol=2e-3)
    assert np.all(observed["scan_c"][5:31] <= full[5:31] + 1e-4)
    np.testing.assert_array_equal(observed["scan_c"][np.r_[0:4, 32:36]], 10.0)


def test_a_scan_that_goes_silent_stops_the_robot_and_aborts_the_episode(
        domain, robot, ros_client, tmp_path):
    """The LiDAR dies after 10 commands: within ``ros.max_sensor_age_s`` (0.5 s, 5 control
    periods) the env sends a zero command, ends the episode as aborted naming /scan and its
    age, and the bag says so; the robot stays put."""
    robot(domain, "--scan", FULL, "--silence-after", "10")
    client = ros_client(domain)
    scans = client.collect("/scan", LaserScan,
                           QoSProfile(depth=5, reliability=ReliabilityPolicy.BEST_EFFORT))
    odom = client.collect("/odom", Odometry)
    env = real_robot_env(domain, **{"record.enabled": True, "record.bags_dir": str(tmp_path),
                                    "record.run": "stale", "episode_max_steps": 200,
                                    "max_linear_m_s": 0.4})
    try:
        env.reset()
        steps, done, info = 0, False, {}
        while not done:  # 0.2 m/s ahead
            *_, terminated, truncated, info = env.step(np.array([0.0, 0.0], np.float32))
            done, steps = terminated or truncated, steps + 1
        ended_ns = time.time_ns()
        client.spin_for(0.5)  # before close() sends its own stop: the abort stopped the robot
        still = [(m.pose.pose.position.x, m.twist.twist.linear.x) for m in odom[-5:]]
    finally:
        env.close()
    assert info["outcome"] == "aborted" and truncated and not terminated
    assert re.fullmatch(r"topic /scan: no message for \d\.\d\d s \(ros\.max_sensor_age_s 0\.5 s\)",
                        info["reason"]), info["reason"]
    assert all(v == 0.0 for v in info["reward_terms"].values())
    last = scans[-1].header.stamp
    silent_s = (ended_ns - (last.sec * 1_000_000_000 + last.nanosec)) / 1e9
    assert 0.5 <= silent_s < 0.5 + 0.5, silent_s  # the bound, plus a control period and load
    assert steps <= 9 + 5 + 3  # the scan stops after the 9th step's command (the reset's 1st)
    assert all(v == 0.0 for _, v in still) and len({x for x, _ in still}) == 1
    assert odom[-1].pose.pose.position.x > 0.1  # it had driven
    result = compute([tmp_path / "stale"])
    row = result.frame.to_dict("records")[0]
    assert row["outcome"] == "aborted" and math.isnan(row["success"])
    assert "aborted by the recorder (topic /scan: no message for" in row["warnings"]


@pytest.mark.bad_input
@pytest.mark.parametrize("robot_args, overrides, expected", [
    ([], {"ros.sensor_qos": "reliable"},
     r"topic /scan \(topics\.scan; 1 publisher\(s\) offering best effort, volatile: none "
     r"matches this env's reliable subscription \(ros\.sensor_qos: best_effort for a "
     r"sensor\)\): nothing within 3 s"),
    ([], {"topics.scan": "laser"},
     r"topic /laser \(topics\.scan; no publisher\): nothing within 3 s"),
    (["--no-odom"], {}, r"topic /odom \(topics\.pose; 1 publisher\(s\) offering reliable, "
     r"volatile\): nothing within 3 s"),  # advertised, silent
    (["--no-odom"], {"ros.step_mode": "lockstep"},
     r"topic /odom \(topics\.pose; 1 publisher\(s\) offering reliable, volatile\): nothing "
     r"within 3 s"),
    ([], {"ros.step_mode": "lockstep", "topics.scan": "laser"},
     r"topic /laser \(topics\.scan; no publisher\): nothing within 3 s"),
])
def test_a_missing_sensor_is_named_alone_with_its_publishers_qos(domain, robot, robot_args,
                                                                   overrides, expected):
    """Only the silent topic, in rate and lockstep stepping, with what the graph says of its
    publishers; the topics that did send are not named."""
    robot(domain, "--scan", FULL, *robot_args)
    env = real_robot_env(domain, **{"ros.timeout_s": 3.0, **overrides})
    try:
        with pytest.raises(TransportError) as err:
            env.reset()
    finally:
        env.close()
    assert re.fullmatch(expected, str(err.value)), str(err.value)
