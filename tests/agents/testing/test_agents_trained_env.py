"""A test env never changes what an agent was trained to observe or how its actions act: the
settings of ``pic4rl_bridge.config.agent_keys`` come from the agent's own config; a params
file, ``-p`` or ``--env-kwargs`` that contradicts one is refused in one line naming the key,
both values and where the other came from, and a suite with such an env file is refused before
any cell runs. ``config/suite_table1.yaml`` gives each shipped agent its trained settings."""

from __future__ import annotations

import contextlib
import io
from pathlib import Path

import pytest
import yaml
from agents_helpers import ROOT

from pic4rl_agents.suites.cell import _plan
from pic4rl_agents.suites.suite import load_suite
from pic4rl_agents.testing import plan as testplan
from pic4rl_agents.testing import tester
from pic4rl_agents.testing.plan import resolve_agents
from pic4rl_bridge.config import AGENT_KEYS, EnvConfig, agent_keys
from pic4rl_bridge.errors import ConfigError

TD3_LIDAR = ROOT / "checkpoints" / "td3_lidar"


def run_main(argv: list[str]) -> tuple[int, str]:
    err = io.StringIO()
    with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(err):
        code = tester.main(argv)
    return code, err.getvalue()


def test_the_declared_keys_are_env_parameters_and_follow_the_sensor() -> None:
    params = EnvConfig().to_params()
    for key in AGENT_KEYS:
        assert key in params or any(p.startswith(key) for p in params), key
    lidar, depth = agent_keys(EnvConfig()), agent_keys(EnvConfig(sensor="depth"))
    assert {"lidar.clip_m", "lidar.sectors", "min_linear_m_s"} <= set(lidar)
    assert not any(k.startswith("depth.") for k in lidar)
    assert {"depth.obs_width", "depth.clip_m", "depth.encoding"} <= set(depth)
    assert "episode_max_steps" not in lidar and "reward.goal" not in lidar


@pytest.mark.bad_input
def test_an_override_that_changes_the_agents_range_is_refused(tmp_path: Path) -> None:
    code, err = run_main(["--agent", str(TD3_LIDAR), "--bags", str(tmp_path), "--no-progress",
                          "--env-kwargs", "lidar.clip_m:10.0"])
    assert code == 2
    assert err.splitlines() == [
        f"pic4rl-test: --agent {TD3_LIDAR}: lidar.clip_m: -p/--env-kwargs gives 10.0 but "
        f"the agent was trained with 3.5 ({TD3_LIDAR / 'config.yaml'}); a test env must not "
        "change what an agent observes or how it acts: remove lidar.clip_m there or set "
        "it to 3.5"]
    assert not list(tmp_path.iterdir())  # nothing driven, no run folder


@pytest.mark.bad_input
def test_a_params_file_that_changes_the_agents_settings_is_refused_naming_it(
        tmp_path: Path) -> None:
    env = tmp_path / "env.yaml"
    env.write_text(yaml.safe_dump({"nav_env": {"ros__parameters": {
        "episode_max_steps": 50, "min_linear_m_s": 0.0, "lidar": {"clip_m": 10.0}}}}))
    code, err = run_main(["--agent", str(TD3_LIDAR), "--bags", str(tmp_path / "bags"),
                          "--ros-args", "--params-file", str(env)])
    assert code == 2
    line, = err.splitlines()
    assert line.startswith(f"pic4rl-test: --agent {TD3_LIDAR}: min_linear_m_s: {env} gives 0.0 "
                           "but the agent was trained with 0.1")
    assert "(also lidar.clip_m)" in line


def test_a_test_env_that_agrees_or_is_silent_keeps_the_agents_settings(tmp_path: Path) -> None:
    env = tmp_path / "env.yaml"
    env.write_text(yaml.safe_dump({"nav_env": {"ros__parameters": {
        "episode_max_steps": 50, "lidar": {"clip_m": 3.5}}}}))
    plain, ros = tester.split_ros_args(["--agent", str(TD3_LIDAR), "--ros-args",
                                        "--params-file", str(env)])
    spec, = resolve_agents(tester.build_plan(tester.build_parser().parse_args(plain), ros))
    assert (spec.run.env.lidar.clip_m, spec.run.env.min_linear_m_s) == (3.5, 0.1)
    assert spec.run.env.episode_max_steps == 50  # the test env's own keys still apply


