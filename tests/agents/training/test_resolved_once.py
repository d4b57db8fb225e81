"""The env's configuration is resolved once, at the edge (issue 39 item 2): ``make_vec_env``
builds one ``Scenario`` (the sim's typed config, the robot, the worlds) for all its envs, each
env selecting its own world from it; imitation's experts share one; an env made from a
``Scenario`` runs as one made from its config; and no module below the edges reads the raw
sim section (``EnvConfig.sim_params``) to resolve it again."""

from __future__ import annotations

import ast
from pathlib import Path

import numpy as np
import pytest

import pic4rl_bridge.scenario as scenario_module
import pic4rl_sim.config as sim_config
from pic4rl_agents.training.envs import make_vec_env
from pic4rl_agents.training.imitation import make_expert
from pic4rl_bridge.config import load_env_config
from pic4rl_bridge.env import NavEnv
from pic4rl_bridge.errors import ConfigError
from pic4rl_bridge.scenario import Scenario

ROOT = Path(__file__).resolve().parents[3]
LIDAR = ROOT / "config" / "env_goto_lidar.yaml"

#: The edges: where a config is loaded, written for a sim node's own process, checked before
#: anything runs, or resolved (``Scenario``). Only these may read ``sim_params``.
EDGES = {
    "pic4rl_bridge/config.py",  # loads it
    "pic4rl_bridge/scenario.py",  # resolves it: the one place
    "pic4rl_bridge/env.py",  # NavEnv(config, sim=...) for users: merges it, then resolves once
    "pic4rl_bridge/recording.py",  # writes the run's config beside its bags
    "pic4rl_agents/runs/config.py",  # loads and writes the run's sections
    "pic4rl_agents/launch/run.py", "pic4rl_agents/stack/driver.py",  # the sim node's file
    "pic4rl_agents/suites/cell.py",  # the sim node's file
    "pic4rl_agents/suites/checks.py",  # a suite's worlds and robots, checked before it runs
    "pic4rl_agents/testing/plan.py",  # the test world, which picks the test pairs
    "pic4rl_agents/training/envs.py",  # no BARN test world, refused before any env
}


def _counting(monkeypatch: pytest.MonkeyPatch) -> dict[str, int]:
    """Counts of ``SimConfig`` builds and ``Scenario``s made from here on."""
    counts = {"build_config": 0, "Scenario": 0}
    build, init = sim_config.build_config, Scenario.__init__

    def counted_build(values):  # type: ignore[no-untyped-def]
        counts["build_config"] += 1
        return build(values)

    def counted_init(self, config):  # type: ignore[no-untyped-def]
        counts["Scenario"] += 1
        init(self, config)

    monkeypatch.setattr(sim_config, "build_config", counted_build)
    monkeypatch.setattr(scenario_module.Scenario, "__init__", counted_init)
    return counts


def test_make_vec_env_resolves_its_config_once_for_all_its_envs(
        monkeypatch: pytest.MonkeyPatch) -> None:
    config = load_env_config(LIDAR, **{"episodes.world_variants": "1,2"})
    counts = _counting(monkeypatch)
    vec = make_vec_env(config, n_envs=2, vec_env="dummy")
    try:
        assert counts == {"build_config": 1, "Scenario": 1}
        first, second = (e.unwrapped.scenario for e in vec.envs)
        assert first is not second and first.sim is second.sim
        assert first.world_at(2) is second.world_at(2)  # built once, shared
        first.select(2)
        assert second.variant is None and first.world is not second.world
        vec.reset()
        assert counts == {"build_config": 1, "Scenario": 1}
    finally:
        vec.close()


def test_an_env_made_from_a_scenario_runs_as_one_made_from_its_config() -> None:
    config = load_env_config(LIDAR)
    resolved = Scenario(config)
    mine, theirs = NavEnv(resolved), NavEnv(config)
    try:
        assert mine.config == theirs.config and mine.scenario.sim is resolved.sim
        obs, info = mine.reset(seed=3)
        expected, info2 = theirs.reset(seed=3)
        np.testing.assert_array_equal(obs, expected)
        assert info == info2
        action = np.array([0.5, 0.2], dtype=np.float32)
        np.testing.assert_array_equal(mine.step(action)[0], theirs.step(action)[0])
    finally:
        mine.close()
        theirs.close()


def test_a_scenario_given_with_overrides_is_resolved_again() -> None:
    resolved = Scenario(load_env_config(LIDAR))
    env = NavEnv(resolved, sim={"lidar.beams": 90})
    try:
        assert env.scenario.sim.robot.lidar is not None
        assert env.scenario.values["lidar.beams"] == 90 != resolved.values["lidar.beams"]
    finally:
        env.close()


@pytest.mark.bad_input
def test_a_scenario_serves_another_env_only_in_another_namespace() -> None:
    resolved = Scenario(load_env_config(LIDAR))
    assert resolved.for_env(resolved.config.replace(**{"ros.namespace": "/r1"})).config \
        .ros.namespace == "/r1"
    with pytest.raises(ConfigError, match=r"^episode_max_steps: differs from the scenario's"):
        resolved.for_env(resolved.config.replace(episode_max_steps=3))


def test_imitation_experts_share_one_resolution(monkeypatch: pytest.MonkeyPatch) -> None:
    resolved = Scenario(load_env_config(LIDAR))
    counts = _counting(monkeypatch)
    experts = [make_expert("explorer", resolved) for _ in range(3)]
    assert len(experts) == 3 and counts == {"build_config": 0, "Scenario": 0}


def _reads_sim_params(path: Path) -> list[int]:
    tree = ast.parse(path.read_text(encoding="utf-8"))
    return [n.lineno for n in ast.walk(tree)
            if isinstance(n, ast.Attribute) and n.attr == "sim_params"]


def test_no_module_below_the_edges_reads_the_raw_sim_section() -> None:
    readers = {}
    for package in sorted(ROOT.glob("pic4rl_*/")):
        for path in sorted(package.rglob("*.py")):
            lines = _reads_sim_params(path)
            if lines:
                readers[path.relative_to(ROOT).as_posix()] = lines
    below = {f: lines for f, lines in readers.items() if f not in EDGES}
    assert not below, f"sim_params read below the edges (resolve it with Scenario): {below}"
    assert {"pic4rl_bridge/scenario.py", "pic4rl_agents/training/envs.py"} <= readers.keys()


def test_the_check_sees_a_read(tmp_path: Path) -> None:
    module = tmp_path / "m.py"
    module.write_text("def f(config):\n    return config.sim_params.get('world')\n")
    assert _reads_sim_params(module) == [2]
    module.write_text("def f(scenario):\n    return scenario.values['world']  # sim_params\n")
    assert _reads_sim_params(module) == []
