"""The env's configuration is resolved once, at the edge (issue 39 item 2): ``make_vec_env``
builds one ``Scenario`` (the sim's typed config, the robot, the worlds) for all its envs, each
env selecting its own world from it; imitation's experts share one; an env made from a
``Scenario`` runs as one made from its config; and no module below the edges reads the raw
sim section (``EnvConfig.sim_params``) to resolve it again."""

from __future__ import annotations

import ast
import dataclasses
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

#: The edges: where a config is loaded or written as it was given, or resolved
#: (``Scenario``). Only these read ``sim_params``; the rest (the sim node's params files of
#: pic4rl-run, a suite's cells and a stack's driver, the test world, the BARN test-world
#: check) take a ``Scenario``'s resolved values.
EDGES = {
    "pic4rl_bridge/config.py",  # loads it
    "pic4rl_bridge/scenario.py",  # resolves it: the one place
    "pic4rl_bridge/env.py",  # NavEnv(config, sim=...) for users: merges it, then resolves once
    "pic4rl_bridge/recording.py",  # writes the run's config beside its bags
    "pic4rl_agents/runs/config.py",  # loads and writes the run's sections
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
def test_a_scenario_serves_another_env_only_where_it_resolves_the_same() -> None:
    resolved = Scenario(load_env_config(LIDAR))
    assert resolved.for_env(resolved.config.replace(**{"ros.namespace": "/r1"})).config \
        .ros.namespace == "/r1"
    slower = resolved.for_env(resolved.config.replace(max_linear_m_s=0.2, episode_max_steps=3))
    assert slower.robot.max_linear_m_s == 0.2 != resolved.robot.max_linear_m_s
    assert slower.sim is resolved.sim and slower.values is resolved.values
    with pytest.raises(ConfigError, match=r"^robot: differs from the scenario's"):
        resolved.for_env(resolved.config.replace(robot="burger"))
    with pytest.raises(ConfigError, match=r"^sim: differs from the scenario's"):
        resolved.for_env(dataclasses.replace(
            resolved.config, sim_params={**resolved.config.sim_params, "world": "empty"}))


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
    assert readers.keys() == EDGES  # each edge still reads it: the list stays true


def test_the_check_sees_a_read(tmp_path: Path) -> None:
    module = tmp_path / "m.py"
    module.write_text("def f(config):\n    return config.sim_params.get('world')\n")
    assert _reads_sim_params(module) == [2]
    module.write_text("def f(scenario):\n    return scenario.values['world']  # sim_params\n")
    assert _reads_sim_params(module) == []


def test_a_training_run_with_imitation_resolves_its_env_once(
        monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    """The trainer hands one ``Scenario`` to its envs and imitation's experts (no evaluation
    env here: it would be another config, its own pairs, resolved on its own)."""
    from agents_helpers import LIDAR_TD3, TINY

    from pic4rl_agents.training import train

    made: list[object] = []
    init = Scenario.__init__

    def counted_init(self, config):  # type: ignore[no-untyped-def]
        made.append(config)
        init(self, config)

    monkeypatch.setattr(scenario_module.Scenario, "__init__", counted_init)
    args = ["--no-progress", "--run", "once", "--hyperparams", f"runs_dir:{tmp_path}", *TINY,
            "imitation.enabled:true", "imitation.bc_steps:20", "imitation.dagger_rounds:0",
            "imitation.critic_warmup_steps:0", "eval.interval_steps:0", "eval.interval_s:0",
            "checkpoint.interval_steps:0", "learning_starts:20", "-n", "40",
            "--env-kwargs", "episode_max_steps:20", "min_linear_m_s:0.0",
            "--ros-args", "--params-file", str(LIDAR_TD3)]
    assert train.main(args) == 0
    assert len(made) == 1
    assert (tmp_path / "once" / "model.zip").is_file()


def test_the_sim_node_takes_a_scenarios_resolved_values_as_its_params_file(
        tmp_path: Path) -> None:
    """What pic4rl-run, a suite's ROS cell and a stack's driver write for the sim node: the
    resolved values (empty arrays, which a ROS params file cannot type, left out), declared
    by the node as they are."""
    import rclpy
    from rclpy.node import Node

    from pic4rl_base import params_file
    from pic4rl_sim.node.parameters import declare

    resolved = Scenario(load_env_config(LIDAR, transport="ros",
                                        **{"robot": "burger", "max_linear_m_s": 0.2}))
    assert resolved.values["start_pose"] == [] and "start_pose" not in resolved.node_values
    file = tmp_path / "sim.yaml"
    file.write_text(params_file.dump({"/**": resolved.node_values}))
    context = rclpy.Context()
    rclpy.init(args=["--ros-args", "--params-file", str(file)], context=context)
    try:
        node = Node("resolved_probe", context=context)
        try:
            _, values = declare(node)
            assert values == resolved.values and values["robot"] == "burger"
        finally:
            node.destroy_node()
    finally:
        rclpy.shutdown(context=context)
