"""``pic4rl-test`` in process: a trained agent and the proportional baseline drive the same
recorded episodes (the default indoor pairs, or ``--random N`` pairs from the simulator),
every bag is judged by ``pic4rl_metrics``, and the table has a row per agent; a taken run
name gets a suffix, claimed atomically; a model tested with another sensor or a missing agent
exits 2, leaving no run folder. The
default test pairs are free space in the indoor world."""

from __future__ import annotations

import contextlib
import io
import json
import math
import re
import threading
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import yaml
from agents_helpers import CONFIG, LIDAR_TD3, TrainedRun

from pic4rl_agents.runs.config import load_run_config
from pic4rl_agents.launch.rosargs import split_ros_args
from pic4rl_agents.testing import tester
from pic4rl_agents.testing.plan import DEFAULT_PAIRS, AgentSpec, resolve_agents
from pic4rl_base.atomic import claim_dir
from pic4rl_bridge.config import load_env_config
from pic4rl_metrics.tables.aggregate import aggregate
from pic4rl_metrics.tables.batch import MetricsResult, compute
from pic4rl_sim.engine.core import EngineConfig
from pic4rl_sim.engine.robot_specs import JACKAL
from pic4rl_sim.engine.sampling import check_free
from pic4rl_sim.engine.worlds.generators import make_world

SHORT = ["--env-kwargs", "episode_max_steps:100", "--no-progress"]
PAIRS = json.loads(DEFAULT_PAIRS.read_text())


def run_main(argv: list[str]) -> tuple[int, str, str]:
    """``tester.main(argv)``, its stdout and its stderr."""
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = tester.main(argv)
    return code, out.getvalue(), err.getvalue()


def episode_dirs(agent_dir: Path) -> list[str]:
    return sorted(p.name for p in agent_dir.iterdir() if p.is_dir())


def pairs_by_agent(result: MetricsResult) -> dict[str, list[tuple[tuple[float, ...], ...]]]:
    """Each agent's (start x, y) and goal per episode, in episode order, from the bags' facts."""
    out: dict[str, list[tuple[str, tuple[float, ...], tuple[float, ...]]]] = {}
    for episode in result.episodes:
        facts = episode.facts
        assert facts.start is not None and facts.goal is not None, episode.bag
        out.setdefault(str(facts.agent), []).append(
            (str(facts.episode), tuple(facts.start[:2]), tuple(facts.goal)))
    return {agent: [(start, goal) for _, start, goal in sorted(rows)]
            for agent, rows in out.items()}


def test_an_agent_and_the_baseline_drive_the_same_recorded_episodes(
        trained_run: TrainedRun, tmp_path: Path) -> None:
    assert trained_run.code == 0, trained_run.stderr
    agent = trained_run.run_dir.name
    bags = tmp_path / "bags"
    code, out, err = run_main(["--agent", str(trained_run.run_dir), "--baseline", "proportional",
                               "--episodes", "2", "--bags", str(bags), "--run", "cmp", *SHORT])
    assert code == 0, err
    run_dir = bags / "cmp"
    assert f"bags: {run_dir}" in err
    for name in (agent, "proportional"):
        assert episode_dirs(run_dir / name) == ["episode_0000", "episode_0001"]
        for episode in ("episode_0000", "episode_0001"):
            bag = run_dir / name / episode
            assert (bag / "metadata.yaml").is_file()
            assert [p.name for p in bag.glob("*.db3")] == [f"{episode}.db3"]
        assert (run_dir / name / "config.yaml").is_file()
        assert re.search(rf"^{name}: [0-2]/2 goals$", err, re.MULTILINE), err

    result = compute([run_dir])
    assert len(result.results) == 4 and not result.failed
    table = aggregate(result.frame, by="agent")
    assert sorted(table.index) == sorted([agent, "proportional"])
    for name in table.index:
        assert re.fullmatch(r"[0-2]/2", table.loc[name, "success"])
        assert table.loc[name, "n_episodes"] == 2 and table.loc[name, "n_failed"] == 0
    assert "success" in out and agent in out and "proportional" in out  # the printed table

    episodes_csv = pd.read_csv(run_dir / "episodes.csv")
    assert len(episodes_csv) == 4 and set(episodes_csv["agent"]) == {agent, "proportional"}
    table_md = (run_dir / "table.md").read_text()
    assert table_md.startswith("| agent |")
    assert f"| {agent} |" in table_md and "| proportional |" in table_md

    pairs = pairs_by_agent(result)
    assert pairs[agent] == pairs["proportional"]  # the same start-goal pairs
    recorded = load_env_config(run_dir / agent / "config.yaml").episodes
    assert recorded.file == str(DEFAULT_PAIRS)  # not the training pairs of the agent's config
    assert recorded.ordered and recorded.starting_episodes == 0
    expected = [(tuple(p[:2]), tuple(g)) for p, g in zip(PAIRS["poses"][:2], PAIRS["goals"][:2])]
    for got, want in zip(pairs[agent], expected):  # the default test pairs, in order
        np.testing.assert_allclose(np.concatenate(got), np.concatenate(want), atol=1e-6)
    assert {str(e.facts.outcome.value) for e in result.episodes} <= {
        "goal", "collision", "timeout"}


