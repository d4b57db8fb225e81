"""``pic4rl-train`` in process (the in-process transport, tiny nets): what a run writes, a
taken run name, resuming a run where it stopped, picking the checkpoint to resume from, bad
arguments (exit 2, naming the key or file), and Ctrl-C or SIGTERM saving the model."""

from __future__ import annotations

import contextlib
import hashlib
import io
import os
import re
import shutil
import signal
import subprocess
import sys
import threading
import time
import weakref
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import yaml
from agents_helpers import (
    CHECKPOINT_STEPS,
    EVAL_STEPS,
    LIDAR_TD3,
    PNG_MAGIC,
    ROOT,
    SHORT_EPISODES,
    TINY,
    TRAINED_STEPS,
    TrainedRun,
)

from pic4rl_agents.training import train
from pic4rl_agents.models.algorithms import load_model
from pic4rl_agents.training.callbacks import StopWhenSet, stop_on_signal, stopped_by_signal
from pic4rl_agents.runs.config import load_run_config
from pic4rl_agents.models.action_noise import epsilon_at
from pic4rl_agents.runs.rundir import find_resume
from pic4rl_bridge.errors import ConfigError


def run_main(argv: list[str]) -> tuple[int, str]:
    """``train.main(argv)`` and what it printed to stderr."""
    err = io.StringIO()
    with contextlib.redirect_stderr(err):
        code = train.main(argv)
    return code, err.getvalue()


def monitor_rows(run_dir: Path) -> pd.DataFrame:
    """Every row of every monitor CSV of the run (the first line of each is a JSON header)."""
    files = sorted((run_dir / "monitor").glob("*.monitor.csv"))
    return pd.concat([pd.read_csv(f, skiprows=1) for f in files], ignore_index=True)


def buffer_size(model_zip: Path, buffer: Path) -> int:
    """Transitions in ``buffer`` (loaded into the TD3 model of ``model_zip``)."""
    model = load_model(model_zip, "td3")
    model.load_replay_buffer(buffer)
    return int(model.replay_buffer.size())


def digest(run_dir: Path) -> dict[str, str]:
    """Every file under ``run_dir`` and a hash of its bytes."""
    return {str(p.relative_to(run_dir)): hashlib.sha256(p.read_bytes()).hexdigest()
            for p in sorted(run_dir.rglob("*")) if p.is_file()}


# --- one run --------------------------------------------------------------------------------------


def test_a_short_run_writes_every_artifact(trained_run: TrainedRun) -> None:
    assert trained_run.code == 0, trained_run.stderr
    run = trained_run.run_dir
    assert f"pic4rl-train: {TRAINED_STEPS} steps" in trained_run.stderr

    config = load_run_config([run / "config.yaml"])  # a params file again, all three sections
    assert config.train.max_steps == TRAINED_STEPS and config.train.policy.net_arch == (16,)
    assert config.train.checkpoint.interval_steps == CHECKPOINT_STEPS
    assert config.env.episode_max_steps == 60 and config.env.sim_params["world"] == "indoor"
    assert config.train.runs_dir == str(run.parent) and config.name == run.name

    steps = range(CHECKPOINT_STEPS, TRAINED_STEPS + 1, CHECKPOINT_STEPS)
    assert sorted(p.name for p in (run / "checkpoints").iterdir()) == sorted(
        [f"model_{s}_steps.zip" for s in steps]
        + [f"model_replay_buffer_{s}_steps.pkl" for s in steps])
    assert load_model(run / "checkpoints" / "model_100_steps.zip", "td3").num_timesteps == 100
    # SB3 saves a checkpoint before it stores the transition of that step
    assert buffer_size(run / "checkpoints" / "model_200_steps.zip",
                       run / "checkpoints" / "model_replay_buffer_200_steps.pkl") in (199, 200)

    model = load_model(run / "model.zip", "td3")
    assert model.num_timesteps == TRAINED_STEPS
    assert buffer_size(run / "model.zip", run / "replay_buffer.pkl") == TRAINED_STEPS

    png = (run / "reward_curve.png").read_bytes()
    assert png.startswith(PNG_MAGIC) and len(png) > 5000

    summary = yaml.safe_load((run / "summary.yaml").read_text())
    assert summary["total_steps"] == summary["session_steps"] == TRAINED_STEPS
    assert summary["run"] == run.name and summary["algorithm"] == "td3"
    assert summary["transport"] == "inprocess" and summary["sensor"] == "lidar"
    assert summary["session"] == 0 and summary["n_envs"] == 1

    episodes = monitor_rows(run)
    assert [p.name for p in (run / "monitor").iterdir()] == ["0_0.monitor.csv"]
    assert summary["episodes"] == len(episodes) >= TRAINED_STEPS // 60
    assert TRAINED_STEPS - 60 < episodes["l"].sum() <= TRAINED_STEPS  # finished episodes only
    assert set(episodes["outcome"]) <= {"goal", "collision", "timeout"}
    assert (episodes["outcome"] == "timeout").tolist() == (episodes["l"] == 60).tolist()
    assert (episodes["is_success"] == (episodes["outcome"] == "goal")).all()
    assert set(episodes["driver"]) == {"rl"}  # no imitation: every episode is the agent's
    assert summary["episodes_by_driver"]["rl"]["episodes"] == len(episodes)
    if summary["agent_last_100_mean_reward"] is not None:
        assert summary["agent_last_100_mean_reward"] == pytest.approx(episodes["r"].mean(),
                                                                      abs=0.06)
    assert list(summary)[0] == "evaluation" and summary["evaluation"]["steps"] == 2 * EVAL_STEPS

    progress = pd.read_csv(run / "logs" / "0" / "progress.csv")
    assert {EVAL_STEPS, TRAINED_STEPS} <= set(progress["time/total_timesteps"])
    assert list((run / "logs").iterdir()) == [run / "logs" / "0"]
    assert list((run / "logs" / "0").glob("events.out.tfevents.*"))  # tensorboard:true
    evaluations = np.load(run / "eval" / "0" / "evaluations.npz")  # per session
    assert evaluations["timesteps"].tolist() == [EVAL_STEPS, 2 * EVAL_STEPS]
    assert evaluations["results"].shape == (2, 1)  # eval.episodes: 1
    assert (run / "best" / "0" / "best_model.zip").is_file()


