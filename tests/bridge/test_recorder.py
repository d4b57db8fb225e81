"""The episode recorder against the bag contract: bags written through ``RunRecorder`` are read
back with rosbags (counts, bytes, QoS, custom_data) and judged by ``pic4rl_metrics``, whose
answers for a straight line are known by hand. Nothing on disk is ever overwritten, and a
recorder killed with SIGKILL leaves a bag the metrics read.

Messages are built from the rosbags typestore and serialized to CDR as a transport delivers
them; no ROS graph is needed.
"""

from __future__ import annotations

import json
import math
import os
import signal
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import yaml
from rosbags.interfaces import QosDurability
from rosbags.rosbag2 import Reader

from pic4rl_bridge.errors import RecorderError
from pic4rl_bridge.recorder import EpisodeBag, RunRecorder
from pic4rl_bridge.transports.transport import RawMessage
from pic4rl_metrics import Outcome, compute, read_episode
from pic4rl_metrics.contract import fact_text, parse_facts, typestore

REPO = Path(__file__).resolve().parents[2]
VICTIM = Path(__file__).with_name("recorder_victim.py")

T0_NS = 1_700_000_000_000_000_000
DT_NS = 100_000_000  # 10 Hz
LENGTH = 1e-6  # path lengths: sums of 40 float64 steps of 0.05 m, far below this
FACTS = {
    "agent": "sac",
    "task": "go_to_pose",
    "world": "indoor:0",
    "seed": 7,
    "footprint": {"radius_m": 0.2},
    "start": (0.0, 0.0, 0.0),
    "goal": [2.0, 0.0],
    "goal_tolerance_m": 0.3,
}


def _header(ns: int, frame: str) -> object:
    t = typestore().types
    sec, nanosec = divmod(ns, 1_000_000_000)
    return t["std_msgs/msg/Header"](t["builtin_interfaces/msg/Time"](sec, nanosec), frame)


def _pose(x: float, y: float) -> object:
    t = typestore().types
    return t["geometry_msgs/msg/Pose"](t["geometry_msgs/msg/Point"](x, y, 0.0),
                                       t["geometry_msgs/msg/Quaternion"](0.0, 0.0, 0.0, 1.0))


def _twist(vx: float) -> object:
    t = typestore().types
    vec = t["geometry_msgs/msg/Vector3"]
    return t["geometry_msgs/msg/Twist"](vec(vx, 0.0, 0.0), vec(0.0, 0.0, 0.0))


def _raw(topic: str, msg: object, ns: int) -> RawMessage:
    msgtype = msg.__msgtype__  # type: ignore[attr-defined]
    return RawMessage(topic, msgtype, bytes(typestore().serialize_cdr(msg, msgtype)), ns)


def odometry(topic: str, ns: int, x: float, vx: float) -> RawMessage:
    t = typestore().types
    msg = t["nav_msgs/msg/Odometry"](
        _header(ns, "odom"), "base_link",
        t["geometry_msgs/msg/PoseWithCovariance"](_pose(x, 0.0), np.zeros(36)),
        t["geometry_msgs/msg/TwistWithCovariance"](_twist(vx), np.zeros(36)),
    )
    return _raw(topic, msg, ns)


def scan(ns: int) -> RawMessage:
    t = typestore().types
    msg = t["sensor_msgs/msg/LaserScan"](_header(ns, "base_scan"), -math.pi, math.pi, math.pi,
                                         0.0, 0.0, 0.05, 10.0, np.full(3, 5.0, np.float32),
                                         np.zeros(0, np.float32))
    return _raw("/scan", msg, ns)


def goal_pose(ns: int, x: float, y: float) -> RawMessage:
    t = typestore().types
    return _raw("/goal_pose", t["geometry_msgs/msg/PoseStamped"](_header(ns, "map"), _pose(x, y)),
                ns)


