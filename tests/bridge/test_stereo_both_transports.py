"""The stereo depth camera through both transports (issue 40 item 3): the sim node with
``stereo.enabled`` publishes a depth image and a ``stereo_msgs/DisparityImage`` each step, a bag
records them when ``record.topics`` names them, they equal the in-process engine's for one
seed and one command sequence, and the bridge's reading ``stereo_depth`` decodes the depth."""

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
STEREO = {"stereo.enabled": True, "stereo.width": 32, "stereo.height": 20}
TOPICS = [*RECORDED, "stereo/depth/image_raw", "stereo/disparity"]


def _stereo(make, bags: str, run: str) -> tuple[list[np.ndarray], list[np.ndarray]]:
    """Each step's decoded depth image and disparity image of one 8-step episode."""
    env = make({"record.enabled": True, "record.bags_dir": bags, "record.run": run,
                "record.storage": "sqlite3", "record.topics": TOPICS, "episode_max_steps": 8})
    rng = np.random.default_rng(4)
    try:
        env.reset(seed=9)
        for _ in range(8):
            _, _, terminated, truncated, _ = env.step(
                rng.uniform(-1, 1, env.action_space.shape).astype(np.float32))
            if terminated or truncated:
                break
    finally:
        env.close()
    depth, disparity = [], []
    with Reader(Path(bags) / run / "episode_0000") as reader:
        for conn, _, raw in reader.messages():
            if conn.topic == "/stereo/depth/image_raw":
                msg = STORE.deserialize_cdr(raw, conn.msgtype)
                depth.append(BY_NAME["stereo_depth"].decode(msg, Pose2D(0, 0, 0), conn.topic))
            elif conn.topic == "/stereo/disparity":
                msg = STORE.deserialize_cdr(raw, conn.msgtype)
                assert conn.msgtype == "stereo_msgs/msg/DisparityImage" and abs(msg.t - 0.05) < 1e-7
                image = np.frombuffer(msg.image.data, np.float32).reshape(20, 32)
                valid = image > 0
                assert np.allclose(msg.f * msg.t / image[valid], depth[-1][valid], rtol=1e-5)
                disparity.append(image)
    return depth, disparity


def test_the_stereo_camera_is_published_recorded_and_decoded_alike_by_both_transports(
        domain: int, start_sim) -> None:
    start_sim(domain, "--params-file", str(CONFIG), "-p", "stereo.enabled:=true",
              "-p", "stereo.width:=32", "-p", "stereo.height:=20")
    with tempfile.TemporaryDirectory() as bags:
        ros = _stereo(lambda o: make_env(CONFIG, transport="ros",
                                         overrides={**o, "ros.domain_id": domain}), bags, "ros")
        local = _stereo(lambda o: make_env(CONFIG, overrides=o, sim=STEREO), bags, "local")
    assert len(ros[0]) == len(local[0]) >= 6 and len(ros[1]) == len(ros[0])
    for ours, theirs in zip(ros, local):
        for i, (a, b) in enumerate(zip(ours, theirs)):
            np.testing.assert_array_equal(a, b, err_msg=f"stereo images differ at step {i}")
    assert any(np.isfinite(d).any() for d in ros[0])  # it sees the world