@pytest.mark.bad_input
def test_a_suite_whose_env_contradicts_an_agent_is_refused_before_any_cell(
        tmp_path: Path) -> None:
    (tmp_path / "env.yaml").write_text(yaml.safe_dump({"nav_env": {"ros__parameters": {
        "lidar": {"clip_m": 10.0}}}}))
    (tmp_path / "suite.yaml").write_text(yaml.safe_dump({
        "suite": "s", "tasks": [{"name": "goto", "env": "env.yaml",
                                 "agents": {"td3": str(TD3_LIDAR)}}]}))
    with pytest.raises(ConfigError, match=r"^\S+suite.yaml: tasks\[0\].agents.td3: --agent "
                       r"\S+: lidar.clip_m: \S+env.yaml gives 10.0 but the agent was "
                       r"trained with 3.5"):
        load_suite(tmp_path / "suite.yaml")


def test_the_table1_suite_gives_each_agent_its_trained_observation(tmp_path: Path) -> None:
    suite = load_suite(ROOT / "config" / "suite_table1.yaml", bags_dir=tmp_path)
    trained = {}
    for cell in suite.cells:
        if cell.agent_path and cell.agent not in trained:
            spec, = resolve_agents(_plan(cell, suite.root, episodes=1, pairs="", domain=1))
            trained[cell.agent] = spec.run.env
    assert set(trained) == {"td3_lidar", "sac_lidar", "td3_depth", "sac_depth",
                            "sac_person_hybrid", "td3_person_hybrid"}
    for name in ("td3_lidar", "sac_lidar"):
        env = trained[name]
        assert (env.lidar.clip_m, env.lidar.sectors, env.min_linear_m_s) == (3.5, 36, 0.1)
        assert env.max_linear_m_s == 0.5 and env.normalize_observations
    for name in ("td3_depth", "sac_depth"):
        assert (trained[name].depth.obs_width, trained[name].depth.obs_height) == (40, 30)
    for name in ("sac_person_hybrid", "td3_person_hybrid"):
        assert trained[name].lidar.clip_m == 5.0 and trained[name].person.control == "hybrid"


@pytest.mark.bad_input
def test_a_test_robot_that_changes_the_agents_speed_range_or_period_is_refused(
        tmp_path: Path) -> None:
    """The same keys, but a slower robot (the Burger's 0.22 m/s caps the agent's 0.5) or
    another control period, given to the env: the agent's actions would mean something else."""
    for env, theirs in (
            ("robot:burger", "v in [0.1, 0.22] m/s, |ω| ≤ 1 rad/s every 0.1 s"),
            ("control_dt_s:0.05", "v in [0.1, 0.5] m/s, |ω| ≤ 1 rad/s every 0.05 s")):
        code, err = run_main(["--agent", str(TD3_LIDAR), "--bags", str(tmp_path),
                              "--env-kwargs", env])
        assert code == 2
        assert err.splitlines() == [
            f"pic4rl-test: --agent {TD3_LIDAR}: its test robot drives {theirs} but the agent was "
            f"trained on v in [0.1, 0.5] m/s, |ω| ≤ 1 rad/s every 0.1 s "
            f"({TD3_LIDAR / 'config.yaml'}); an action must mean what it meant in training: test "
            "it on a robot as fast, at its period"]
    assert not list(tmp_path.iterdir())


def _sim_refusal(key: str, source: str, theirs: object, mine: object, also: str = "") -> str:
    return (f"pic4rl-test: --agent {TD3_LIDAR}: {key}: {source} gives {theirs!r} but the agent "
            f"was trained with {mine!r} ({TD3_LIDAR / 'config.yaml'}){also}; a test env must "
            f"not change what an agent observes or how it acts: remove {key} there or set it "
            f"to {mine!r}")