def record_line(bag: EpisodeBag, *, speed_mps: float = 0.5, n: int = 41,
                outcome: str | None = "goal") -> list[RawMessage]:
    """Record a straight line along +x (``n`` poses at 10 Hz, from x = 0) with scans, commands,
    one goal and ``FACTS``; close with ``outcome`` (``None``: leave open). Return the messages
    given to ``write``."""
    sent = [goal_pose(T0_NS, 2.0, 0.0)]
    for i in range(n):
        ns, x = T0_NS + i * DT_NS, speed_mps * i * DT_NS * 1e-9
        sent += [odometry("/ground_truth", ns, x, speed_mps), odometry("/odom", ns, x, speed_mps),
                 scan(ns), _raw("/cmd_vel", _twist(speed_mps), ns)]
    bag.facts(parse_facts(FACTS, source="test")[0], T0_NS)
    for msg in sent:
        bag.write(msg)
    if outcome is not None:
        bag.close(outcome, T0_NS + (n - 1) * DT_NS)
    return sent


def read_bag(path: Path) -> tuple[dict[str, list[bytes]], dict[str, str], dict[str, object]]:
    """Messages per topic (raw CDR), custom_data and each topic's connection."""
    with Reader(path) as reader:
        conns = {c.topic: c for c in reader.connections}
        messages: dict[str, list[bytes]] = {topic: [] for topic in conns}
        for conn, _, data in reader.messages():
            messages[conn.topic].append(bytes(data))
    info = yaml.safe_load((path / "metadata.yaml").read_text())["rosbag2_bagfile_information"]
    return messages, info["custom_data"] or {}, conns


def _string(data: bytes) -> str:
    return typestore().deserialize_cdr(data, "std_msgs/msg/String").data


# --- round trip -------------------------------------------------------------------------------


@pytest.mark.parametrize("storage", ["sqlite3", "mcap"])
def test_round_trip_keeps_every_message_fact_and_outcome(tmp_path: Path, storage: str) -> None:
    recorder = RunRecorder(tmp_path, "run1", storage=storage)
    bag = recorder.begin()
    sent = record_line(bag, outcome=None)
    path = bag.close("goal", T0_NS + 40 * DT_NS)

    assert path == tmp_path / "run1" / "episode_0000" and recorder.episodes == [path]
    assert (path / "metadata.yaml").is_file()
    messages, custom, conns = read_bag(path)
    expected = {"/goal_pose": 1, "/ground_truth": 41, "/odom": 41, "/scan": 41, "/cmd_vel": 41,
                "/episode/facts": 1, "/episode/outcome": 1}
    assert {topic: len(data) for topic, data in messages.items()} == expected
    assert bag.counts == expected
    assert messages["/scan"] == [m.data for m in sent if m.topic == "/scan"]

    facts = {**FACTS, "run": "run1", "episode": "episode_0000"}
    assert json.loads(_string(messages["/episode/facts"][0])) == json.loads(json.dumps(facts))
    assert json.loads(_string(messages["/episode/outcome"][0])) == {
        "outcome": "goal", "stamp_ns": T0_NS + 40 * DT_NS}
    assert custom == {**{k: fact_text(v) for k, v in facts.items()}, "outcome": "goal"}
    assert custom["footprint"] == '{"radius_m": 0.2}' and custom["start"] == "[0.0, 0.0, 0.0]"

    qos = {topic: c.ext.offered_qos_profiles[0].durability for topic, c in conns.items()}
    assert qos["/goal_pose"] == QosDurability.TRANSIENT_LOCAL
    assert qos["/scan"] == QosDurability.VOLATILE


@pytest.mark.parametrize("storage", ["sqlite3", "mcap"])
def test_metrics_judge_a_recorded_straight_line(tmp_path: Path, storage: str) -> None:
    """0.5 m/s along +x for 4 s, goal at (2, 0): success, path length 2 m."""
    bag = RunRecorder(tmp_path, "run", storage=storage).begin()
    record_line(bag, outcome="goal")

    frame = compute([bag.path]).frame
    assert len(frame) == 1
    row = frame.iloc[0]
    assert row["error"] == ""
    assert row["success"] == 1.0 and row["outcome"] == "goal"
    assert row["path_length_m"] == pytest.approx(2.0, abs=LENGTH)
    assert row["n_poses"] == 41
    facts = read_episode(bag.path).facts
    assert facts.outcome == Outcome.GOAL
    assert facts.outcome_stamp_ns == T0_NS + 40 * DT_NS
    assert facts.goal == (2.0, 0.0) and facts.seed == 7 and facts.episode == "episode_0000"