def test_a_taken_run_name_gets_a_suffix_and_nothing_is_overwritten(
        trained_run: TrainedRun, tmp_path: Path) -> None:
    first = trained_run.copy_to(tmp_path)
    before = digest(first)
    code, err = run_main(["--hyperparams", *TINY, "checkpoint.interval_steps:0",
                          "eval.interval_steps:0", "--env-kwargs", *SHORT_EPISODES,
                          "-n", "60", "--run", first.name, "--no-progress",
                          "--ros-args", "--params-file", str(LIDAR_TD3),
                          "-p", f"runs_dir:={tmp_path}"])
    assert code == 0, err
    second = tmp_path / f"{first.name}-2"
    assert digest(first) == before
    assert load_model(second / "model.zip", "td3").num_timesteps == 60
    assert yaml.safe_load((second / "summary.yaml").read_text())["run"] == first.name
    assert not (second / "checkpoints").exists()  # checkpoint.interval_steps: 0


# --- resume ---------------------------------------------------------------------------------------


def test_resume_continues_the_run_where_it_stopped(trained_run: TrainedRun,
                                                   tmp_path: Path) -> None:
    """300 steps, then --resume the run directory with -n 500: 200 more steps in a new session
    (logs/1, monitor/1_0, summary-2.yaml, config-2.yaml) with the replay buffer kept, the
    step count and the ε schedule continued, the first session's files untouched."""
    run = trained_run.copy_to(tmp_path)
    session0 = {p: (run / p).read_bytes() for p in (
        "logs/0/progress.csv", "summary.yaml", "config.yaml", "monitor/0_0.monitor.csv",
        "checkpoints/model_300_steps.zip", "eval/0/evaluations.npz")}
    code, err = run_main(["--resume", str(run), "-n", "500", "--no-progress"])
    assert code == 0, err
    assert not list(tmp_path.glob(f"{run.name}-*"))  # the same run, no new directory
    for path, data in session0.items():
        assert (run / path).read_bytes() == data, path

    assert load_model(run / "model.zip", "td3").num_timesteps == 500
    size = buffer_size(run / "model.zip", run / "replay_buffer.pkl")
    assert size == 500 > TRAINED_STEPS  # the 300 transitions of session 0 were kept
    assert {"model_400_steps.zip", "model_500_steps.zip"} <= {
        p.name for p in (run / "checkpoints").iterdir()}

    summary = yaml.safe_load((run / "summary-2.yaml").read_text())
    assert summary["session"] == 1 and summary["total_steps"] == 500
    assert summary["session_steps"] == 500 - TRAINED_STEPS
    assert summary["episodes"] == len(monitor_rows(run))
    assert (run / "monitor" / "1_0.monitor.csv").is_file()
    # the session's 150 steps' evaluation, then the saved model's at its end (500)
    assert np.load(run / "eval" / "1" / "evaluations.npz")["timesteps"].tolist() == [
        TRAINED_STEPS + EVAL_STEPS, 500]
    assert summary["evaluation"]["steps"] == 500
    assert summary["evaluation"]["steps_before_saved"] == 0
    assert load_run_config([run / "config-2.yaml"]).train.max_steps == 500

    progress = pd.read_csv(run / "logs" / "1" / "progress.csv")
    rows = progress.dropna(subset=["rollout/epsilon"])
    assert len(rows) and rows["time/total_timesteps"].min() > TRAINED_STEPS
    for steps, eps in zip(rows["time/total_timesteps"], rows["rollout/epsilon"]):
        since = int(steps) - 50  # learning_starts of the run
        assert epsilon_at(since, 0.2, 0.99995, 0.01) - 1e-12 <= eps
        assert eps <= epsilon_at(since - 1, 0.2, 0.99995, 0.01) + 1e-12


