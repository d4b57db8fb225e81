"""``pic4rl-run`` for real: the launcher starts ``pic4rl-sim`` processes and the trainer or
tester, which talk ROS 2 on the test's own DDS domain. Each algorithm trains a few hundred
steps through ROS; two envs train against two sims (``env_0``, ``env_1``); the tester records
bags the metrics judge; Ctrl-C to the launcher saves the model; a trainer with no sim to talk
to exits 2 saying how to start one. After every launcher exits, no sim it started is left
running (each sim carries the test's tag in its environment, so the test finds them in /proc
even though they run in sessions of their own).
"""

from __future__ import annotations

import math
import os
import signal
import subprocess
import sys
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path

import pytest
import yaml
from agents_helpers import (
    LIDAR_TD3,
    ROS_ARGS,
    SIM,
    TINY,
    TRAINER,
    Launcher,
    processes_with,
)
from ros_helpers import SimProcess, next_domain, sim_command, sim_env

from pic4rl_agents.training import train
from pic4rl_agents.models.algorithms import ALGORITHMS, load_model
from pic4rl_metrics.tables.aggregate import aggregate
from pic4rl_metrics.tables.batch import compute

pytestmark = pytest.mark.integration

def train_args(runs: Path, algorithm: str, *extra: str, steps: int = 200) -> list[str]:
    hyper = [*TINY, f"algorithm:{algorithm}", "checkpoint.interval_steps:0",
             "eval.interval_steps:0"]
    if algorithm == "ppo":
        hyper += ["epsilon.initial:0.0", "ppo.n_steps:64", "ppo.n_epochs:2"]
    return ["train", "--hyperparams", *hyper, "--env-kwargs", "episode_max_steps:60",
            "-n", str(steps), "--run", algorithm, "--no-progress", *extra,
            "--ros-args", "--params-file", str(LIDAR_TD3), "-p", f"runs_dir:={runs}",
            *ROS_ARGS]


@dataclass(frozen=True)
class RosRun:
    code: int
    run_dir: Path
    output: str
    sims_left: list[int]


@pytest.fixture(scope="module")
def ros_runs(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Callable[[str], RosRun]]:
    """``pic4rl-run train`` of an algorithm through ROS (tiny nets, 200 steps), once per
    module: the TD3 run is also the agent the tester drives."""
    runs = tmp_path_factory.mktemp("ros_runs")
    done: dict[str, RosRun] = {}
    launchers: list[Launcher] = []

    def get(algorithm: str) -> RosRun:
        if algorithm not in done:
            launcher = Launcher.start(train_args(runs, algorithm), runs / f"{algorithm}.log",
                                      next_domain())
            launchers.append(launcher)
            code = launcher.wait(300)
            done[algorithm] = RosRun(code, runs / algorithm, launcher.output, launcher.left())
        return done[algorithm]

    try:
        yield get
    finally:
        for launcher in launchers:
            launcher.stop(interrupt=False)


@pytest.mark.slow
@pytest.mark.parametrize("algorithm", ["ddpg", "td3", "sac", "ppo"])
def test_each_algorithm_trains_through_ros(ros_runs: Callable[[str], RosRun],
                                           algorithm: str) -> None:
    run = ros_runs(algorithm)
    assert run.code == 0, run.output
    assert run.sims_left == [], run.output
    summary = yaml.safe_load((run.run_dir / "summary.yaml").read_text())
    assert summary["transport"] == "ros" and summary["algorithm"] == algorithm
    assert summary["n_envs"] == 1
    assert summary["total_steps"] >= 200  # PPO rounds up to whole rollouts of 64
    model = load_model(run.run_dir / "model.zip", algorithm)
    assert isinstance(model, ALGORITHMS[algorithm])
    assert model.num_timesteps == summary["total_steps"]
    config = yaml.safe_load((run.run_dir / "config.yaml").read_text())
    assert config["nav_env"]["ros__parameters"]["transport"] == "ros"


