"""Several sensors through both transports (issue 40 item 1): goToPose with ``sensors: [lidar,
depth]`` gives the same Dict observations from the sim node over ROS 2 as in process, for one
seed and one action sequence, and each episode's bag records both sensors and names them in
its task fact."""

from __future__ import annotations

import tempfile
from pathlib import Path
from typing import Any

import numpy as np
import yaml
from rosbags.rosbag2 import Reader

from pic4rl_bridge.recording import make_env

ROOT = Path(__file__).resolve().parents[2]
CONFIG = ROOT / "config" / "env_goto_lidar.yaml"
SIM = {"depth.enabled": True, "depth.width": 40, "depth.height": 30}
FUSED = {"sensors": ["lidar", "depth"], "depth.obs_width": 20, "depth.obs_height": 15,
         "episode_max_steps": 8}


def _episode(make, bags: str, run: str) -> tuple[list[dict[str, Any]], Path]:
    """Each observation of one seeded 8-step episode, and its bag."""
    env = make({**FUSED, "record.enabled": True, "record.bags_dir": bags, "record.run": run,
                "record.storage": "sqlite3"})
    rng = np.random.default_rng(4)
    try:
        obs, _ = env.reset(seed=9)
        seen = [obs]
        for _ in range(7):
            obs, _, terminated, truncated, _ = env.step(
                rng.uniform(-1, 1, env.action_space.shape).astype(np.float32))
            seen.append(obs)
            if terminated or truncated:
                break
    finally:
        env.close()
    return seen, Path(bags) / run / "episode_0000"


def _bag(path: Path) -> tuple[dict[str, int], str]:
    """The bag's messages per topic, and its task fact."""
    counts: dict[str, int] = {}
    with Reader(path) as reader:
        for conn, _, _ in reader.messages():
            counts[conn.topic] = counts.get(conn.topic, 0) + 1
    facts = yaml.safe_load((path / "metadata.yaml").read_text())
    return counts, str(facts)


def test_lidar_and_depth_observations_are_alike_through_both_transports(
        domain: int, start_sim) -> None:
    start_sim(domain, "--params-file", str(CONFIG),
              *(arg for k, v in SIM.items() for arg in ("-p", f"{k}:={str(v).lower()}")))
    with tempfile.TemporaryDirectory() as bags:
        ros, ros_bag = _episode(lambda o: make_env(CONFIG, transport="ros", sim=SIM,
                                                   overrides={**o, "ros.domain_id": domain}),
                                bags, "ros")
        local, local_bag = _episode(lambda o: make_env(CONFIG, overrides=o, sim=SIM), bags,
                                    "local")
        assert len(ros) == len(local) >= 8
        for i, (a, b) in enumerate(zip(ros, local)):
            assert set(a) == {"lidar", "depth", "goal"}
            for key in a:
                np.testing.assert_array_equal(a[key], b[key], err_msg=f"{key} at step {i}")
        assert len({o["depth"].tobytes() for o in ros}) > 1  # the camera sees the robot move
        for path in (ros_bag, local_bag):
            counts, facts = _bag(path)
            assert counts["/scan"] >= 8 and counts["/camera/depth/image_raw"] >= 8, counts
            assert "goToPose/lidar+depth" in facts
