"""A pairs file says where it was drawn: the pairs the project draws record their world
(``kind:variant``) and robot radius, the shipped files too; the env refuses them in another
world and refuses a start in collision (one line each), and warns about a user's file that
records no world. ``pic4rl-test`` and a suite say so before any episode runs."""

from __future__ import annotations

import json
import logging
from pathlib import Path

import pytest
import yaml

from pic4rl_bridge.env import NavEnv
from pic4rl_bridge.episodes import PairSampler, load_goals_and_poses, save_goals_and_poses
from pic4rl_bridge.errors import ConfigError
from pic4rl_sim.engine.robot_specs import load_robot
from pic4rl_sim.engine.sampling import PAIR_KINDS

REPO = Path(__file__).resolve().parents[2]
LIDAR_CONFIG = REPO / "config" / "env_goto_lidar.yaml"
TEST_PAIRS = REPO / "pic4rl_agents" / "data" / "goals_indoor_test.json"
TRAIN_PAIRS = REPO / "config" / "goals_indoor_train.json"
JACKAL_RADIUS = load_robot("jackal").footprint.bounding_radius_m


def test_drawn_pairs_record_their_world_and_robot_radius(tmp_path: Path) -> None:
    env = NavEnv(LIDAR_CONFIG, sim={"world_variant": 2})
    env.close()
    sampler = PairSampler.for_scenario(env.scenario)
    assert sampler is not None
    path = save_goals_and_poses(sampler.goals_and_poses(3, seed=1, kind=PAIR_KINDS["paper"]),
                                tmp_path / "pairs.json")
    doc = json.loads(path.read_text())
    assert doc["world"] == "indoor:2"
    assert doc["robot_radius_m"] == pytest.approx(JACKAL_RADIUS, abs=1e-4)
    loaded = load_goals_and_poses(path)
    assert (loaded.world, len(loaded.goals)) == ("indoor:2", 3)
    NavEnv(LIDAR_CONFIG, sim={"world_variant": 2},
           overrides={"episodes.file": str(path)}).close()  # its own world: accepted


def test_the_shipped_pairs_files_record_the_indoor_world() -> None:
    for path in (TEST_PAIRS, TRAIN_PAIRS):
        pairs = load_goals_and_poses(path)
        assert pairs.world == "indoor:0"
        assert pairs.robot_radius_m == pytest.approx(JACKAL_RADIUS, abs=1e-4)
        NavEnv(LIDAR_CONFIG, overrides={"episodes.file": str(path)}).close()


@pytest.mark.bad_input
def test_pairs_in_another_world_are_refused_in_one_line() -> None:
    with pytest.raises(ConfigError) as err:
        NavEnv(LIDAR_CONFIG, sim={"world_variant": 2},
               overrides={"episodes.file": str(TEST_PAIRS)})
    assert str(err.value) == (
        f"{TEST_PAIRS}: its pairs were drawn in world indoor:0 but this env runs indoor:2; "
        "give the sim that world (e.g. --sim-kwargs world_variant:0) or pairs of it")


@pytest.mark.bad_input
def test_a_start_in_collision_is_refused_naming_it(tmp_path: Path) -> None:
    doc = json.loads(TEST_PAIRS.read_text())
    doc["poses"][3] = [-6.95, -4.0, 0.0]  # 5 cm from the indoor world's west wall
    path = tmp_path / "bad.json"
    path.write_text(json.dumps(doc))
    with pytest.raises(ConfigError, match=r"^\S+bad.json: poses\[3\]: \(-6.950, -4.000\) is "
                       r".* that start is in collision for this robot \(radius 0.333 m\)$"):
        NavEnv(LIDAR_CONFIG, overrides={"episodes.file": str(path)})


def test_a_users_file_without_a_world_is_warned_about_and_used(
        tmp_path: Path, caplog: pytest.LogCaptureFixture) -> None:
    doc = json.loads(TEST_PAIRS.read_text())
    del doc["world"], doc["robot_radius_m"]
    path = tmp_path / "mine.json"
    path.write_text(json.dumps(doc))
    with caplog.at_level(logging.WARNING, logger="pic4rl_bridge.episodes"):
        env = NavEnv(LIDAR_CONFIG, overrides={"episodes.file": str(path),
                                              "episodes.ordered": True})
    try:
        _, info = env.reset(seed=0)
    finally:
        env.close()
    assert list(info["goal"]) == doc["goals"][0]
    assert [r.getMessage() for r in caplog.records] == [
        f"{path}: the file records no world; its pairs are taken to be in indoor:0"]


@pytest.mark.bad_input
def test_a_suite_runs_a_pairs_file_only_in_its_world(tmp_path: Path) -> None:
    from pic4rl_agents.suites.suite import load_suite

    (tmp_path / "suite.yaml").write_text(yaml.safe_dump({
        "suite": "s", "tasks": [{"name": "goto", "env": str(LIDAR_CONFIG),
                                 "baselines": ["dwa"], "worlds": ["indoor:0", "indoor:1"],
                                 "pairs": ["paper"]}]}))
    with pytest.raises(ConfigError, match=r"tasks\[0\].pairs: 'paper' is invalid; expected "
                       r"pairs of the task's world indoor:1: \S+goals_indoor_test.json was "
                       r"drawn in indoor:0"):
        load_suite(tmp_path / "suite.yaml")