@pytest.mark.slow
def test_two_envs_train_against_two_sims(launch: Callable[..., Launcher],
                                         tmp_path: Path) -> None:
    launcher = launch(*train_args(tmp_path / "runs", "td3", "--n-envs", "2"))
    code = launcher.wait(300)
    assert code == 0, launcher.output
    assert launcher.left() == [], launcher.output
    run = tmp_path / "runs" / "td3"
    summary = yaml.safe_load((run / "summary.yaml").read_text())
    assert summary["n_envs"] == 2 and summary["transport"] == "ros"
    assert summary["total_steps"] == 200
    monitors = sorted(p.name for p in (run / "monitor").iterdir())
    assert monitors == ["0_0.monitor.csv", "0_1.monitor.csv"]
    episodes = sum(len(p.read_text().splitlines()) - 2 for p in (run / "monitor").iterdir())
    assert summary["episodes"] == episodes > 0


@pytest.mark.slow
def test_the_tester_records_bags_through_ros(ros_runs: Callable[[str], RosRun],
                                             launch: Callable[..., Launcher],
                                             tmp_path: Path) -> None:
    trained = ros_runs("td3")
    assert trained.code == 0, trained.output
    bags = tmp_path / "bags"
    launcher = launch("test", "--agent", str(trained.run_dir), "--baseline", "proportional",
                      "--episodes", "2", "--bags", str(bags), "--run", "ros", "--no-progress",
                      "--env-kwargs", "episode_max_steps:100", "--ros-args", *ROS_ARGS)
    code = launcher.wait(300)
    assert code == 0, launcher.output
    assert launcher.left() == [], launcher.output
    result = compute([bags / "ros"])
    assert len(result.results) == 4 and not result.failed
    assert "success" in result.frame.columns
    table = aggregate(result.frame, by="agent")
    assert sorted(table.index) == ["proportional", "td3"]
    assert table["n_episodes"].tolist() == [2, 2]
    assert all(s.endswith("/2") for s in table["success"])
    config = yaml.safe_load((bags / "ros" / "td3" / "config.yaml").read_text())
    assert config["nav_env"]["ros__parameters"]["transport"] == "ros"


@pytest.mark.slow
def test_ctrl_c_to_the_launcher_saves_the_model_and_stops_everything(
        launch: Callable[..., Launcher], tmp_path: Path) -> None:
    runs = tmp_path / "runs"
    args = train_args(runs, "td3", steps=1_000_000)
    args[args.index("checkpoint.interval_steps:0")] = "checkpoint.interval_steps:60"
    launcher = launch(*args)
    checkpoint = runs / "td3" / "checkpoints" / "model_60_steps.zip"
    deadline = time.monotonic() + 240
    while not checkpoint.exists():  # training is under way
        assert launcher.proc.poll() is None, launcher.output
        assert time.monotonic() < deadline, f"no checkpoint after 240 s:\n{launcher.output}"
        time.sleep(0.2)
    assert processes_with(launcher.tag, TRAINER) and processes_with(launcher.tag, SIM)
    os.kill(launcher.proc.pid, signal.SIGINT)  # the launcher alone, as a terminal's Ctrl-C
    code = launcher.wait(120)
    assert code == 0, launcher.output
    assert "pic4rl-run: stopping" in launcher.output
    assert "interrupted at" in launcher.output
    assert launcher.left(SIM) == [] and launcher.left(TRAINER) == [], launcher.output
    model = load_model(runs / "td3" / "model.zip", "td3")
    assert 60 <= model.num_timesteps < 1_000_000
    summary = yaml.safe_load((runs / "td3" / "summary.yaml").read_text())
    assert summary["total_steps"] == model.num_timesteps and summary["transport"] == "ros"


# --- no sim ---------------------------------------------------------------------------------------


def train_without_a_sim(tmp_path: Path, capfd: pytest.CaptureFixture[str],
                        *ros_args: str) -> tuple[int, str]:
    """``pic4rl-train`` in process over ROS with nothing answering (1 s timeouts), and its
    stderr (captured at the descriptor: rclpy's executor wants a real stderr)."""
    capfd.readouterr()
    code = train.main(["--hyperparams", *TINY, "checkpoint.interval_steps:0",
                       "eval.interval_steps:0", "-n", "50", "--no-progress",
                       "--ros-args", "--params-file", str(LIDAR_TD3),
                       "-p", "transport:=ros", "-p", "ros.timeout_s:=1.0",
                       "-p", f"runs_dir:={tmp_path}", *ros_args])
    return code, capfd.readouterr().err