def test_find_resume_picks_the_latest_checkpoint_by_steps(trained_run: TrainedRun,
                                                         tmp_path: Path) -> None:
    run = trained_run.copy_to(tmp_path)
    checkpoints = run / "checkpoints"
    (run / "model.zip").unlink()
    for steps in (1000, 900):
        shutil.copy(checkpoints / "model_100_steps.zip", checkpoints / f"model_{steps}_steps.zip")
        shutil.copy(checkpoints / "model_replay_buffer_100_steps.pkl",
                    checkpoints / f"model_replay_buffer_{steps}_steps.pkl")
    shutil.copy(checkpoints / "model_100_steps.zip", checkpoints / "notes.zip")
    found = find_resume(run)
    assert found.model == checkpoints / "model_1000_steps.zip"  # by number, not by name
    assert found.replay_buffer == checkpoints / "model_replay_buffer_1000_steps.pkl"
    assert found.run_dir == run and found.skipped == ()
    (checkpoints / "model_replay_buffer_1000_steps.pkl").unlink()
    assert find_resume(run).replay_buffer is None


def test_find_resume_prefers_a_final_model_with_more_steps(trained_run: TrainedRun,
                                                          tmp_path: Path) -> None:
    run = trained_run.copy_to(tmp_path)  # model.zip: 300 steps; checkpoints 100 to 300
    (run / "checkpoints" / "model_300_steps.zip").unlink()
    found = find_resume(run)
    assert found.model == run / "model.zip"
    assert found.replay_buffer == run / "replay_buffer.pkl" and found.run_dir == run
    shutil.copy(run / "checkpoints" / "model_200_steps.zip",
                run / "checkpoints" / "model_400_steps.zip")
    assert find_resume(run).model == run / "checkpoints" / "model_400_steps.zip"


def test_find_resume_of_a_checkpoint_zip(trained_run: TrainedRun) -> None:
    run = trained_run.run_dir
    found = find_resume(run / "checkpoints" / "model_200_steps.zip")
    assert found.model == run / "checkpoints" / "model_200_steps.zip"
    assert found.replay_buffer == run / "checkpoints" / "model_replay_buffer_200_steps.pkl"
    assert found.run_dir == run


def test_resuming_a_finished_run_does_nothing(trained_run: TrainedRun, tmp_path: Path) -> None:
    run = trained_run.copy_to(tmp_path)
    before = digest(run)
    code, err = run_main(["--resume", str(run), "-n", str(TRAINED_STEPS), "--no-progress"])
    assert code == 0 and "nothing to do" in err
    assert digest(run) == before


def test_find_resume_of_the_best_model_resumes_its_run(trained_run: TrainedRun) -> None:
    run = trained_run.run_dir
    assert find_resume(run / "best" / "0" / "best_model.zip").run_dir == run


@pytest.mark.parametrize("make", [
    lambda tmp: tmp,  # a directory without a checkpoint
    lambda tmp: tmp / "nope",
    lambda tmp: tmp / "model.pkl",
])
def test_find_resume_without_a_checkpoint_is_an_error(tmp_path: Path, make) -> None:
    path = make(tmp_path)
    if path.suffix == ".pkl":
        path.write_bytes(b"")
    with pytest.raises(ConfigError, match=rf"--resume {re.escape(str(path))}: no "):
        find_resume(path)


