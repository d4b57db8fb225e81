"""A recorded BARN episode (config/env_barn.yaml, the privileged planner, in process): its bag
carries the world's reference path length, and its BARN score is the challenge's formula on
the bag's own numbers."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from pic4rl_metrics import compute
from pic4rl_metrics.bags.reader import read_episode
from pic4rl_sim.engine.worlds.barn import barn_data

from pic4rl_bridge.baselines.registry import make_baseline
from pic4rl_bridge.recording import make_env

CONFIG = Path(__file__).resolve().parents[2] / "config" / "env_barn.yaml"
WORLD = 6


def test_a_barn_episodes_bag_carries_the_reference_and_its_score(tmp_path: Path) -> None:
    env = make_env(CONFIG, sim={"world_variant": WORLD},
                   overrides={"record.enabled": True, "record.bags_dir": str(tmp_path),
                              "record.run": "barn"})
    nav = env.unwrapped
    try:
        planner = make_baseline("planner", nav.config, nav.scenario.robot, nav.scenario.world)
        _, info = env.reset(seed=1)
        assert info["start"] == pytest.approx([-2.25, 3.0, 1.57]) and info["goal"] == (-2.25, 13.0)
        planner.reset()
        while True:
            *_, terminated, truncated, info = env.step(planner.action(nav.frame))
            if terminated or truncated:
                break
    finally:
        env.close()
    assert info["outcome"] == "goal"
    bag = tmp_path / "barn" / "episode_0000"
    reference = barn_data()["worlds"][WORLD]["reference_path_length_m"]
    episode = read_episode(bag)
    assert episode.facts.reference_path_m == reference
    assert episode.facts.world == f"barn:{WORLD}" and episode.facts.goal_tolerance_m == 1.0

    row = compute([bag]).frame.iloc[0]
    assert row["error"] == "" and row["success"] == 1.0
    # AT by hand from the bag's poses: the first 0.1 m off the start to the outcome's stamp
    t = (episode.pose.t_ns - episode.pose.t_ns[0]) * 1e-9
    off = np.hypot(episode.pose.x - (-2.25), episode.pose.y - 3.0) >= 0.1
    end = (episode.facts.outcome_stamp_ns - episode.pose.t_ns[0]) * 1e-9
    actual = end - t[np.argmax(off)]
    assert row["barn_time_s"] == pytest.approx(actual, abs=1e-9)
    optimal = reference / 2.0
    expected = optimal / min(max(actual, 2 * optimal), 8 * optimal)
    assert row["barn_score"] == pytest.approx(expected, abs=1e-12)
    assert 0.0 < row["barn_score"] <= 0.5 and math.isfinite(row["barn_score"])
