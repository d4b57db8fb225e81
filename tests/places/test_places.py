"""The places table of ``docs/architecture.md``, executed: for a metric, a baseline, a task
and a sensor, a piece written outside the packages (its files under ``tests/places/<piece>/``,
registered as a user registers one: imported, or named in its ``pyproject.toml``'s entry
points) is run end to end, and the table's count for that piece is the number of files its
folder holds."""

from __future__ import annotations

import importlib
import math
import os
import re
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
HERE = Path(__file__).resolve().parent
DOC = ROOT / "docs" / "architecture.md"
#: Each piece's folder under ``tests/places/`` → its row in the places table.
ROWS = {"metric": "a metric", "baseline": "a baseline", "task": "a task", "sensor": "a sensor"}
GOTO = ROOT / "config" / "env_goto_lidar.yaml"


def _written(piece: str) -> list[Path]:
    """The files a user wrote for ``piece``."""
    return sorted(p for p in (HERE / piece).rglob("*")
                  if p.is_file() and "__pycache__" not in p.parts)


def _doc_count(row: str) -> int:
    text = DOC.read_text(encoding="utf-8").split("## Places for a new piece", 1)[1]
    found = re.search(rf"^\| {re.escape(row)} \| (\d+) \|", text, re.MULTILINE)
    assert found, f"docs/architecture.md's places table has no row {row!r}"
    return int(found[1])


def _install(piece: str, site: Path) -> dict[str, str]:
    """What ``pip install`` of the user's package ``piece`` leaves behind: its entry points
    (from its ``pyproject.toml``) in a ``.dist-info`` under ``site``; the environment of a
    process that has it installed (its modules on the path)."""
    project = tomllib.loads((HERE / piece / "pyproject.toml").read_text())["project"]
    info = site / f"{project['name'].replace('-', '_')}-{project['version']}.dist-info"
    info.mkdir(parents=True)
    (info / "METADATA").write_text(f"Metadata-Version: 2.1\nName: {project['name']}\n"
                                   f"Version: {project['version']}\n")
    (info / "entry_points.txt").write_text("".join(
        f"[{group}]\n" + "".join(f"{k} = {v}\n" for k, v in points.items()) + "\n"
        for group, points in project["entry-points"].items()))
    path = os.pathsep.join([str(site), str(HERE / piece), os.environ.get("PYTHONPATH", "")])
    return {**os.environ, "PYTHONPATH": path}


def _console(script: str, argv: list[str], env: dict[str, str]) -> subprocess.CompletedProcess:
    """The installed console script ``script`` run as a user runs it."""
    return subprocess.run([str(Path(sys.executable).parent / script), *argv], env=env,
                          capture_output=True, text=True, timeout=500, check=False)


@pytest.mark.parametrize("piece", sorted(ROWS))
def test_the_table_counts_the_files_each_piece_took(piece: str) -> None:
    files = _written(piece)
    assert files, f"tests/places/{piece}/ holds no file"
    assert _doc_count(ROWS[piece]) == len(files), \
        f"{ROWS[piece]}: the table says {_doc_count(ROWS[piece])}, the test wrote {len(files)}"


# -- a metric: one file, registered by its import -----------------------------------------------

