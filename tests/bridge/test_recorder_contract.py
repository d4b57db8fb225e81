"""The recorder writes the bag contract's facts as the synthetic bags do (``custom_data`` in
``metadata.yaml`` and the facts topic), byte for byte, in both storages: the metrics read a
recorded episode as they read their own test bags."""

from __future__ import annotations

import math
from pathlib import Path

import pytest
import yaml
from rosbags.rosbag2 import Reader

from pic4rl_bridge.recorder import RunRecorder
from pic4rl_metrics import contract
from pic4rl_metrics.contract import EpisodeFacts, Outcome
from pic4rl_metrics.geometry import Footprint, Mount
from pic4rl_metrics.testing.synthetic import DEFAULT_T0_NS, straight_line, write_episode_bag

#: Facts as the env writes them (a Jackal after a goToPose episode).
ENV_FACTS = EpisodeFacts(
    agent="sac", task="goToPose/lidar", world="indoor:0", robot="jackal", run="run1",
    episode="episode_0000", seed=7, footprint=Footprint(length_m=0.508, width_m=0.43),
    start=(0.0, 0.0, 0.0), goal=(2.0, 0.0), goal_tolerance_m=0.3, collision_tolerance_m=0.05,
    safety_margin_m=0.1, max_speed_mps=2.0, shortest_path_m=math.inf, straight_line_m=2.0,
    scan_mount=Mount(0.12, 0.0, 0.0),
)


def _metadata_custom(bag: Path) -> list[tuple[str, str]]:
    info = yaml.safe_load((bag / "metadata.yaml").read_text())["rosbag2_bagfile_information"]
    return list(info["custom_data"].items())


def _facts_message(bag: Path) -> str:
    ts = contract.typestore()
    with Reader(bag) as reader:
        conns = [c for c in reader.connections if c.topic == contract.FACTS_TOPIC]
        (_, _, raw), = list(reader.messages(connections=conns))
    return ts.deserialize_cdr(raw, "std_msgs/msg/String").data


@pytest.mark.parametrize("storage", ["sqlite3", "mcap"])
def test_the_recorder_and_the_synthetic_writer_write_the_same_facts(
    tmp_path: Path, storage: str
) -> None:
    facts = EpisodeFacts(**{**vars(ENV_FACTS), "row_centerline": ((0.0, 0.0), (2.0, 0.5))})
    recorded = RunRecorder(tmp_path / "rec", "run1", storage=storage).begin("episode_0000")
    recorded.facts(facts, DEFAULT_T0_NS)
    recorded_path = recorded.close(Outcome.COLLISION, DEFAULT_T0_NS)
    synthetic = write_episode_bag(tmp_path / "syn" / "run1" / "episode_0000",
                                  straight_line(0.5, 1.0), facts=facts, outcome="collision",
                                  storage=storage)
    assert _metadata_custom(recorded_path) == _metadata_custom(synthetic)
    assert dict(_metadata_custom(synthetic)) == (
        EpisodeFacts(**{**vars(facts), "outcome": Outcome.COLLISION}).custom_data())
    assert _facts_message(recorded_path) == _facts_message(synthetic) == facts.facts_json()
