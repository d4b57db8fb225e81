"""The recorder writes the bag contract's facts as the synthetic bags do (``custom_data`` in
``metadata.yaml`` and the facts topic), byte for byte, in both storages: the metrics read a
recorded episode as they read their own test bags."""

from __future__ import annotations

from pathlib import Path

import pytest
import yaml
from contract_helpers import ENV_FACTS
from rosbags.rosbag2 import Reader

from pic4rl_bridge.recorder import RunRecorder
from pic4rl_metrics import contract
from pic4rl_metrics.contract import EpisodeFacts, Outcome
from pic4rl_metrics.synthetic.synthetic import DEFAULT_T0_NS, straight_line, write_episode_bag


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
