"""The crowd's ``people`` topic is the same through both transports: the sim node with
``crowd.count`` 5 and the in-process engine, one seed and one command sequence, record equal
``geometry_msgs/PoseArray`` messages (issue 41 item 1), and the env's ``people`` reading (what
the ``orca`` baseline reads) is the same each step (item 4)."""

from __future__ import annotations

import tempfile
from pathlib import Path

import numpy as np
from rosbags.rosbag2 import Reader
from rosbags.typesys import Stores, get_typestore

from pic4rl_bridge.recording import make_env

ROOT = Path(__file__).resolve().parents[2]
CONFIG = ROOT / "config" / "env_goto_lidar.yaml"
STORE = get_typestore(Stores.ROS2_JAZZY)
CROWD = {"crowd.count": 5}


def _people(make, bags: str, run: str) -> tuple[list[np.ndarray], list[np.ndarray]]:
    """Each recorded ``people`` message of one 12-step episode as (x, y, qz, qw) rows, and
    each step's ``people`` reading of the env's frame."""
    env = make({"record.enabled": True, "record.bags_dir": bags, "record.run": run,
                "record.storage": "sqlite3", "episode_max_steps": 12})
    rng = np.random.default_rng(4)
    readings = []
    try:
        env.reset(seed=9)
        for _ in range(12):
            readings.append(env.unwrapped.frame.readings["people"])
            _, _, terminated, truncated, _ = env.step(
                rng.uniform(-1, 1, env.action_space.shape).astype(np.float32))
            if terminated or truncated:
                break
    finally:
        env.close()
    out = []
    with Reader(Path(bags) / run / "episode_0000") as reader:
        for conn, _, raw in reader.messages():
            if conn.topic == "/people":
                msg = STORE.deserialize_cdr(raw, conn.msgtype)
                out.append(np.array([(p.position.x, p.position.y, p.orientation.z,
                                      p.orientation.w) for p in msg.poses]))
    return out, readings


def test_the_people_topic_is_the_same_through_both_transports(domain: int, start_sim) -> None:
    start_sim(domain, "--params-file", str(CONFIG), "-p", "crowd.count:=5")
    with tempfile.TemporaryDirectory() as bags:
        ros, ros_read = _people(lambda o: make_env(CONFIG, transport="ros", sim=CROWD,
                                                   overrides={**o, "ros.domain_id": domain}),
                                bags, "ros")
        local, local_read = _people(lambda o: make_env(CONFIG, overrides=o, sim=CROWD), bags,
                                    "local")
    assert len(ros_read) == len(local_read) >= 10
    for i, (a, b) in enumerate(zip(ros_read, local_read)):
        assert a.shape == (5, 3)
        np.testing.assert_array_equal(a, b, err_msg=f"people readings differ at step {i}")
    assert np.abs(ros_read[-1][:, :2] - ros_read[0][:, :2]).max() > 0.3
    assert len(ros) == len(local) >= 10
    assert all(a.shape == (5, 4) for a in ros)
    for i, (a, b) in enumerate(zip(ros, local)):
        np.testing.assert_array_equal(a, b, err_msg=f"people differ at message {i}")
    assert np.abs(ros[-1][:, :2] - ros[0][:, :2]).max() > 0.3  # they walk
