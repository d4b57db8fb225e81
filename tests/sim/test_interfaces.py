"""The sim's interface table: consistent in itself, with the node's rclpy profiles and with the
topic names the metrics read (``pic4rl_metrics.contract`` keeps its own, not importing the
sim). Starts no ROS graph."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pic4rl_metrics.contract as contract
import pytest
from rclpy.qos import DurabilityPolicy, ReliabilityPolicy

from pic4rl_sim.interfaces import (
    GOAL_POSE,
    INTERFACE_TABLE,
    RECORDED,
    SCAN,
    STEP_TOPICS,
    WORLD_MARKERS,
    Direction,
    QosKind,
    find,
    interface,
)
from pic4rl_sim.node.ros_interfaces import PROFILES, qos_profile, ros_type

REPO = Path(__file__).resolve().parents[2]
#: The contract's topics that the recorder writes itself (facts, outcome): not the sim's.
NOT_THE_SIMS = {contract.FACTS_TOPIC, contract.OUTCOME_TOPIC}
#: Recorded topics no metric reads.
UNREAD_BY_METRICS = {"/camera/depth/image_raw", "/camera/depth/camera_info", "/plan"}


def test_names_are_unique_relative_and_the_recording_order_is_the_bag_contracts() -> None:
    names = [i.name for i in INTERFACE_TABLE]
    assert len(set(names)) == len(names)
    assert all(n and not n.startswith("/") for n in names)
    orders = [i.record_order for i in INTERFACE_TABLE if i.record_order is not None]
    assert sorted(orders) == list(range(len(orders)))
    assert RECORDED == ("clock", "ground_truth", "odom", "scan", "cmd_vel", "goal_pose",
                        "camera/depth/image_raw", "camera/depth/camera_info", "person/pose",
                        "plan", "tf", "tf_static", "people")


def test_a_step_ends_with_the_scan_and_only_topics_have_a_qos() -> None:
    assert STEP_TOPICS[-1] is SCAN
    for i in INTERFACE_TABLE:
        assert (i.qos is None) == (i.direction is Direction.SRV), i.name
        assert (i.cadence is not None) == (i.direction is Direction.PUB), i.name


def test_lookups_take_relative_and_resolved_names() -> None:
    assert interface("goal_pose") is GOAL_POSE
    with pytest.raises(KeyError):
        interface("/goal_pose")
    assert find("/robot1/world/markers") is WORLD_MARKERS
    assert find("scan") is SCAN and find("/front/scan") is SCAN
    assert find("/episode/facts") is None and find("/markers") is None


def test_every_type_resolves_and_the_profiles_are_the_tables() -> None:
    for i in INTERFACE_TABLE:
        kind = ros_type(i.type)
        assert i.type.split("/") == [kind.__module__.split(".")[0], i.type.split("/")[1],
                                     kind.__name__]
        if i.qos is not None:
            assert qos_profile(i) is PROFILES[i.qos]
    for kind, profile in PROFILES.items():
        settings = kind.value
        assert (profile.reliability is ReliabilityPolicy.RELIABLE) == settings.reliable
        assert (profile.durability is DurabilityPolicy.TRANSIENT_LOCAL) == settings.transient_local
        assert profile.depth == settings.depth
    assert set(PROFILES) == set(QosKind)


def test_the_metrics_read_the_recorded_topics_by_the_same_names() -> None:
    topics = {value for name, value in vars(contract).items() if name.endswith("_TOPIC")}
    sims = topics - NOT_THE_SIMS
    recorded = {f"/{name}" for name in RECORDED}
    assert sims == recorded - UNREAD_BY_METRICS


def test_importing_the_table_loads_no_ros_or_mujoco() -> None:
    code = ("import json, sys\nimport pic4rl_sim.interfaces\n"
            "print(json.dumps(sorted(m for m in sys.modules "
            "if m.split('.')[0] in ('rclpy', 'mujoco', 'numpy'))))\n")
    done = subprocess.run([sys.executable, "-c", code], cwd=REPO, capture_output=True,
                          text=True, timeout=60, check=False)
    assert done.returncode == 0, done.stderr
    assert json.loads(done.stdout) == []
