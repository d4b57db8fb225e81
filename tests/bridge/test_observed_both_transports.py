"""The sonar ring and the stereo camera observed through both transports (issue 40 item 2):
``sensors: [lidar, sonar]`` and ``sensor: stereo`` give bit-identical observations, rewards and
ends over ROS 2 (the sim node in its own process) and in process for one seed and one action
sequence, and each bag records the observed sensor's topics with no ``record.topics`` of its
own."""

from __future__ import annotations

import tempfile
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from rosbags.rosbag2 import Reader

from pic4rl_bridge.recording import make_env

pytestmark = pytest.mark.integration

ROOT = Path(__file__).resolve().parents[2]
CONFIG = ROOT / "config" / "env_goto_lidar.yaml"
CASES = {
    "lidar+sonar": ({"sonar.enabled": True, "sonar.count": 6},
                    {"sensors": ["lidar", "sonar"]}, [f"/sonar/cone{i}" for i in range(6)]),
    "stereo": ({"stereo.enabled": True, "stereo.width": 32, "stereo.height": 20},
               {"sensor": "stereo", "stereo.obs_width": 32, "stereo.obs_height": 20},
               ["/stereo/depth/image_raw"]),
}


def _run(make, bags: str, run: str) -> list[tuple[Any, ...]]:
    """Each step's (observation, reward, terminated, truncated) of two recorded episodes."""
    env = make({"record.enabled": True, "record.bags_dir": bags, "record.run": run,
                "record.storage": "sqlite3", "episode_max_steps": 10})
    rng = np.random.default_rng(6)
    seen: list[tuple[Any, ...]] = []
    try:
        for episode in range(2):
            obs, _ = env.reset(seed=21 if episode == 0 else None)
            seen.append((obs,))
            done = False
            while not done:
                obs, reward, terminated, truncated, _ = env.step(
                    rng.uniform(-1, 1, env.action_space.shape).astype(np.float32))
                seen.append((obs, reward, terminated, truncated))
                done = terminated or truncated
    finally:
        env.close()
    return seen


def _counts(bag: Path) -> dict[str, int]:
    with Reader(bag) as reader:
        return {c.topic: c.msgcount for c in reader.connections}


@pytest.mark.parametrize("case", sorted(CASES))
def test_an_observed_sonar_or_stereo_camera_is_alike_through_both_and_recorded(
        case: str, domain: int, start_sim) -> None:
    sim, overrides, topics = CASES[case]
    start_sim(domain, "--params-file", str(CONFIG),
              *(arg for k, v in sim.items() for arg in ("-p", f"{k}:={str(v).lower()}")))
    with tempfile.TemporaryDirectory() as bags:
        ros = _run(lambda o: make_env(CONFIG, transport="ros", sim=sim, overrides={
            **overrides, **o, "ros.domain_id": domain}), bags, "ros")
        local = _run(lambda o: make_env(CONFIG, sim=sim, overrides={**overrides, **o}), bags,
                     "local")
        counts = {run: [_counts(Path(bags) / run / f"episode_000{i}") for i in range(2)]
                  for run in ("ros", "local")}
    assert len(ros) == len(local) >= 12
    key = "sonar" if case == "lidar+sonar" else "stereo"
    for step, (r, here) in enumerate(zip(ros, local)):
        assert r[0].keys() == here[0].keys() and key in r[0]
        for name in r[0]:
            np.testing.assert_array_equal(r[0][name], here[0][name],
                                          err_msg=f"{name} differs at step {step}")
        assert r[1:] == here[1:], f"reward or end differs at step {step}"
    assert len({r[0][key].tobytes() for r in ros}) > 1  # the sensor sees the robot move
    for run, episodes in counts.items():
        for i, episode in enumerate(episodes):
            steps = episode["/odom"]
            assert all(episode.get(t) == steps for t in topics), (run, i, episode)
