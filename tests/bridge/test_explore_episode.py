"""Recorded explore episodes (config/env_explore.yaml, in process): the frontier baseline and the
random walk on the same seed, each episode's bag judged by pic4rl_metrics alone. The bags carry
the world's free area, so coverage is a percentage, the frontier's above the random walk's, and
the metrics' area seen from the bag agrees with the area the task paid for."""

from __future__ import annotations

import math
from pathlib import Path

import gymnasium as gym
import pytest
from pic4rl_metrics import compute
from pic4rl_metrics.bags.reader import read_episode

from pic4rl_bridge.baselines.registry import make_baseline
from pic4rl_bridge.tasks.explore import free_area_m2

CONFIG = Path(__file__).resolve().parents[2] / "config" / "env_explore.yaml"
SEED, STEPS = 1, 300


def _run(name: str, bags: Path) -> tuple[float, float, dict]:
    """(reward summed, area the task saw (m²), last info) of one recorded episode."""
    env = gym.make("pic4rl/ExploreLidar-v0", config=CONFIG,
                   overrides={"episode_max_steps": STEPS, "record.enabled": True,
                              "record.bags_dir": str(bags), "record.run": name})
    nav = env.unwrapped
    try:
        baseline = make_baseline(name, nav.config, nav.scenario.robot, nav.scenario.world)
        _, info = env.reset(seed=SEED)
        assert info["goal"] is None
        baseline.reset()
        total = 0.0
        while True:
            _, reward, terminated, truncated, info = env.step(baseline.action(nav.frame))
            total += reward
            if terminated or truncated:
                break
        seen = nav._context.extra["seen"].area_m2
        start = nav._context.start
        assert nav.episode_facts().free_area_m2 == pytest.approx(
            free_area_m2(nav.scenario.world, (start.x, start.y)))
    finally:
        env.close()
    return total, seen, info


def test_frontier_exploration_covers_more_than_a_random_walk(tmp_path: Path) -> None:
    rows = {}
    for name in ("frontier", "random_walk"):
        total, seen, info = _run(name, tmp_path)
        assert info["outcome"] in ("timeout", "goal"), info
        bag = tmp_path / name / "episode_0000"
        episode = read_episode(bag)
        assert episode.facts.task == "explore/lidar" and episode.facts.goal is None
        free = episode.facts.free_area_m2
        assert free is not None and 50.0 < free < 200.0
        row = compute([bag]).frame.iloc[0]
        assert row["error"] == ""
        # the bag's area seen is the task's within the metrics' scan thinning
        assert row["area_seen_m2"] == pytest.approx(seen, rel=0.05)
        assert row["coverage_pct"] == pytest.approx(100.0 * row["area_seen_m2"] / free)
        # the reward paid the area seen after the first scan (reward.area 1, no collision)
        assert 0.0 < total < seen
        rows[name] = row
    frontier, walk = rows["frontier"]["coverage_pct"], rows["random_walk"]["coverage_pct"]
    assert math.isfinite(frontier) and math.isfinite(walk)
    assert frontier > walk + 10.0, (frontier, walk)