def test_recorded_outcome_is_what_the_metrics_use(tmp_path: Path) -> None:
    """A collision recorded at the goal stays a collision (not inferred from the poses)."""
    bag = RunRecorder(tmp_path, "run").begin()
    record_line(bag, outcome="collision")
    row = compute([bag.path]).frame.iloc[0]
    assert row["outcome"] == "collision" and row["success"] == 0.0


# --- never overwrite --------------------------------------------------------------------------


def test_an_existing_explicit_episode_is_refused(tmp_path: Path) -> None:
    recorder = RunRecorder(tmp_path, "run")
    kept = tmp_path / "run" / "ep" / "precious.txt"
    kept.parent.mkdir()
    kept.write_text("mine")
    with pytest.raises(RecorderError, match=r"run/ep.*exists"):
        recorder.begin("ep")
    assert kept.read_text() == "mine" and sorted(kept.parent.iterdir()) == [kept]
    assert recorder.episodes == []


@pytest.mark.parametrize("name", ["", "..", "a/b"])
def test_an_episode_name_must_be_one_directory(tmp_path: Path, name: str) -> None:
    with pytest.raises(RecorderError, match="one directory name"):
        RunRecorder(tmp_path, "run").begin(name)


def test_automatic_names_skip_existing_episodes(tmp_path: Path) -> None:
    run_dir = tmp_path / "run"
    for name in ("episode_0000", "episode_0003"):
        (run_dir / name).mkdir(parents=True)
        (run_dir / name / "precious.txt").write_text(name)

    first = RunRecorder(tmp_path, "run")
    a = first.begin()
    a.abort()
    b = first.begin()
    b.abort()
    assert [p.name for p in first.episodes] == ["episode_0004", "episode_0005"]
    second = RunRecorder(tmp_path, "run")  # a second run into the same directory appends
    c = second.begin()
    c.abort()
    assert c.path.name == "episode_0006"
    for name in ("episode_0000", "episode_0003"):
        assert (run_dir / name / "precious.txt").read_text() == name


def test_config_is_never_overwritten(tmp_path: Path) -> None:
    run_dir = tmp_path / "run"
    a = {"task": "go_to_pose", "reward": {"goal": 500.0}, "topics": ("scan", "odom")}
    b = {"task": "vineyard", "reward": {"goal": 100.0}}

    assert RunRecorder(tmp_path, "run", config=a).config_path == run_dir / "config.yaml"
    assert RunRecorder(tmp_path, "run", config=a).config_path == run_dir / "config.yaml"
    assert RunRecorder(tmp_path, "run", config=b).config_path == run_dir / "config-2.yaml"
    assert RunRecorder(tmp_path, "run", config=b).config_path == run_dir / "config-2.yaml"
    assert RunRecorder(tmp_path, "run", config=a).config_path == run_dir / "config.yaml"

    assert sorted(p.name for p in run_dir.iterdir()) == ["config-2.yaml", "config.yaml"]
    assert yaml.safe_load((run_dir / "config.yaml").read_text()) == {
        **a, "topics": ["scan", "odom"]}
    assert yaml.safe_load((run_dir / "config-2.yaml").read_text()) == b


# --- errors and aborts ------------------------------------------------------------------------


def test_an_unknown_message_type_names_the_topic(tmp_path: Path) -> None:
    bag = RunRecorder(tmp_path, "run").begin()
    with pytest.raises(RecorderError, match=r"'/weird'.*'foo_msgs/msg/Bar'"):
        bag.write(RawMessage("/weird", "foo_msgs/msg/Bar", b"\x00\x01\x00\x00", T0_NS))
    bag.write(odometry("/odom", T0_NS, 0.0, 0.0))  # the bag goes on
    bag.abort()
    messages, _, _ = read_bag(bag.path)
    assert {t: len(m) for t, m in messages.items()} == {"/odom": 1}
    assert bag.counts == {"/odom": 1}


