"""UWB ranging through both transports (issue 40 item 3): the sim node with ``uwb.enabled``
and two anchors publishes a ``sensor_msgs/Range`` per anchor and one for the goal's tag each
step and the anchors' positions latched; a bag records them when ``record.topics`` names
them; they equal the in-process engine's for one seed and one command sequence, and the
bridge's readings ``uwb_<anchor>`` decode them."""

from __future__ import annotations

import tempfile
from pathlib import Path

import numpy as np
from rosbags.rosbag2 import Reader
from rosbags.typesys import Stores, get_typestore

from pic4rl_base.geometry import Pose2D
from pic4rl_bridge.readings.sensor_table import BY_NAME
from pic4rl_bridge.recording import make_env
from pic4rl_sim.interfaces import RECORDED

ROOT = Path(__file__).resolve().parents[2]
CONFIG = ROOT / "config" / "env_goto_lidar.yaml"
STORE = get_typestore(Stores.ROS2_JAZZY)
ANCHORS = [3.0, 3.0, -3.0, -3.0]
UWB = {"uwb.enabled": True, "uwb.anchors_xy_m": ANCHORS, "uwb.noise_std_m": 0.05,
       "uwb.dropout_prob": 0.1}
TARGETS = ("a0", "a1", "goal")
TOPICS = [*RECORDED, "uwb/a0", "uwb/a1", "uwb/a2", "uwb/a3", "uwb/goal", "uwb/anchors"]


def _uwb(make, bags: str, run: str) -> tuple[list[np.ndarray], list[float], list, dict]:
    """Each step's three ranges of one 12-step episode, the goal's decoded by the bridge's
    reading, the recorded anchors' positions and the topics' types."""
    env = make({"record.enabled": True, "record.bags_dir": bags, "record.run": run,
                "record.storage": "sqlite3", "record.topics": TOPICS,
                "episode_max_steps": 12})
    rng = np.random.default_rng(4)
    try:
        env.reset(seed=9)
        for _ in range(12):
            _, _, terminated, truncated, _ = env.step(
                rng.uniform(-1, 1, env.action_space.shape).astype(np.float32))
            if terminated or truncated:
                break
    finally:
        env.close()
    steps: dict[int, dict[str, float]] = {}
    decoded, anchors = [], []
    with Reader(Path(bags) / run / "episode_0000") as reader:
        types = {c.topic: c.msgtype for c in reader.connections}
        for conn, stamp, raw in reader.messages():
            msg = STORE.deserialize_cdr(raw, conn.msgtype)
            if conn.topic == "/uwb/anchors":
                anchors.append([(p.position.x, p.position.y, p.position.z) for p in msg.poses])
            elif conn.topic.startswith("/uwb/"):
                target = conn.topic.removeprefix("/uwb/")
                assert msg.header.frame_id == "uwb_tag"
                steps.setdefault(stamp, {})[target] = msg.range
                if target == "goal":
                    decoded.append(BY_NAME["uwb_goal"].decode(msg, Pose2D(0, 0, 0), conn.topic))
    ranges = [np.array([r[t] for t in TARGETS], np.float32) for _, r in sorted(steps.items())]
    return ranges, decoded, anchors, types


def test_uwb_ranges_are_published_recorded_and_decoded_alike_by_both_transports(
        domain: int, start_sim) -> None:
    start_sim(domain, "--params-file", str(CONFIG), "-p", "uwb.enabled:=true",
              "-p", f"uwb.anchors_xy_m:={ANCHORS}", "-p", "uwb.noise_std_m:=0.05",
              "-p", "uwb.dropout_prob:=0.1")
    with tempfile.TemporaryDirectory() as bags:
        ros = _uwb(lambda o: make_env(CONFIG, transport="ros",
                                      overrides={**o, "ros.domain_id": domain}), bags, "ros")
        local = _uwb(lambda o: make_env(CONFIG, overrides=o, sim=UWB), bags, "local")
    for ranges, decoded, anchors, types in (ros, local):
        assert len(ranges) >= 10
        assert types["/uwb/a0"] == types["/uwb/goal"] == "sensor_msgs/msg/Range"
        assert "/uwb/a2" not in types and "/uwb/a3" not in types  # two anchors
        assert types["/uwb/anchors"] == "geometry_msgs/msg/PoseArray"
        assert anchors == [[(3.0, 3.0, 2.0), (-3.0, -3.0, 2.0)]]  # once, at the episode's start
        assert decoded == [float(r[2]) for r in ranges]
    for i, (a, b) in enumerate(zip(ros[0], local[0])):
        np.testing.assert_array_equal(a, b, err_msg=f"UWB ranges differ at step {i}")
    stacked = np.stack(ros[0])
    assert np.isfinite(stacked).all(axis=1).any() and np.isposinf(stacked).any()  # dropouts