def test_a_shipped_training_file_works_from_any_directory(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(tmp_path)
    code, err = run_main(["--hyperparams", *TINY, "checkpoint.interval_steps:0",
                          "eval.interval_steps:0", "-n", "20", "--no-progress",
                          "--ros-args", "--params-file", str(LIDAR_TD3),
                          "-p", f"runs_dir:={tmp_path / 'runs'}"])
    assert code == 0, err


# --- bad arguments --------------------------------------------------------------------------------


@pytest.mark.bad_input
@pytest.mark.parametrize(("argv", "message"), [
    ([], "no --params-file given"),
    (["--ros-args", "--params-file", "/nonexistent/t.yaml"], "/nonexistent/t.yaml"),
    (["--hyperparams", "learning_rat:0.1"], "did you mean 'learning_rate'"),
    (["--hyperparams", "algorithm:foo"], "algorithm: 'foo' is invalid"),
    (["--hyperparams", "oops"], "--hyperparams 'oops': expected key:value"),
    (["--env-kwargs", "sensor:radar"], "sensor: 'radar' is invalid"),
    (["--sim-kwargs", "x"], "--sim-kwargs 'x'"),
    (["--ros-args", "-p", "transprt:=ros", "--"], "did you mean 'transport'"),
    (["--ros-args", "-p"], "-p: expected key:=value"),
    (["--resume", "/nonexistent/run"], "--resume /nonexistent/run"),
    (["-n", "0"], "max_steps: 0 is invalid"),
])
def test_bad_arguments_exit_2_naming_the_key_or_file(
        argv: list[str], message: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(tmp_path)
    if argv and argv[0] != "--ros-args" and message != "no --params-file given":
        argv = [*argv, "--ros-args", "--params-file", str(LIDAR_TD3)]
    if argv and argv[0] == "--ros-args" and "--params-file" not in argv:
        argv = [*argv, "--ros-args", "--params-file", str(LIDAR_TD3)]
    code, err = run_main(argv)
    assert code == 2
    assert err.startswith("pic4rl-train: ") and message in err
    assert list(tmp_path.iterdir()) == []  # nothing written


@pytest.mark.bad_input
@pytest.mark.parametrize(("argv", "line"), [
    (["-n", "-5"], "-n/--max-steps: max_steps: -5 is invalid; expected a positive number"),
    (["--n-envs", "0"], "--n-envs: n_envs: 0 is invalid; expected a positive number"),
    (["--ros-args", "-p", "batch_size:=abc"],
     "-p parameters: batch_size: 'abc' is invalid; expected an integer"),
    (["--ros-args", "-p", "gamma:=0"],
     "-p parameters: gamma: 0 is invalid; expected a value in (0, 1]"),
    (["--hyperparams", "batch_size:abc"],
     "--hyperparams: batch_size: 'abc' is invalid; expected an integer"),
    (["--hyperparams", "learning_rat:0.1"],
     "--hyperparams: unknown key 'learning_rat'; did you mean 'learning_rate'?"),
    (["--env-kwargs", "episode_max_steps:abc"],
     "--env-kwargs: episode_max_steps: 'abc' is invalid; expected an integer"),
    (["--sim-kwargs", "lidar.beems:36"],
     "--sim-kwargs: unknown key 'lidar.beems'; did you mean 'lidar.beams'?"),
    (["--sim-kwargs", "lidar.beams:abc"],
     "--sim-kwargs: lidar.beams: 'abc' is invalid; expected an integer"),
])
def test_bad_arguments_name_the_flag_not_the_params_file(
        argv: list[str], line: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """A bad command-line value is one line naming the flag it came from (and the key), not
    the params file that holds a good one; nothing is written."""
    monkeypatch.chdir(tmp_path)
    code, err = run_main([*argv, "--ros-args", "--params-file", str(LIDAR_TD3)])
    assert code == 2
    assert err == f"pic4rl-train: {line}\n"
    assert list(tmp_path.iterdir()) == []


def test_a_malformed_flag_is_argparse_usage_error(capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as exit_:
        train.main(["-n", "many", "--ros-args", "--params-file", str(LIDAR_TD3)])
    assert exit_.value.code == 2
    assert "-n/--max-steps: invalid int value: 'many'" in capsys.readouterr().err


# --- interrupted ----------------------------------------------------------------------------------


@pytest.mark.parametrize("signum", [signal.SIGTERM, signal.SIGINT])
def test_a_stop_signal_is_an_interrupt_while_training(signum: int) -> None:
    """SIGTERM (``pic4rl-run`` or a scheduler stopping the trainer) and SIGINT raise
    KeyboardInterrupt, which the trainer catches to save, and set its stop flag; the previous
    handler comes back afterwards."""
    previous = signal.getsignal(signum)
    stop = threading.Event()
    with pytest.raises(KeyboardInterrupt):
        with stop_on_signal(stop):
            os.kill(os.getpid(), signum)
            time.sleep(5)  # the handler runs at once; this is never reached in full
    assert stop.is_set()
    assert signal.getsignal(signum) is previous


def test_a_stop_turned_into_another_error_by_an_extension_is_still_the_stop() -> None:
    """A KeyboardInterrupt raised while rclpy deserializes a message leaves pybind11 as a
    TypeError chained from it (seen in CI); with the stop flag set that is the stop, and
    without it, or unchained, it is an error."""
    def raised(stop: threading.Event) -> BaseException:
        try:
            try:
                raise KeyboardInterrupt
            except KeyboardInterrupt as err:
                raise TypeError("Unable to convert function return value") from err
        except TypeError as err:
            return err

    stop = threading.Event()
    assert not stopped_by_signal(raised(stop), stop)
    stop.set()
    assert stopped_by_signal(raised(stop), stop)
    assert stopped_by_signal(KeyboardInterrupt(), threading.Event())
    assert not stopped_by_signal(TypeError("a real bug"), stop)


@pytest.mark.filterwarnings("ignore::pytest.PytestUnraisableExceptionWarning")
def test_a_stop_that_python_drops_still_ends_training() -> None:
    """A signal that lands while a weakref callback runs: Python prints and drops its
    KeyboardInterrupt ("Exception ignored in ..."), but the flag stays set and the first
    callback of training ends ``learn`` at its next step."""
    stop = threading.Event()

    class Owner:
        pass

    def on_collect(_: object) -> None:
        os.kill(os.getpid(), signal.SIGINT)
        time.sleep(0.5)  # the KeyboardInterrupt is raised here, and dropped

    with stop_on_signal(stop):
        owner = Owner()
        ref = weakref.ref(owner, on_collect)
        del owner  # runs on_collect; no exception leaves it
    assert ref() is None and stop.is_set()
    assert StopWhenSet(stop)._on_step() is False
    assert StopWhenSet(threading.Event())._on_step() is True


@pytest.mark.slow
def test_an_interrupted_training_saves_its_model_and_exits_0(tmp_path: Path) -> None:
    """Ctrl-C (SIGINT) to ``python -m pic4rl_agents.training.train`` during training: the model, its
    replay buffer and a summary are saved, and the exit code is 0."""
    log = (tmp_path / "train.log").open("wb")
    proc = subprocess.Popen(
        [sys.executable, "-m", "pic4rl_agents.training.train", "--hyperparams", *TINY,
         "checkpoint.interval_steps:60", "eval.interval_steps:0", "-n", "1000000",
         "--run", "long", "--no-progress", "--ros-args", "--params-file", str(LIDAR_TD3),
         "-p", f"runs_dir:={tmp_path / 'runs'}"],
        cwd=ROOT, stdout=log, stderr=subprocess.STDOUT, start_new_session=True)
    run = tmp_path / "runs" / "long"
    try:
        deadline = time.monotonic() + 120
        while not (run / "checkpoints" / "model_60_steps.zip").exists():  # after the warm-up
            assert proc.poll() is None, (tmp_path / "train.log").read_text()
            assert time.monotonic() < deadline, "no checkpoint after 120 s"
            time.sleep(0.2)
        os.kill(proc.pid, signal.SIGINT)
        code = proc.wait(timeout=60)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()
        log.close()
    output = (tmp_path / "train.log").read_text()
    assert code == 0, output
    assert "interrupted at" in output
    model = load_model(run / "model.zip", "td3")
    assert 60 <= model.num_timesteps < 1_000_000
    stored = min(model.num_timesteps, 5000)  # buffer_size: 5000
    # the signal may land between counting a step and storing its transition
    assert buffer_size(run / "model.zip", run / "replay_buffer.pkl") in (stored - 1, stored)
    summary = yaml.safe_load((run / "summary.yaml").read_text())
    assert summary["total_steps"] == model.num_timesteps