def test_training_without_a_sim_exits_2_saying_how_to_start_one(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
        capfd: pytest.CaptureFixture[str]) -> None:
    domain = next_domain()
    monkeypatch.setenv("ROS_DOMAIN_ID", str(domain))
    monkeypatch.setenv("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")
    code, err = train_without_a_sim(tmp_path, capfd)
    assert code == 2
    assert err.startswith("pic4rl-train: ") and "nothing within 1 s" in err
    assert f"Is a sim answering in ROS domain {domain}?" in err
    assert "pic4rl-run train" in err
    assert not list(tmp_path.rglob("model.zip"))  # no model after 0 steps


def test_the_no_sim_hint_names_the_configured_domain(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
        capfd: pytest.CaptureFixture[str]) -> None:
    monkeypatch.setenv("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")
    domain = next_domain()
    code, err = train_without_a_sim(tmp_path, capfd, "-p", f"ros.domain_id:={domain}")
    assert code == 2
    assert f"Is a sim answering in ROS domain {domain}?" in err


# --- a sim killed mid-episode -------------------------------------------------------------------


@pytest.mark.slow
def test_a_sim_killed_mid_episode_leaves_an_aborted_episode_out_of_the_success_rate(
        tmp_path: Path) -> None:
    """The sim runs in real time; it is killed 3 s into the episode under way. The tester stops
    (exit 2), the bag is kept without an outcome, and the metrics judge it ``aborted``: counted
    apart, not a timeout, not in the success rate unless asked."""
    domain = next_domain()
    sim = SimProcess(sim_command("--params-file", str(LIDAR_TD3), "-p", "clock_mode:=realtime"),
                     domain, tmp_path / "sim.log")
    bags = tmp_path / "bags"
    log = (tmp_path / "tester.log").open("wb")
    tester = subprocess.Popen(
        [sys.executable, "-m", "pic4rl_agents.testing.tester", "--baseline", "proportional",
         "--episodes", "2", "--bags", str(bags), "--run", "killed", "--no-progress",
         "--env-kwargs", "episode_max_steps:600", "--ros-args", "--params-file", str(LIDAR_TD3),
         "-p", "transport:=ros", "-p", "ros.timeout_s:=20.0"],
        env=sim_env(domain), stdout=log, stderr=subprocess.STDOUT, start_new_session=True)
    try:
        deadline = time.monotonic() + 120
        while not list(bags.glob("killed/*/*/metadata.yaml")) and not list(
                bags.glob("killed/*/*/*.mcap")) and not list(bags.glob("killed/*/*/*.db3")):
            assert tester.poll() is None, (tmp_path / "tester.log").read_text()
            assert time.monotonic() < deadline, (tmp_path / "tester.log").read_text()
            time.sleep(0.2)
        time.sleep(3.0)
        os.killpg(sim.proc.pid, signal.SIGKILL)
        assert tester.wait(120) == 2
    finally:
        if tester.poll() is None:
            os.killpg(tester.pid, signal.SIGKILL)
        sim.stop()
        log.close()
    output = (tmp_path / "tester.log").read_text()
    assert "closed without an outcome" in output
    result = compute([bags / "killed"])
    assert result.results and not result.failed
    frame = result.frame.sort_values("bag")
    *finished, killed = frame.to_dict("records")  # the killed episode is the last one
    assert killed["outcome"] == "aborted" and math.isnan(killed["success"])
    assert "judged aborted (cut short)" in killed["warnings"]
    assert all(row["outcome"] != "aborted" for row in finished)
    table = aggregate(frame, by="agent").loc["proportional"]
    assert table["n_aborted"] == 1 and table["n_judged"] == len(finished)
    counted = aggregate(frame, by="agent", count_aborted=True).loc["proportional"]
    assert counted["n_judged"] == len(finished) + 1
    assert counted["n_success"] == table["n_success"]