def test_a_taken_run_name_gets_a_suffix_and_random_runs_n_simulator_pairs(
        trained_run: TrainedRun, tmp_path: Path) -> None:
    bags = tmp_path / "bags"
    code, _, err = run_main(["--baseline", "proportional", "--episodes", "1", "--bags",
                             str(bags), "--run", "r", *SHORT,
                             "--ros-args", "--params-file", str(LIDAR_TD3)])
    assert code == 0, err
    assert episode_dirs(bags / "r" / "proportional") == ["episode_0000"]
    first = {p: p.read_bytes() for p in (bags / "r").rglob("*") if p.is_file()}

    code, _, err = run_main(["--agent", f"mine={trained_run.run_dir}", "--baseline",
                             "proportional", "--random", "3", "--bags", str(bags), "--run", "r",
                             *SHORT])
    assert code == 0, err
    assert {p: p.read_bytes() for p in (bags / "r").rglob("*") if p.is_file()} == first
    for name in ("mine", "proportional"):  # NAME=PATH names the agent
        assert episode_dirs(bags / "r-2" / name) == [f"episode_000{i}" for i in range(3)]
    result = compute([bags / "r-2"])
    assert len(result.results) == 6 and not result.failed
    pairs = pairs_by_agent(result)
    assert pairs["mine"] == pairs["proportional"]
    goals = [goal for _, goal in pairs["mine"]]
    assert len(set(goals)) == 3  # three different pairs
    for goal in goals:  # drawn by the simulator, not the file's
        assert all(math.dist(goal, g) > 1e-3 for g in PAIRS["goals"])


def test_a_model_tested_with_another_sensor_exits_2(trained_run: TrainedRun,
                                                    tmp_path: Path) -> None:
    """The LiDAR model in a depth env (depth camera on in the sim): refused before it drives,
    in one line naming the sensors it was trained with and the file that says so."""
    code, out, err = run_main(["--agent", str(trained_run.run_dir), "--episodes", "1", "--bags",
                               str(tmp_path), "--run", "w", "--no-progress",
                               "--env-kwargs", "sensor:depth",
                               "--sim-kwargs", "depth.enabled:true"])
    assert code == 2
    (line,) = err.splitlines()
    run = trained_run.run_dir
    assert line == (f"pic4rl-test: --agent {run}: sensors: the test env gives ['depth'] but the "
                    f"agent was trained with ['lidar'] ({run / 'config.yaml'}); a test env must "
                    "not change what an agent observes or how it acts: remove sensors there or "
                    "set it to ['lidar']"), line
    assert out == ""
    assert not (tmp_path / "w").exists()  # a refused agent leaves no run folder behind


def test_runs_claiming_one_name_at_once_each_get_their_own_folder(tmp_path: Path) -> None:
    """``atomic.claim_dir``, as ``pic4rl-test --run`` and ``pic4rl-train`` claim theirs:
    16 threads released together each create a folder of their own."""
    start = threading.Barrier(16)

    def claim(_: int) -> Path:
        start.wait()
        return claim_dir(tmp_path / "bags" / "r")

    with ThreadPoolExecutor(16) as pool:
        claimed = list(pool.map(claim, range(16)))
    assert sorted(p.name for p in claimed) == sorted(["r"] + [f"r-{n}" for n in range(2, 17)])