def test_an_unknown_outcome_is_refused(tmp_path: Path) -> None:
    bag = RunRecorder(tmp_path, "run").begin()
    with pytest.raises(RecorderError, match="'success' is not one of goal, collision, timeout"):
        bag.close("success", T0_NS)
    assert bag.is_open
    bag.abort()


def test_an_aborted_episode_keeps_its_outcome_and_reason(tmp_path: Path) -> None:
    """The env's abort (a sensor went silent): outcome ``aborted`` and its ``end_reason`` in
    ``custom_data``, which the reader decodes; ``unknown`` stays the reader's alone."""
    with pytest.raises(RecorderError, match="'unknown' is not one of .*diverged, aborted"):
        RunRecorder(tmp_path, "other").begin().close("unknown", T0_NS)
    bag = RunRecorder(tmp_path, "run").begin()
    bag.write(odometry("/odom", T0_NS, 0.0, 0.0))
    bag.close("aborted", T0_NS, "topic /scan: no message for 0.61 s")
    messages, custom, _ = read_bag(bag.path)
    assert custom["outcome"] == "aborted"
    assert custom["end_reason"] == "topic /scan: no message for 0.61 s"
    facts, _ = parse_facts(custom, source="custom_data")
    assert facts.outcome is Outcome.ABORTED and facts.end_reason == custom["end_reason"]
    assert len(messages["/episode/outcome"]) == 1


def test_abort_keeps_a_readable_bag_without_outcome(tmp_path: Path) -> None:
    with RunRecorder(tmp_path, "run").begin() as bag:
        record_line(bag, n=11, outcome=None)
    assert not bag.is_open
    assert bag.abort() == bag.path  # a second abort does nothing
    messages, custom, _ = read_bag(bag.path)
    assert "/episode/outcome" not in messages and "outcome" not in custom
    assert custom["goal"] == "[2.0, 0.0]"
    assert len(messages["/ground_truth"]) == 11
    row = compute([bag.path]).frame.iloc[0]
    assert row["error"] == ""
    assert row["path_length_m"] == pytest.approx(0.5, abs=LENGTH)
    with pytest.raises(RecorderError, match="closed"):
        bag.write(odometry("/odom", T0_NS, 0.0, 0.0))


# --- killed recorder --------------------------------------------------------------------------


def test_a_recorder_killed_with_sigkill_leaves_a_readable_bag(tmp_path: Path) -> None:
    """50 poses at 0.05 m apart committed one by one, then SIGKILL: 2.45 m of path remain."""
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(
        p for p in (str(REPO), os.environ.get("PYTHONPATH", "")) if p)}
    victim = subprocess.Popen([sys.executable, str(VICTIM), str(tmp_path), "run", "50"],
                              stdout=subprocess.PIPE, text=True, cwd=REPO, env=env)
    try:
        assert victim.stdout is not None
        lines = [victim.stdout.readline().strip() for _ in range(2)]
        assert lines[1] == "READY", lines
        victim.send_signal(signal.SIGKILL)
        assert victim.wait(timeout=60) == -signal.SIGKILL
    finally:
        if victim.poll() is None:
            victim.kill()
            victim.wait()
        if victim.stdout is not None:
            victim.stdout.close()

    bag_dir = Path(lines[0])
    assert bag_dir == tmp_path / "run" / "episode_0000"
    assert not (bag_dir / "metadata.yaml").exists()
    assert (bag_dir / "episode_0000.db3").is_file()

    frame = compute([bag_dir]).frame
    assert len(frame) == 1
    row = frame.iloc[0]
    assert row["error"] == ""
    assert row["n_poses"] == 50
    assert row["path_length_m"] == pytest.approx(49 * 0.05, abs=LENGTH)
    facts = read_episode(bag_dir / "episode_0000.db3").facts
    assert facts.goal == (2.0, 0.0) and facts.start == (0.0, 0.0, 0.0)
    assert facts.run == "run" and facts.episode == "episode_0000"
    assert facts.outcome is None
