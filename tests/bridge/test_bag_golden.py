"""The messages a recorded episode holds stay the same through refactors: one short episode of
each shipped env config is recorded in process and every message is compared, topic by topic,
with the digest stored in ``data/golden_episodes.json``.

The digest hashes each message's receive time and its CDR bytes as rosbags re-serializes the
decoded message: rclpy leaves CDR alignment padding uninitialized, so the raw bytes of two
identical recordings differ in their padding, never in their content. Every float64 is rounded
to 1e-9 first: numpy's vectorised sin, cos and arctan2 (the plan's headings and points) differ
in the last bits between CPUs with and without AVX-512, which is no change of content.
Regenerate the file
(only when a change of the recorded content is intended, and say so in the commit) with
``python tests/bridge/test_bag_golden.py``.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import sys
import tempfile
from pathlib import Path

import numpy as np
import pytest
from rosbags.rosbag2 import Reader
from rosbags.typesys import Stores, get_typestore

from pic4rl_bridge.recording import make_env

ROOT = Path(__file__).resolve().parents[2]
GOLDEN = Path(__file__).with_name("data") / "golden_episodes.json"
#: config → steps: one episode each, with commands that turn both ways.
EPISODES = {"env_goto_lidar.yaml": 12, "env_goto_depth.yaml": 6, "env_person_omni.yaml": 8,
            "env_vineyard_depth.yaml": 6}
TYPESTORE = get_typestore(Stores.ROS2_JAZZY)


def command(i: int, size: int) -> np.ndarray:
    base = [0.3 + 0.1 * np.sin(i), 0.5 * np.cos(i / 3), -0.2 * np.sin(i / 2)]
    return np.array(base[:size], np.float32)


def rounded(msg: object) -> object:
    """``msg`` (a rosbags message) with every float64 field and array rounded to 1e-9."""
    if isinstance(msg, float):
        return round(msg, 9) + 0.0  # -0.0 → 0.0
    if isinstance(msg, np.ndarray):
        return np.round(msg, 9) + 0.0 if msg.dtype == np.float64 else msg
    if isinstance(msg, list):
        return [rounded(item) for item in msg]
    if dataclasses.is_dataclass(msg):
        return dataclasses.replace(msg, **{f.name: rounded(getattr(msg, f.name))
                                           for f in dataclasses.fields(msg)})
    return msg


def episode_digest(config: str, steps: int) -> dict[str, dict[str, object]]:
    """Per topic: message type, count and the SHA-256 of (receive time, canonical CDR)."""
    with tempfile.TemporaryDirectory() as bags:
        env = make_env(ROOT / "config" / config,
                       overrides={"record.enabled": True, "record.bags_dir": bags, "record.run": "r",
                                  "record.storage": "sqlite3", "episode_max_steps": steps})
        try:
            env.reset(seed=3)
            for i in range(steps):
                _, _, terminated, truncated, _ = env.step(command(i, env.action_space.shape[0]))
                if terminated or truncated:
                    break
        finally:
            env.close()
        topics: dict[str, dict] = {}
        with Reader(Path(bags) / "r" / "episode_0000") as reader:
            for conn, stamp, raw in reader.messages():
                entry = topics.setdefault(conn.topic, {"type": conn.msgtype, "count": 0,
                                                       "sha": hashlib.sha256()})
                msg = TYPESTORE.deserialize_cdr(raw, conn.msgtype)
                entry["count"] += 1
                entry["sha"].update(stamp.to_bytes(8, "little"))
                entry["sha"].update(bytes(TYPESTORE.serialize_cdr(rounded(msg), conn.msgtype)))
    return {topic: {"type": e["type"], "count": e["count"], "sha256": e["sha"].hexdigest()}
            for topic, e in sorted(topics.items())}


@pytest.mark.parametrize("config", sorted(EPISODES))
def test_a_recorded_episode_holds_the_same_messages(config):
    expected = json.loads(GOLDEN.read_text())[config]
    assert episode_digest(config, EPISODES[config]) == expected


if __name__ == "__main__":
    GOLDEN.parent.mkdir(exist_ok=True)
    digests = {config: episode_digest(config, steps) for config, steps in sorted(EPISODES.items())}
    GOLDEN.write_text(json.dumps(digests, indent=1) + "\n")
    sys.exit(0)
