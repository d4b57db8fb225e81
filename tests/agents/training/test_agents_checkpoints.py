"""Checkpoints that a kill cannot break: every file a run writes is whole or absent, a resume
takes the newest checkpoint that loads and says which it skipped and why, a run with none that
loads is one line and exit 2 (nothing written), and a ``pic4rl-train`` killed at any moment,
in the middle of a write included, leaves a run that resumes."""

from __future__ import annotations

import contextlib
import io
import os
import random
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
import yaml
from agents_helpers import LIDAR_TD3, ROOT, SHORT_EPISODES, TINY, TRAINED_STEPS, TrainedRun
from stable_baselines3.common.save_util import load_from_pkl

from pic4rl_agents.models.algorithms import load_model
from pic4rl_agents.runs.rundir import find_resume
from pic4rl_agents.training import train
from pic4rl_base.atomic import replacing
from pic4rl_bridge.errors import ConfigError

VICTIM = Path(__file__).with_name("checkpoint_victim.py")
KILL_INTERVAL = 40  # steps between the checkpoints of the killed runs


def run_main(argv: list[str]) -> tuple[int, str]:
    err = io.StringIO()
    with contextlib.redirect_stderr(err):
        code = train.main(argv)
    return code, err.getvalue()


def truncate(path: Path) -> None:
    """Keep the first half of ``path``'s bytes, as a write cut short does."""
    data = path.read_bytes()
    path.write_bytes(data[: len(data) // 2])


def files(run: Path) -> dict[str, bytes]:
    return {str(p.relative_to(run)): p.read_bytes() for p in sorted(run.rglob("*"))
            if p.is_file()}


# --- whole or not at all --------------------------------------------------------------------------


def test_a_write_that_fails_leaves_the_previous_file_and_no_temporary_one(tmp_path: Path) -> None:
    target = tmp_path / "model.zip"
    target.write_bytes(b"previous")
    with pytest.raises(RuntimeError, match="disk full"):
        with replacing(target) as tmp:
            assert tmp.parent == tmp_path and tmp.suffix == ".zip" and tmp.name.startswith(".")
            tmp.write_bytes(b"half")
            raise RuntimeError("disk full")
    assert list(tmp_path.iterdir()) == [target] and target.read_bytes() == b"previous"


def test_a_model_and_its_buffer_are_saved_whole_with_sb3_suffixes(trained_run: TrainedRun,
                                                                  tmp_path: Path) -> None:
    model = load_model(trained_run.run_dir / "model.zip", "td3")
    model.save(tmp_path / "m")  # SB3 appends .zip, and .pkl to the buffer
    model.save_replay_buffer(tmp_path / "b")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["b.pkl", "m.zip"]
    assert load_model(tmp_path / "m.zip", "td3").num_timesteps == TRAINED_STEPS
    umask = os.umask(0)
    os.umask(umask)
    assert (tmp_path / "m.zip").stat().st_mode & 0o777 == 0o666 & ~umask  # not mkstemp's 0600


# --- which checkpoint a resume takes --------------------------------------------------------------


@pytest.mark.parametrize(("broken", "chosen", "skipped"), [
    (["model.zip"], "checkpoints/model_300_steps.zip",
     ["model.zip: the model does not load (ValueError: "]),
    (["model.zip", "checkpoints/model_300_steps.zip"], "checkpoints/model_200_steps.zip",
     ["model.zip: the model does not load (",
      "checkpoints/model_300_steps.zip: the model does not load (ValueError: "]),
    (["replay_buffer.pkl", "checkpoints/model_replay_buffer_300_steps.pkl"],
     "checkpoints/model_200_steps.zip",
     ["model.zip: its replay buffer replay_buffer.pkl does not load (UnpicklingError: pickle "
      "data was truncated)",
      "checkpoints/model_300_steps.zip: its replay buffer model_replay_buffer_300_steps.pkl "
      "does not load"]),
])
def test_resume_takes_the_newest_checkpoint_that_loads(
        trained_run: TrainedRun, tmp_path: Path, broken: list[str], chosen: str,
        skipped: list[str]) -> None:
    run = trained_run.copy_to(tmp_path)  # model.zip (the newest) and checkpoints 100-300
    for name in broken:
        truncate(run / name)
    found = find_resume(run)
    steps = chosen.split("_")[1]
    assert found.model == run / chosen
    assert found.replay_buffer == run / "checkpoints" / f"model_replay_buffer_{steps}_steps.pkl"
    assert len(found.skipped) == len(skipped)
    for line, start in zip(found.skipped, skipped):
        assert line.startswith(start) and "\n" not in line and str(run) not in line


def test_a_resume_says_which_checkpoint_it_loaded_and_which_it_skipped(
        trained_run: TrainedRun, tmp_path: Path) -> None:
    run = trained_run.copy_to(tmp_path)
    truncate(run / "model.zip")
    code, err = run_main(["--resume", str(run), "-n", str(TRAINED_STEPS + 20), "--no-progress"])
    assert code == 0, err
    assert re.search(r"^pic4rl-train: skipped model\.zip: the model does not load "
                     r"\(ValueError: [^\n]+\)$", err, re.MULTILINE), err
    assert ("pic4rl-train: resuming from checkpoints/model_300_steps.zip (300 steps) with its "
            "replay buffer model_replay_buffer_300_steps.pkl\n") in err
    assert load_model(run / "model.zip", "td3").num_timesteps == TRAINED_STEPS + 20
    # the resumed session's files carry its number, as the docs say
    assert (run / "config-2.yaml").is_file() and (run / "summary-2.yaml").is_file()
    assert yaml.safe_load((run / "summary-2.yaml").read_text())["session"] == 1


@pytest.mark.bad_input
@pytest.mark.parametrize("target", ["run", "zip"])
def test_bad_arguments_resume_with_no_checkpoint_that_loads_is_one_line_exit_2(
        trained_run: TrainedRun, tmp_path: Path, target: str) -> None:
    run = trained_run.copy_to(tmp_path)
    for zip_file in [run / "model.zip", *(run / "checkpoints").glob("*.zip")]:
        truncate(zip_file)
    before = files(run)
    path = run if target == "run" else run / "checkpoints" / "model_200_steps.zip"
    code, err = run_main(["--resume", str(path), "-n", "400", "--no-progress"])
    assert code == 2
    expected = (rf"pic4rl-train: --resume {re.escape(str(run))}: none of its 4 checkpoints "
                r"loads \(newest: model\.zip: the model does not load \(ValueError: .+\)\)\n"
                if target == "run" else
                rf"pic4rl-train: --resume {re.escape(str(path))}: the model does not load "
                r"\(ValueError: .+\); give the run directory to resume from its newest "
                r"checkpoint that loads\n")
    assert re.fullmatch(expected, err), err
    assert files(run) == before  # no config-2.yaml, nothing else either


@pytest.mark.bad_input
def test_bad_arguments_a_resume_whose_model_does_not_fit_its_env_is_one_line_and_no_config(
        trained_run: TrainedRun, tmp_path: Path) -> None:
    """The LiDAR checkpoint resumed with 24 observation sectors instead of 36: one line with
    both shapes, the sensors and the configs they came from; no config-2.yaml is left."""
    run = trained_run.copy_to(tmp_path)
    code, err = run_main(["--resume", str(run), "-n", "400", "--no-progress",
                          "--env-kwargs", "lidar.sectors:24"])
    assert code == 2
    *info, line = err.splitlines()
    assert info == ["pic4rl-train: resuming from model.zip (300 steps) with its replay buffer "
                    "replay_buffer.pkl"]
    assert re.fullmatch(
        rf"pic4rl-train: {re.escape(str(run / 'model.zip'))} \(trained with sensor lidar, from "
        rf"{re.escape(str(run / 'config.yaml'))}\) was trained on the observation space "
        r"Box\(40\) in \[\S+, \S+\] but this session's env \(sensor lidar, from "
        rf"{re.escape(str(run / 'config.yaml'))} \+ command line\) gives Box\(28\) in "
        r"\[\S+, \S+\]; use the sensor and settings it was trained with", line), line
    assert not list(run.glob("config-*")) and not list(run.glob("summary-*"))


# --- killed ---------------------------------------------------------------------------------------


def killed_run_args(runs: Path, max_steps: int) -> list[str]:
    """A tiny in-process run with a checkpoint (and its replay buffer) every 40 steps."""
    return ["--hyperparams", *TINY, f"checkpoint.interval_steps:{KILL_INTERVAL}",
            "eval.interval_steps:0", "--env-kwargs", *SHORT_EPISODES, "-n", str(max_steps),
            "--run", "killed", "--no-progress", "--ros-args", "--params-file", str(LIDAR_TD3),
            "-p", f"runs_dir:={runs}"]


def assert_every_checkpoint_loads(run: Path) -> None:
    """What a kill may leave: whole files, and hidden temporary ones no glob of a run sees."""
    for model in [*run.glob("model.zip"), *(run / "checkpoints").glob("model_*_steps.zip")]:
        assert load_model(model, "td3").num_timesteps > 0, model
    for buffer in [*run.glob("[!.]*.pkl"), *(run / "checkpoints").glob("[!.]*.pkl")]:
        assert load_from_pkl(buffer).size() > 0, buffer


def resume_after_kill(run: Path, steps: int) -> str:
    """Resume the killed run in process up to ``steps``; what it printed."""
    code, err = run_main(["--resume", str(run), "-n", str(steps), "--no-progress"])
    assert code == 0, err
    assert load_model(run / "model.zip", "td3").num_timesteps == steps
    assert not list(run.rglob(".*.tmp*"))  # the killed writer's temporary file is gone
    # session 0 never wrote a summary; the resumed one's is summary-2.yaml, beside config-2
    assert (run / "config-2.yaml").is_file() and (run / "summary-2.yaml").is_file()
    assert not (run / "summary.yaml").exists()
    return err


@pytest.mark.slow
@pytest.mark.parametrize("what", ["pkl", "zip"])
def test_a_kill_in_the_middle_of_a_checkpoint_write_leaves_a_run_that_resumes(
        tmp_path: Path, what: str) -> None:
    """The second checkpoint's replay buffer (``pkl``) or model (``zip``) is half written when
    the process is SIGKILLed: the half file is a hidden temporary one, the first checkpoint is
    whole, and the run resumes from it."""
    runs = tmp_path / "runs"
    proc = subprocess.run([sys.executable, str(VICTIM), what, *killed_run_args(runs, 400)],
                          cwd=ROOT, capture_output=True, text=True, timeout=300,
                          env={**os.environ, "PYTHONPATH": str(ROOT)})
    assert proc.returncode == -signal.SIGKILL, proc.stderr
    run = runs / "killed"
    assert len(list(run.rglob(".*.tmp*"))) == 1  # the write the kill cut short
    assert_every_checkpoint_loads(run)
    first = f"checkpoints/model_{KILL_INTERVAL}_steps.zip"
    assert find_resume(run).model == run / first
    err = resume_after_kill(run, 3 * KILL_INTERVAL)
    assert f"resuming from {first} ({KILL_INTERVAL} steps) with its replay buffer" in err
    assert re.search(r"removed \S+\.tmp\.(pkl|zip), a file a killed session left half-written",
                     err), err


@pytest.mark.slow
def test_a_kill_at_any_moment_leaves_a_run_that_resumes(tmp_path: Path) -> None:
    """``python -m pic4rl_agents.training.train`` SIGKILLed at a random moment after its first
    checkpoint, while it writes one every 40 steps: every checkpoint left loads, and the run
    resumes from the newest."""
    runs = tmp_path / "runs"
    log = (tmp_path / "train.log").open("wb")
    proc = subprocess.Popen([sys.executable, "-m", "pic4rl_agents.training.train",
                             *killed_run_args(runs, 1_000_000)],
                            cwd=ROOT, stdout=log, stderr=subprocess.STDOUT,
                            start_new_session=True, env={**os.environ, "PYTHONPATH": str(ROOT)})
    run = runs / "killed"
    try:
        deadline = time.monotonic() + 120
        while not (run / "checkpoints" / f"model_{KILL_INTERVAL}_steps.zip").exists():
            assert proc.poll() is None, (tmp_path / "train.log").read_text()
            assert time.monotonic() < deadline, "no checkpoint after 120 s"
            time.sleep(0.05)
        time.sleep(random.uniform(0.0, 2.0))
    finally:
        os.killpg(proc.pid, signal.SIGKILL)
        proc.wait()
        log.close()
    assert_every_checkpoint_loads(run)
    found = find_resume(run)
    assert found.skipped == () and found.replay_buffer is not None
    newest = max(int(p.name.split("_")[1]) for p in (run / "checkpoints").glob("model_*.zip"))
    assert found.model.name == f"model_{newest}_steps.zip"
    err = resume_after_kill(run, newest + KILL_INTERVAL)
    assert f"resuming from checkpoints/model_{newest}_steps.zip ({newest} steps)" in err


def test_find_resume_refuses_a_zip_that_is_no_model(tmp_path: Path) -> None:
    (tmp_path / "model.zip").write_bytes(b"")
    with pytest.raises(ConfigError, match=r"--resume .*model\.zip: the model does not load"):
        find_resume(tmp_path / "model.zip")