@pytest.mark.bad_input
@pytest.mark.parametrize(("sim", "key", "theirs", "mine", "also"), [
    ("lidar.range_max_m:1.5", "lidar.range_max_m", 1.5, 10.0, ""),
    ("lidar.beams:180", "lidar.beams", 180, 360, ""),
    ("lidar.fov_deg:270", "lidar.fov_deg", 270.0, 360.0, ""),
    ("control_dt_s:0.05", "control_dt_s", 0.05, 0.1, ""),
    # the Burger's own LiDAR starts at another range: named after the robot
    ("robot:burger", "robot", "burger", "jackal", " (also lidar.range_min_m)"),
])
def test_a_sim_override_that_changes_what_the_agent_observes_is_refused(
        tmp_path: Path, sim: str, key: str, theirs: object, mine: object, also: str) -> None:
    """td3_lidar was trained on the sim's 10 m, 360-beam LiDAR (its config.yaml's sim
    section): a 1.5 m sensor would show free space where obstacles stand 2-3.5 m away."""
    code, err = run_main(["--agent", str(TD3_LIDAR), "--bags", str(tmp_path), "--no-progress",
                          "--sim-kwargs", sim])
    assert code == 2
    assert err.splitlines() == [_sim_refusal(key, "--sim-kwargs", theirs, mine, also)]
    assert not list(tmp_path.iterdir())


@pytest.mark.bad_input
def test_a_params_files_sim_section_that_changes_the_agents_sensor_is_refused_naming_it(
        tmp_path: Path) -> None:
    env = tmp_path / "env.yaml"
    env.write_text(yaml.safe_dump({"sim": {"ros__parameters": {"lidar": {"range_max_m": 2.0}}},
                                   "nav_env": {"ros__parameters": {"episode_max_steps": 50}}}))
    code, err = run_main(["--agent", str(TD3_LIDAR), "--bags", str(tmp_path / "bags"),
                          "--ros-args", "--params-file", str(env)])
    assert code == 2
    assert err.splitlines() == [
        _sim_refusal("lidar.range_max_m", f"{env} (sim section)", 2.0, 10.0)]
    assert not (tmp_path / "bags").exists()


def test_sim_settings_that_leave_the_agents_input_alone_are_accepted(tmp_path: Path) -> None:
    """The world, its variant, the seed and sensor noise are the test's to choose; the
    agent's own values, given again, are no change; another sensor's settings (the depth
    camera a depth agent beside it needs) do not touch a LiDAR agent's input."""
    env = tmp_path / "env.yaml"
    env.write_text(yaml.safe_dump({"sim": {"ros__parameters": {
        "world_variant": 3, "lidar": {"range_max_m": 10.0, "beams": 360}}}}))
    plan = testplan.TestPlan(agents=(str(TD3_LIDAR),), params_files=(str(env),), sim_overrides={
        "seed": 7, "lidar.noise_std_m": 0.01, "depth.enabled": True, "depth.width": 40})
    spec, = resolve_agents(plan)
    sim = spec.run.env.sim_params
    assert (sim["world_variant"], sim["seed"], sim["lidar.noise_std_m"]) == (3, 7, 0.01)
    assert (sim["lidar.range_max_m"], sim["depth.width"]) == (10.0, 40)


def test_the_input_shaping_sim_keys_are_sim_parameters() -> None:
    from pic4rl_agents.testing.plan import AGENT_SIM_KEYS
    from pic4rl_sim.config import parameter_table
    from pic4rl_sim.engine.robot_specs import load_robot

    names = {spec.name for spec in parameter_table(load_robot("jackal"))}
    assert set(AGENT_SIM_KEYS) <= names
    assert not {"world", "world_variant", "seed", "lidar.noise_std_m"} & set(AGENT_SIM_KEYS)


def test_an_agents_saved_record_settings_are_not_the_tests() -> None:
    """td3_lidar's config lists the topics recorded when it was trained (no people, no tf): a
    test records what the test asks, so a crowd's people reach the agent's bags too."""
    saved = yaml.safe_load((TD3_LIDAR / "config.yaml").read_text())["nav_env"]["ros__parameters"]
    assert "people" not in saved["record.topics"]
    plan = testplan.TestPlan(agents=(str(TD3_LIDAR),), baselines=("dwa",),
                             params_files=(str(ROOT / "config" / "env_crowd.yaml"),))
    specs = resolve_agents(plan)
    assert [s.name for s in specs] == ["td3_lidar", "dwa"]
    for spec in specs:
        assert {"people", "tf", "tf_static", "scan"} <= set(spec.run.env.record.topics), spec.name
