"""No silent reset: a simulator whose physics diverges (and puts the robot back at its start)
ends the episode visibly, in process and through ROS 2: truncated, ``info["outcome"] ==
"diverged"`` with the reason, zero reward, and ``diverged`` as the bag's outcome.

The divergence is real, not mocked: a world with a 1 µg ball on a spring of stiffness 1e12 N/m
(away from the robot, touching nothing) blows MuJoCo's solver up in the first physics step.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from rosbags.rosbag2 import Reader
from world_helpers import walled_square_mjcf

from pic4rl_bridge.env import NavEnv
from pic4rl_bridge.recording import make_env

ROOT = Path(__file__).resolve().parents[2]
CONFIG = ROOT / "config" / "env_goto_lidar.yaml"
UNSTABLE_MJCF = walled_square_mjcf(5.0, """
    <body name="spring" pos="4 4 0.5">
      <joint name="spring" type="slide" axis="0 0 1" stiffness="1e12" springref="1"/>
      <geom type="sphere" size="0.05" mass="1e-6" contype="0" conaffinity="0"/>
    </body>
""", model="unstable")
EPISODE = {"start": [-2.0, 0.0, 0.0], "goal": [0.0, 0.0]}
FORWARD = np.array([0.0, 0.0], np.float32)


@pytest.fixture
def unstable(tmp_path: Path) -> Path:
    path = tmp_path / "unstable.xml"
    path.write_text(UNSTABLE_MJCF)
    return path


def _assert_diverged(step: tuple, bag: Path) -> None:
    _, reward, terminated, truncated, info = step
    assert (terminated, truncated) == (False, True)
    assert info["outcome"] == "diverged" and info["is_success"] is False
    assert info["reason"].startswith("physics diverged at t=")
    assert reward == 0.0 and set(info["reward_terms"].values()) == {0.0}
    with Reader(bag) as reader:
        assert reader.storage.metadata.custom["outcome"] == "diverged"
        outcome = [c for c in reader.connections if c.topic == "/episode/outcome"]
        assert [c.msgcount for c in outcome] == [1]


def test_a_divergence_in_process_ends_the_episode_as_diverged(unstable, tmp_path, caplog):
    env = make_env(CONFIG, sim={"world": str(unstable)},
                   overrides={"record.enabled": True, "record.bags_dir": str(tmp_path / "bags"),
                              "record.run": "r"})
    try:
        env.reset(seed=0, options=EPISODE)
        with caplog.at_level("ERROR"):
            step = env.step(FORWARD)
        with pytest.raises(Exception, match="after the episode ended"):
            env.step(FORWARD)
    finally:
        env.close()
    _assert_diverged(step, tmp_path / "bags" / "r" / "episode_0000")
    assert "physics diverged" in caplog.text


def test_a_stable_world_never_reports_a_fault(tmp_path):
    env = NavEnv(CONFIG)
    try:
        env.reset(seed=0)
        for _ in range(5):
            *_, info = env.step(FORWARD)
            assert "reason" not in info and env.transport.fault is None
    finally:
        env.close()


@pytest.mark.integration
def test_a_divergence_in_the_sim_node_ends_the_ros_episode_as_diverged(
        domain, start_sim, unstable, tmp_path):
    sim = start_sim(domain, "--params-file", str(CONFIG), "-p", f"world:={unstable}")
    env = make_env(CONFIG, transport="ros", sim={"world": str(unstable)},
                   overrides={"ros.domain_id": domain, "record.enabled": True,
                              "record.bags_dir": str(tmp_path / "bags"), "record.run": "r"})
    try:
        env.reset(seed=0, options=EPISODE)
        step = env.step(FORWARD)
        env.reset(seed=1, options=EPISODE)  # the next episode starts normally
    finally:
        env.close()
    _assert_diverged(step, tmp_path / "bags" / "r" / "episode_0000")
    assert "physics diverged at t=" in sim.output
