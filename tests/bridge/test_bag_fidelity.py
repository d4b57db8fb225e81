"""Recorded bags say what happened on the wire: each topic with the QoS its publisher offered
(the sim's scan is best effort, its goal latched), ``ros_distro: jazzy``, and MCAP chunks
with CRCs, so that a damaged chunk is an error, never silently wrong numbers."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from rosbags.interfaces import QosDurability, QosReliability
from rosbags.rosbag2 import Reader, ReaderError

from pic4rl_bridge.recording import make_env

ROOT = Path(__file__).resolve().parents[2]
CONFIG = ROOT / "config" / "env_goto_lidar.yaml"
STOP = np.array([-1.0, 0.0], np.float32)


def record(tmp_path: Path, storage: str, **overrides) -> Path:
    env = make_env(CONFIG, overrides={"record.enabled": True, "record.bags_dir": str(tmp_path),
                                      "record.run": "r", "record.storage": storage,
                                      "episode_max_steps": 3, **overrides})
    try:
        env.reset(seed=0)
        for _ in range(3):
            env.step(STOP)
    finally:
        env.close()
    return tmp_path / "r" / "episode_0000"


def offered(bag: Path) -> dict[str, tuple[QosReliability, QosDurability]]:
    with Reader(bag) as reader:
        return {c.topic: (c.ext.offered_qos_profiles[0].reliability,
                          c.ext.offered_qos_profiles[0].durability) for c in reader.connections}


def check_offered(bag: Path) -> None:
    qos = offered(bag)
    assert qos["/scan"][0] is QosReliability.BEST_EFFORT
    assert qos["/odom"] == (QosReliability.RELIABLE, QosDurability.VOLATILE)
    assert qos["/goal_pose"] == (QosReliability.RELIABLE, QosDurability.TRANSIENT_LOCAL)


@pytest.mark.parametrize("storage", ["sqlite3", "mcap"])
def test_bags_record_the_offered_qos_and_the_ros_distro(tmp_path, storage):
    bag = record(tmp_path, storage)
    check_offered(bag)
    assert "ros_distro: jazzy" in (bag / "metadata.yaml").read_text()
    with Reader(bag) as reader:
        assert sum(1 for _ in reader.messages()) == sum(c.msgcount for c in reader.connections)


def test_a_damaged_mcap_chunk_fails_its_crc(tmp_path):
    bag = record(tmp_path, "mcap")
    (mcap,) = bag.glob("*.mcap")
    data = bytearray(mcap.read_bytes())
    data[len(data) // 3] ^= 0xFF  # inside the one chunk: a scan's ranges or the like
    mcap.write_bytes(bytes(data))
    with Reader(bag) as reader, pytest.raises(ReaderError, match="checksum"):
        list(reader.messages())


@pytest.mark.integration
def test_through_ros_the_qos_is_the_sims(tmp_path, domain, start_sim):
    start_sim(domain, "--params-file", str(CONFIG))
    bag = record(tmp_path, "sqlite3", transport="ros", **{"ros.domain_id": domain})
    check_offered(bag)