@pytest.mark.bad_input
@pytest.mark.parametrize(("argv", "message"), [
    (["--agent", "{tmp}/nope"], "--agent {tmp}/nope: no such model"),
    (["--agent", "{tmp}"], "--agent {tmp}: no model.zip in it"),
    (["--baseline", "proportional"], "no env to run it in"),
    ([], "nothing to test"),
    (["--baseline", "proportional", "--episodes", "0"], "expected a positive number"),
    (["--baseline", "proportional", "--env-kwargs", "sensr:depth", "--ros-args",
      "--params-file", str(LIDAR_TD3)], "did you mean 'sensor'"),
    (["--baseline", "proportional", "--ros-args", "--params-file",
      str(CONFIG / "env_person_omni.yaml")],
     "--baseline proportional: it drives goToPose; this env's task is 'personMonitoring'. "
     "Test it with --baseline dwa_heading"),
    (["--baseline", "dwa_heading", "--ros-args", "--params-file", str(LIDAR_TD3)],
     "--baseline dwa_heading: it drives personMonitoring; this env's task is 'goToPose'"),
    (["--baseline", "planner", "--ros-args", "--params-file",
      str(CONFIG / "env_vineyard_depth.yaml")],
     "this env's task is 'vineyard'. Test it with --baseline centerline or row_follower"),
])
def test_bad_arguments_exit_2(tmp_path: Path, argv: list[str], message: str) -> None:
    argv = [a.replace("{tmp}", str(tmp_path)) for a in argv]
    code, out, err = run_main(["--bags", str(tmp_path / "bags"), "--no-progress", *argv])
    assert code == 2
    assert err.startswith("pic4rl-test: ") and message.replace("{tmp}", str(tmp_path)) in err
    assert not (tmp_path / "bags").exists()


@pytest.mark.bad_input
@pytest.mark.parametrize(("argv", "line"), [
    (["--episodes", "-5"], "--episodes -5: expected a positive number of episodes"),
    (["--random", "0"], "--random 0: expected a positive number of episodes"),
    (["--ros-args", "-p", "episode_max_steps:=abc"],
     "-p parameters: episode_max_steps: 'abc' is invalid; expected an integer"),
    (["--ros-args", "-p", "batch_size:=32"], "-p parameters: unknown key 'batch_size'; "),
    (["--env-kwargs", "lidar.sectors:abc"],
     "--env-kwargs: lidar.sectors: 'abc' is invalid; expected an integer"),
    (["--env-kwargs", "lidar.beams:24"], "--env-kwargs: key 'lidar.beams' is renamed "
                                         "'lidar.sectors'"),
    (["--ros-args", "-p", "depth.max_depth_m:=4.0"],
     "-p parameters: key 'depth.max_depth_m' is renamed 'depth.clip_m'"),
    (["--ros-args", "-p", "baselines.dwa.horizon_s:=-1.0"],
     "-p parameters: baselines.dwa.horizon_s: -1.0 is invalid; expected a positive number"),
    (["--sim-kwargs", "lidar.beems:36"],
     "--sim-kwargs: unknown key 'lidar.beems'; did you mean 'lidar.beams'?"),
])
def test_bad_arguments_name_the_flag_not_the_params_file(tmp_path: Path, argv: list[str],
                                                         line: str) -> None:
    """A bad command-line value is one line naming the flag it came from, not the params
    file; no bag is written."""
    code, out, err = run_main(["--baseline", "proportional", "--bags", str(tmp_path / "bags"),
                               "--no-progress", *argv, "--ros-args", "--params-file",
                               str(LIDAR_TD3)])
    assert code == 2 and out == ""
    assert err.startswith(f"pic4rl-test: {line}") and err.count("\n") == 1
    assert str(LIDAR_TD3) not in err
    assert not (tmp_path / "bags").exists()


# --- which episodes ------------------------------------------------------------------------------


def resolve(argv: list[str]) -> list[AgentSpec]:
    """The agents ``pic4rl-test ARGV`` would drive, with their test envs, driving nothing."""
    plain, ros = split_ros_args(argv)
    plan = tester.build_plan(tester.build_parser().parse_args(plain), ros)
    return resolve_agents(plan, plan.bags_dir / "r")


def test_baseline_settings_come_from_the_baselines_section_and_p(tmp_path: Path) -> None:
    """``-p baselines.*`` and a params file's ``baselines:`` section reach the DWA baseline;
    the env's parameters stay the env's."""
    data = yaml.safe_load(LIDAR_TD3.read_text())
    data["baselines"] = {"ros__parameters": {"dwa.horizon_s": 2.0, "dwa.linear_samples": 5}}
    path = tmp_path / "with_baselines.yaml"
    path.write_text(yaml.safe_dump(data))
    (spec,) = resolve(["--baseline", "dwa", "--bags", str(tmp_path), "--ros-args",
                       "--params-file", str(path), "-p", "baselines.dwa.linear_samples:=9",
                       "-p", "goal_tolerance_m:=0.3"])
    assert spec.settings is not None
    assert (spec.settings.dwa.horizon_s, spec.settings.dwa.linear_samples) == (2.0, 9)
    assert spec.run.env.goal_tolerance_m == 0.3


