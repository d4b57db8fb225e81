"""Pairs of a kind in the env: ``episodes.pair_kind`` and ``reset(options=...)`` draw pairs the
filter holds, one seed gives one sequence (through ROS 2 too), the path search runs only when
something needs it, recorded episodes carry ``shortest_path_m`` and ``straight_line_m``, and
bad filters are refused."""

from __future__ import annotations

import json
import math
import re
from pathlib import Path

import pytest
from rosbags.highlevel import AnyReader

from pic4rl_bridge.config import EnvConfig
from pic4rl_bridge.env import NavEnv
from pic4rl_bridge.episodes import (
    PairSampler,
    load_goals_and_poses,
    save_goals_and_poses,
)
from pic4rl_bridge.errors import ConfigError
from pic4rl_bridge.recording import make_env
from pic4rl_metrics.contract import parse_facts
from pic4rl_sim.engine.paths import planner_for
from pic4rl_sim.engine.sampling import PAIR_KINDS

REPO = Path(__file__).resolve().parents[2]
LIDAR_CONFIG = REPO / "config" / "env_goto_lidar.yaml"


def pair(info: dict) -> tuple[tuple[float, float], tuple[float, float]]:
    return (info["start"][0], info["start"][1]), (info["goal"][0], info["goal"][1])


def detour(env: NavEnv, start: tuple[float, float], goal: tuple[float, float]) -> float:
    planner = planner_for(env.scenario.world,
                          robot_radius_m=env.scenario.robot.footprint.bounding_radius_m)
    return planner.length(start, goal) / math.dist(start, goal)


def test_paper_pairs_hold_the_filter_and_one_seed_gives_one_sequence() -> None:
    env = NavEnv(LIDAR_CONFIG, overrides={"episodes.pair_kind": "paper"})
    try:
        first = [pair(env.reset(seed=4 if i == 0 else None)[1]) for i in range(4)]
        again = [pair(env.reset(seed=4 if i == 0 else None)[1]) for i in range(4)]
    finally:
        env.close()
    assert first == again and len(set(first)) == 4
    for start, goal in first:
        assert 4.0 <= math.dist(start, goal) <= 8.0
        assert detour(env, start, goal) <= 1.3


def test_plain_any_leaves_sampling_to_the_simulator_and_searches_no_path() -> None:
    """Not recording, kind ``any``: no planner is built (training pays nothing)."""
    env = NavEnv(LIDAR_CONFIG)
    try:
        for i in range(3):
            env.reset(seed=1 if i == 0 else None)
        assert env._sampler is not None and env._sampler._planner is None
    finally:
        env.close()


def test_reset_options_choose_the_kind_and_bounds_for_one_episode() -> None:
    env = NavEnv(LIDAR_CONFIG)
    try:
        _, info = env.reset(seed=2, options={"pair_kind": "paper"})
        start, goal = pair(info)
        assert 4.0 <= math.dist(start, goal) <= 8.0 and detour(env, start, goal) <= 1.3
        for _ in range(3):
            _, info = env.reset(options={"max_distance_m": 2.0})
            assert 1.0 <= math.dist(*pair(info)) <= 2.0  # any's minimum: the sim's 1 m
        _, info = env.reset(options={"pair_kind": "paper", "max_detour": 1.05})
        assert detour(env, *pair(info)) <= 1.05
    finally:
        env.close()


@pytest.mark.parametrize(("options", "message"), [
    ({"pair_kind": "paper", "start": [0.0, 0.0, 0.0]}, "cannot go with start or goal"),
    ({"pair_kind": "nope"}, "pair_kind: 'nope' is invalid; expected one of any, paper"),
    ({"max_detour": -1.0}, "max_detour: -1.0 is invalid"),
    ({"pair_kind": "paper", "max_distance_m": 2.0}, "max_distance_m"),  # below paper's 4 m
])
def test_bad_pair_options_are_refused(options: dict, message: str) -> None:
    env = NavEnv(LIDAR_CONFIG)
    try:
        with pytest.raises(ConfigError, match=message.replace("(", r"\(").replace(")", r"\)")):
            env.reset(seed=0, options=options)
    finally:
        env.close()


@pytest.mark.parametrize(("override", "message"), [
    ({"episodes.min_distance_m": 5.0, "episodes.max_distance_m": 3.0},
     "episodes.max_distance_m: 3.0 is invalid; expected a distance >= min_distance_m=5.0 m"),
    ({"episodes.max_detour": 0.5}, "episodes.max_detour: 0.5 is invalid; expected a ratio >= 1"),
])
def test_a_bad_pair_filter_in_the_config_names_its_key(override: dict, message: str) -> None:
    with pytest.raises(ConfigError, match="^" + re.escape(message)):
        EnvConfig().replace(**override)


