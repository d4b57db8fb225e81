"""``roles``: the one table of the metrics' input topics, and what derives from it."""

from __future__ import annotations

import dataclasses
import pickle
from pathlib import Path

import numpy as np
import pytest

from pic4rl_metrics.cli.commands import _inputs, build_parser
from pic4rl_metrics.contract import EpisodeFacts
from pic4rl_metrics.core.derived import INPUT_TESTS, Derived
from pic4rl_metrics.core.roles import (
    LASER_SCAN,
    ODOMETRY,
    POSE_ARRAY,
    POSE_COV,
    POSE_STAMPED,
    ROLE_TYPES,
    ROLE_TABLE,
    SERIES_ROLES,
    SUPPORTED_POSE_MSGS,
    TWIST_STAMPED,
    has_header,
)
from pic4rl_metrics.core.series import CmdSeries, Episode, PoseSeries
from pic4rl_metrics.bags.topics import TopicMap, topic_map_from_dict

DOC = Path(__file__).resolve().parents[3] / "docs" / "metrics.md"


def _pose() -> PoseSeries:
    t = np.array([0, 10**9], dtype=np.int64)
    return PoseSeries(t, np.zeros(2), np.zeros(2), np.zeros(2))


def test_a_topic_map_has_every_role_with_its_default_topic() -> None:
    topic_map = TopicMap()
    assert {role.name: getattr(topic_map, role.name) for role in ROLE_TABLE} == {
        role.name: role.topic for role in ROLE_TABLE}
    assert set(ROLE_TYPES) == {role.name for role in ROLE_TABLE}


def test_a_role_topic_is_a_keyword_normalized_and_replaced() -> None:
    topic_map = TopicMap(scan="front/scan", person=None)
    assert (topic_map.scan, topic_map.person, topic_map.cmd_vel) == ("/front/scan", None, "/cmd_vel")
    assert dataclasses.replace(topic_map, cmd_vel="/c").cmd_vel == "/c"
    assert dataclasses.replace(topic_map, cmd_vel="/c").scan == "/front/scan"
    over = topic_map.with_overrides(goal="/g", scan=None)
    assert (over.goal, over.scan, over.explicit) == ("/g", "/front/scan", frozenset({"goal"}))
    assert pickle.loads(pickle.dumps(over)) == over
    with pytest.raises(TypeError, match="unknown roles \\['lidar'\\]"):
        TopicMap(lidar="/x")
    with pytest.raises(AttributeError, match="lidar"):
        _ = topic_map.lidar


def test_topic_map_yaml_keys_and_cli_options_come_from_the_table() -> None:
    data = {role.key: f"/mapped/{role.name}" for role in ROLE_TABLE}
    topic_map, _, _ = topic_map_from_dict(data, source="test")
    assert all(getattr(topic_map, r.name) == f"/mapped/{r.name}" for r in ROLE_TABLE)
    assert topic_map.explicit == {role.name for role in ROLE_TABLE}
    assert {r.key for r in ROLE_TABLE} >= {"scan", "cmd_vel", "facts_topic", "outcome_topic"}
    flagged = [role for role in ROLE_TABLE if role.flag]
    assert [r.flag for r in flagged] == ["--scan-topic", "--cmd-topic", "--goal-topic",
                                         "--person-topic", "--people-topic"]
    argv = ["compute", "bag"] + [x for r in flagged for x in (r.flag, f"/cli/{r.name}")]
    from_cli, _, _ = _inputs(build_parser().parse_args(argv))
    assert all(getattr(from_cli, r.name) == f"/cli/{r.name}" for r in flagged)
    assert from_cli.explicit == {r.name for r in flagged}


def test_an_episode_has_every_series_role_as_an_attribute() -> None:
    cmd = CmdSeries(np.array([5], dtype=np.int64), np.ones(1), np.zeros(1), np.zeros(1))
    episode = Episode(Path("b"), EpisodeFacts(), _pose(), "/odom", cmd=cmd)
    assert {name: getattr(episode, name) for name in SERIES_ROLES} == {
        "scan": None, "cmd": cmd, "person": None, "people": None}
    assert dataclasses.replace(episode, cmd=None).cmd is None
    assert dataclasses.replace(episode, pose_topic="/x").cmd is cmd
    assert pickle.loads(pickle.dumps(episode)).cmd.vx.tolist() == [1.0]
    with pytest.raises(TypeError, match="unknown series \\['lidar'\\]"):
        Episode(Path("b"), EpisodeFacts(), _pose(), "/odom", lidar=cmd)


def test_a_series_role_is_an_input_a_metric_can_need() -> None:
    assert set(SERIES_ROLES.values()) <= {r for r in ROLE_TABLE if r.name in INPUT_TESTS}
    cmd = CmdSeries(np.zeros(0, dtype=np.int64), np.zeros(0), np.zeros(0), np.zeros(0))
    empty = Derived(Episode(Path("b"), EpisodeFacts(), _pose(), "/odom", cmd=cmd))
    assert [name for name in ("scan", "cmd_vel", "person", "people")
            if INPUT_TESTS[name](empty)] == []
    cmd = dataclasses.replace(cmd, t_ns=np.array([1]), vx=np.ones(1), vy=np.ones(1),
                              wz=np.ones(1))
    assert INPUT_TESTS["cmd_vel"](Derived(Episode(Path("b"), EpisodeFacts(), _pose(), "/o",
                                                  cmd=cmd)))


def test_the_stamped_types_are_those_with_a_header() -> None:
    accepted = {t for types in ROLE_TYPES.values() for t in types} | SUPPORTED_POSE_MSGS
    assert {t for t in accepted if has_header(t)} == {
        LASER_SCAN, ODOMETRY, POSE_STAMPED, POSE_COV, TWIST_STAMPED, POSE_ARRAY}
    assert not has_header("my_msgs/msg/NotInJazzy")


def test_docs_topic_table_names_every_role_its_topic_and_types() -> None:
    table = DOC.read_text().split("## Inputs and conventions", 1)[1].split("\n\n", 2)[1]
    rows = table.splitlines()[2:]
    for role in ROLE_TABLE:
        row = next((r for r in rows if f"`{role.topic}`" in r), None)
        assert row is not None, f"docs/metrics.md's topic table has no row for {role.name}"
        for msgtype in role.types:
            named = f"`{msgtype}`" in row or f"`{msgtype.rsplit('/', 1)[-1]}`" in row
            assert named or (role.types == SUPPORTED_POSE_MSGS and "as pose" in row), (
                f"docs/metrics.md: the {role.name} row does not name {msgtype}")