@pytest.fixture
def no_pairs_config(tmp_path: Path) -> Path:
    """config/train_goto_lidar_td3.yaml without its training pairs (no ``episodes:``)."""
    data = yaml.safe_load(LIDAR_TD3.read_text())
    del data["nav_env"]["ros__parameters"]["episodes"]
    path = tmp_path / "no_pairs.yaml"
    path.write_text(yaml.safe_dump(data))
    return path


def test_the_indoor_world_gets_the_default_test_pairs_in_order(no_pairs_config: Path,
                                                               tmp_path: Path) -> None:
    (spec,) = resolve(["--baseline", "proportional", "--bags", str(tmp_path),
                       "--ros-args", "--params-file", str(no_pairs_config)])
    episodes = spec.run.env.episodes
    assert episodes.file == str(DEFAULT_PAIRS) and episodes.ordered
    assert episodes.change_goal_and_pose == 1 and episodes.starting_episodes == 0
    record = spec.run.env.record
    assert record.enabled and record.bags_dir == str(tmp_path / "r")
    assert record.run == spec.run.env.agent == "proportional"


def test_random_pairs_and_other_worlds_use_the_simulator(no_pairs_config: Path) -> None:
    (spec,) = resolve(["--baseline", "proportional", "--random", "3",
                       "--ros-args", "--params-file", str(LIDAR_TD3)])
    assert spec.run.env.episodes.file == "" and not spec.run.env.episodes.ordered
    for sim in ("world:obstacles", "world_variant:1"):  # the indoor pairs mean nothing there
        (spec,) = resolve(["--baseline", "proportional", "--sim-kwargs", sim,
                           "--ros-args", "--params-file", str(no_pairs_config)])
        assert spec.run.env.episodes.file == "", sim


def test_a_test_pairs_file_given_to_the_tester_wins(trained_run: TrainedRun,
                                                    tmp_path: Path) -> None:
    pairs = tmp_path / "pairs.json"
    pairs.write_text(json.dumps({"goals": [[1.0, 1.0]], "poses": [[0.0, 0.0, 0.0]]}))
    specs = resolve(["--agent", str(trained_run.run_dir), "--baseline", "proportional",
                     "--env-kwargs", f"episodes.file:{pairs}"])
    assert [s.run.env.episodes.file for s in specs] == [str(pairs)] * 2
    assert all(s.run.env.episodes.ordered for s in specs)
    params = tmp_path / "test_pairs.yaml"
    params.write_text(yaml.safe_dump({"nav_env": {"ros__parameters": {
        "episodes": {"file": str(pairs)}}}}))
    specs = resolve(["--agent", str(trained_run.run_dir), "--ros-args", "--params-file",
                     str(params)])
    assert specs[0].run.env.episodes.file == str(pairs)


def test_an_agent_trained_on_a_pairs_file_is_tested_on_the_test_pairs(
        trained_run: TrainedRun) -> None:
    assert load_run_config([trained_run.run_dir / "config.yaml"]).env.episodes.file
    specs = resolve(["--agent", str(trained_run.run_dir), "--baseline", "proportional"])
    assert [s.run.env.episodes.file for s in specs] == [str(DEFAULT_PAIRS)] * 2


def test_the_default_test_pairs_are_free_for_the_jackal_in_the_indoor_world() -> None:
    """pic4rl_agents/data/goals_indoor_test.json in world ``indoor`` variant 0 (the training
    files' world): each start and goal inside the bounds with the clearance the simulator wants
    around a sampled start (the Jackal's bounding radius plus its margin), 4 to 8 m apart."""
    world = make_world("indoor", seed=0)
    clearance = JACKAL.footprint.bounding_radius_m + EngineConfig().clearance_m
    assert len(PAIRS["goals"]) == len(PAIRS["poses"]) == 5
    for goal, pose in zip(PAIRS["goals"], PAIRS["poses"]):
        check_free(world, pose[:2], clearance_m=clearance, what="start")
        check_free(world, goal, clearance_m=clearance, what="goal")
        assert 4.0 <= math.dist(goal, pose[:2]) <= 8.0
    with pytest.raises(Exception, match="from the nearest obstacle"):  # the check can fail
        check_free(world, (-6.0 + 0.1, 0.0), clearance_m=clearance, what="start")