def test_reset_options_that_unmake_the_kind_name_the_option() -> None:
    env = NavEnv(LIDAR_CONFIG)
    try:
        with pytest.raises(ConfigError, match=re.escape(
                "pair_kind 'paper': reset options: max_distance_m: 2.0 is invalid; expected a "
                "distance >= min_distance_m=4.0 m")):
            env.reset(seed=0, options={"pair_kind": "paper", "max_distance_m": 2.0})
    finally:
        env.close()


def test_a_real_robot_cannot_draw_pairs_of_a_kind() -> None:
    config = EnvConfig(transport="ros", robot="jackal").replace(
        **{"episodes.pair_kind": "paper"})
    with pytest.raises(ConfigError, match="episodes.pair_kind: 'paper' with filters needs a "
                                          "simulated world"):
        NavEnv(config)


def recorded_facts(bag: Path) -> dict:
    with AnyReader([bag]) as reader:
        conn = next(c for c in reader.connections if c.topic == "/episode/facts")
        _, _, raw = next(reader.messages(connections=[conn]))
        return json.loads(reader.deserialize(raw, conn.msgtype).data)


def test_recorded_episodes_carry_the_shortest_path_and_the_straight_line(
        tmp_path: Path) -> None:
    """The facts' lengths are the planner's for the episode's start and goal; the metrics'
    reader takes them as known facts."""
    env = make_env(LIDAR_CONFIG, overrides={
        "episodes.pair_kind": "paper", "record.enabled": True, "episode_max_steps": 3,
        "record.bags_dir": str(tmp_path), "record.run": "r"})
    try:
        _, info = env.reset(seed=9)
        for _ in range(3):
            env.step(env.action_space.sample() * 0)
    finally:
        env.close()
    facts = recorded_facts(tmp_path / "r" / "episode_0000")
    start, goal = pair(info)
    assert facts["straight_line_m"] == pytest.approx(math.dist(start, goal))
    assert facts["shortest_path_m"] == pytest.approx(detour(env.unwrapped, start, goal)
                                                     * math.dist(start, goal), abs=1e-3)
    assert facts["straight_line_m"] <= facts["shortest_path_m"] <= 1.3 * facts["straight_line_m"]
    parsed, given = parse_facts(facts, source="test")
    assert {"shortest_path_m", "straight_line_m"} <= given
    assert parsed.shortest_path_m == pytest.approx(facts["shortest_path_m"])


def test_pairs_of_a_kind_drawn_from_a_seed_round_trip_a_goals_and_poses_file(
        tmp_path: Path) -> None:
    env = NavEnv(LIDAR_CONFIG)
    env.close()
    sampler = PairSampler.for_scenario(env.scenario)
    assert sampler is not None
    pairs = sampler.goals_and_poses(6, seed=11, kind=PAIR_KINDS["paper"])
    assert pairs == sampler.goals_and_poses(6, seed=11, kind=PAIR_KINDS["paper"])
    path = save_goals_and_poses(pairs, tmp_path / "test_pairs.json", comment="six paper pairs")
    loaded = load_goals_and_poses(path)
    assert len(loaded.goals) == 6 and loaded.initial_pose is None
    for pose, goal in zip(loaded.poses, loaded.goals):
        assert 4.0 - 2e-3 <= math.dist(pose[:2], goal) <= 8.0 + 2e-3
    with pytest.raises(ConfigError, match="exists"):
        save_goals_and_poses(pairs, path)
    assert json.loads(path.read_text())["comment"] == "six paper pairs"


@pytest.mark.integration
def test_ros_and_in_process_run_the_same_paper_pairs(domain: int, start_sim) -> None:
    start_sim(domain, "--params-file", str(LIDAR_CONFIG))
    paper = {"episodes.pair_kind": "paper"}
    ros = NavEnv(LIDAR_CONFIG, transport="ros", overrides={**paper, "ros.domain_id": domain})
    local = NavEnv(LIDAR_CONFIG, overrides=paper)
    try:
        for episode in range(3):
            seed = 5 if episode == 0 else None
            (_, info_r), (_, info_l) = ros.reset(seed=seed), local.reset(seed=seed)
            assert info_r["seed"] == info_l["seed"]
            assert pair(info_r) == pair(info_l)  # the same drawn pair, as sent
            assert 4.0 <= math.dist(*pair(info_r)) <= 8.0
    finally:
        ros.close()
        local.close()