def test_a_metric_from_outside_gets_its_column_and_its_table_place(
        monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    from pic4rl_metrics import METRIC_TABLE, compute
    from pic4rl_metrics.synthetic import circle, write_episode_bag
    from pic4rl_metrics.tables.groups import render_groups
    from pic4rl_metrics.tables.results import table_columns

    monkeypatch.syspath_prepend(str(HERE / "metric"))
    try:
        importlib.import_module("places_chord")  # as the user's program imports it
        # A quarter of a circle of radius 1 m: the chord is sqrt(2) m, the path pi/2 m.
        quarter = circle(1.0, 0.5, math.pi, dt_s=math.pi / 100)
        bag = write_episode_bag(tmp_path / "quarter", quarter, goal=(1.0, 0.0), outcome="goal")
        frame = compute([bag]).frame
        assert frame.iloc[0]["chord_m"] == pytest.approx(math.sqrt(2.0), abs=1e-9)
        assert frame.iloc[0]["path_length_m"] == pytest.approx(math.pi / 2, rel=1e-3)
        assert table_columns(frame)[-1] == "chord_m"
        table = render_groups(frame.assign(agent="mine"), "markdown", columns=table_columns)
        header, _, row = table.splitlines()[:3]
        assert header.endswith("| chord [m] |") and row.endswith("| 1.41 |"), table
    finally:
        METRIC_TABLE.remove("chord_m")
        sys.modules.pop("places_chord", None)


# -- a baseline: its module and its entry point -------------------------------------------------

def test_a_baseline_from_outside_is_driven_by_pic4rl_test_and_judged(tmp_path: Path) -> None:
    from pic4rl_metrics import compute

    env = _install("baseline", tmp_path / "site")
    bags = tmp_path / "bags"
    done = _console("pic4rl-test", ["--baseline", "bearing", "--episodes", "2", "--bags",
                                    str(bags), "--run", "r", "--env-kwargs",
                                    "episode_max_steps:80", "--no-progress", "--ros-args",
                                    "--params-file", str(GOTO)], env)
    assert done.returncode == 0, done.stderr
    assert "bearing" in done.stdout  # its row of the table
    result = compute([bags / "r" / "bearing"])
    assert len(result.results) == 2 and not result.failed
    frame = result.frame
    assert set(frame["agent"]) == {"bearing"}
    assert set(frame["outcome"]) <= {"goal", "collision", "timeout"}
    assert (frame["path_length_m"] > 0.5).all()  # it drove toward its goals


def test_a_bad_entry_point_is_one_line_naming_it(monkeypatch: pytest.MonkeyPatch) -> None:
    from importlib.metadata import EntryPoint, EntryPoints

    from pic4rl_base import plugins
    from pic4rl_base.errors import ConfigError
    from pic4rl_bridge.baselines.registry import BASELINE_GROUP, BASELINE_TABLE, BaselineSpec
    from pic4rl_bridge.settings.tasks import TASK_GROUP, TASK_TABLE, TaskSpec

    def points(name: str, value: str) -> None:
        monkeypatch.setattr(plugins, "installed", lambda: EntryPoints([
            EntryPoint(name, value, BASELINE_GROUP), EntryPoint(name, value, TASK_GROUP)]))

    points("mine", "math:pi")
    with pytest.raises(ConfigError, match=r"^entry point mine = math:pi \(group "
                       r"pic4rl.baselines\): it names a float; expected a BaselineSpec$"):
        plugins.load_group(BASELINE_GROUP, BaselineSpec, taken=BASELINE_TABLE)
    points("mine", "math:sqrt")  # a function that makes the entry, failing
    with pytest.raises(ConfigError, match=r"^entry point mine = math:sqrt \(group "
                       r"pic4rl.baselines\): calling it failed: TypeError"):
        plugins.load_group(BASELINE_GROUP, BaselineSpec, taken=BASELINE_TABLE)
    points("dwa", "math:pi")
    with pytest.raises(ConfigError, match="'dwa' is one of pic4rl's own"):
        plugins.load_group(BASELINE_GROUP, BaselineSpec, taken=BASELINE_TABLE)
    points("mine", "no_such_module_xyz:SPEC")
    with pytest.raises(ConfigError, match="ModuleNotFoundError"):
        plugins.load_group(BASELINE_GROUP, BaselineSpec, taken=BASELINE_TABLE)
    monkeypatch.syspath_prepend(str(HERE / "task"))
    monkeypatch.delitem(sys.modules, "escape_entry", raising=False)
    points("flee", "escape_entry:SPEC")
    with pytest.raises(ConfigError, match="it names TaskSpec 'escape'; expected the entry "
                                          "point's name 'flee'"):
        plugins.load_group(TASK_GROUP, TaskSpec, taken=TASK_TABLE)


# -- a task: its table entry, its code and its entry point --------------------------------------

#: A user's program: the task's Gymnasium id, made and driven for one recorded episode by
#: pic4rl's DWA toward the episode's goal (the task itself has none).
DRIVE = """
import json, sys
import gymnasium as gym
import numpy as np
import pic4rl_bridge  # registers the ids, the user's among them
from pic4rl_bridge.baselines.dwa import DwaController
from pic4rl_bridge.settings.baselines import BaselinesConfig
env = gym.make("places/Escape-v0", config=sys.argv[1], overrides={
    "episode_max_steps": 150, "record.enabled": True, "record.bags_dir": sys.argv[2],
    "record.run": "r"})
obs, info = env.reset(seed=0)
dwa = DwaController(env.unwrapped.scenario.robot, BaselinesConfig().dwa)
first, done, terms = obs, False, set()
while not done:
    action = dwa.action(env.unwrapped.frame)
    obs, reward, terminated, truncated, info = env.step(action)
    terms |= set(info["reward_terms"])
    done = terminated or truncated
env.close()
print(json.dumps({"first": first.tolist(), "last": obs.tolist(), "terms": sorted(terms),
                  "outcome": info["outcome"]}))
"""


def test_a_task_from_outside_gets_an_env_id_an_episode_and_a_judged_bag(tmp_path: Path) -> None:
    import json

    from pic4rl_metrics import compute

    env = _install("task", tmp_path / "site")
    done = subprocess.run([sys.executable, "-c", DRIVE, str(GOTO), str(tmp_path / "bags")],
                          env=env, capture_output=True, text=True, timeout=500, check=False)
    assert done.returncode == 0, done.stderr
    episode = json.loads(done.stdout.splitlines()[-1])
    assert episode["terms"] == ["away", "collision", "escaped", "step"]
    assert episode["first"][0] == pytest.approx(0.0, abs=1e-6)  # its own observation
    result = compute([tmp_path / "bags" / "r"])
    assert len(result.results) == 1 and not result.failed
    row = result.frame.iloc[0]
    assert row["task"] == "escape" and row["outcome"] == episode["outcome"]
    assert episode["outcome"] == "goal" and episode["last"][0] >= 1.0
    assert row["path_length_m"] >= 1.0  # it got 1 m away, as the bag shows


# -- a sensor: its module and its entry points --------------------------------------------------

#: A user's program: a goToPose env whose robot now carries the goal range finder (its sim
#: parameter set like any other) and that observes it beside the LiDAR, one recorded episode of
#: seeded random actions, then the engine's step messages decoded by the bridge's table.
SENSE = """
import json, math, sys
import gymnasium as gym
import pic4rl_bridge
from pic4rl_base.geometry import Pose2D
from pic4rl_bridge.readings.sensor_table import BY_NAME
from pic4rl_sim.node.messages import StateMessages

env = gym.make("pic4rl/GoToPoseLidar-v0", config=sys.argv[1], sim={"goal_range.noise_std_m": 0.0},
               overrides={"sensors": ["lidar", "goal_range"], "episode_max_steps": 20,
                          "record.enabled": True, "record.bags_dir": sys.argv[2],
                          "record.run": "r"})
env.reset(seed=3)
env.action_space.seed(3)
done = False
while not done:
    obs, _, terminated, truncated, _ = env.step(env.action_space.sample())
    done = terminated or truncated
engine = env.unwrapped.transport.engine
messages = StateMessages(engine)
messages.fill(engine, 1)
sensor = BY_NAME["goal_range"]
origin = Pose2D(0.0, 0.0, 0.0)
decoded = sensor.decode(dict(messages.published)[sensor.interface], origin, "goal_range")
pose = engine.robot_pose()
print(json.dumps({"decoded": decoded, "read": sensor.read(engine, origin),
                  "true": math.hypot(engine.goal[0] - pose.x, engine.goal[1] - pose.y),
                  "topic": env.unwrapped.config.topics.goal_range,
                  "keys": sorted(obs), "observed": float(obs["goal_range"][0])}))
env.close()
"""


def _messages(bag: Path, topic: str) -> list[tuple[int, object]]:
    from rosbags.highlevel import AnyReader

    from pic4rl_metrics.contract import typestore

    with AnyReader([bag], default_typestore=typestore()) as reader:
        msgs = [reader.deserialize(raw, c.msgtype) for c, _, raw in reader.messages(
            [c for c in reader.connections if c.topic == topic])]
    return [(m.header.stamp.sec * 10**9 + m.header.stamp.nanosec, m) for m in msgs]


def _ranges_are_the_goal_distance(bags: Path, steps: int) -> None:
    """The recorded run's ``/goal_range`` holds a message a step, each the distance from that
    step's ground-truth pose to the episode's goal."""
    bag = next(bags.rglob("metadata.yaml")).parent
    ranges = _messages(bag, "/goal_range")
    poses = dict(_messages(bag, "/ground_truth"))
    goal = _messages(bag, "/goal_pose")[0][1].pose.position
    assert len(ranges) >= steps and set(dict(ranges)) <= set(poses)
    for stamp, msg in ranges:
        p = poses[stamp].pose.pose.position
        assert msg.range == pytest.approx(math.hypot(goal.x - p.x, goal.y - p.y), rel=1e-6)


def test_a_sensor_from_outside_is_simulated_published_recorded_decoded_and_observed(
        tmp_path: Path) -> None:
    import json

    env = _install("sensor", tmp_path / "site")
    done = subprocess.run([sys.executable, "-c", SENSE, str(GOTO), str(tmp_path / "bags")],
                          env=env, capture_output=True, text=True, timeout=500, check=False)
    assert done.returncode == 0, done.stderr
    seen = json.loads(done.stdout.splitlines()[-1])
    assert seen["topic"] == "goal_range"  # topics.goal_range, from the reading's entry
    assert seen["decoded"] == pytest.approx(seen["true"], rel=1e-6)
    assert seen["read"] == pytest.approx(seen["true"], rel=1e-6)  # in process, no message
    assert seen["keys"] == ["goal", "goal_range", "lidar"]  # observed: a Dict key of its own
    assert seen["observed"] == pytest.approx(seen["true"], rel=1e-6)
    _ranges_are_the_goal_distance(tmp_path / "bags" / "r", 20)


def test_a_sensor_from_outside_leaves_every_random_stream_of_pics_as_it_was(
        tmp_path: Path) -> None:
    """A user's sensor draws from a stream of its own, after every stream of pic4rl's, so the
    same seed gives the same sampling, noise and crowd with it installed."""
    import json

    code = "import json; from pic4rl_sim.engine import core; print(json.dumps(core._STREAMS))"
    run = [sys.executable, "-c", code]
    plain = subprocess.run(run, capture_output=True, text=True, timeout=120, check=True)
    mine = json.loads(plain.stdout.splitlines()[-1])
    user = subprocess.run(run, env=_install("sensor", tmp_path / "site"), capture_output=True,
                          text=True, timeout=120, check=True)
    theirs = json.loads(user.stdout.splitlines()[-1])
    assert {"sampling", "lidar", "crowd", "sonar"} <= set(mine)
    assert theirs == [*mine, "goal_range"]


#: The same over ROS 2: the sim node publishes the user's topic, the ROS transport records it
#: and observes it, each step's observed range the one its message carried.
SENSE_ROS = """
import json, sys
import gymnasium as gym
import pic4rl_bridge

env = gym.make("pic4rl/GoToPoseLidar-v0", config=sys.argv[1], transport="ros",
               overrides={"ros.domain_id": int(sys.argv[3]), "episode_max_steps": 15,
                          "sensors": ["lidar", "goal_range"], "record.enabled": True,
                          "record.bags_dir": sys.argv[2], "record.run": "r"})
obs, _ = env.reset(seed=3)
env.action_space.seed(3)
observed, done = [float(obs["goal_range"][0])], False
while not done:
    obs, _, terminated, truncated, _ = env.step(env.action_space.sample())
    observed.append(float(obs["goal_range"][0]))
    done = terminated or truncated
env.close()
print(json.dumps(observed))
"""


@pytest.mark.integration
def test_the_sensor_from_outside_goes_over_ros_too(tmp_path: Path) -> None:
    import json

    from ros_helpers import SimProcess, next_domain, sim_command, sim_env

    env = _install("sensor", tmp_path / "site")
    domain, path = next_domain(), {"PYTHONPATH": env["PYTHONPATH"]}
    sim = SimProcess(sim_command("--params-file", str(GOTO)), domain, tmp_path / "sim.log",
                     env_extra=path)
    try:
        done = subprocess.run([sys.executable, "-c", SENSE_ROS, str(GOTO),
                               str(tmp_path / "bags"), str(domain)], env=sim_env(domain, path),
                              capture_output=True, text=True, timeout=300, check=False)
    finally:
        sim.stop()
    assert done.returncode == 0, done.stderr
    _ranges_are_the_goal_distance(tmp_path / "bags" / "r", 15)
    bag = next((tmp_path / "bags" / "r").rglob("metadata.yaml")).parent
    sent = [msg.range for _, msg in _messages(bag, "/goal_range")]
    assert json.loads(done.stdout.splitlines()[-1]) == pytest.approx(sent[-16:], rel=1e-6)
