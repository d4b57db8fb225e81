"""``pic4rl-tune`` with tiny trials in a SQLite study: a trial completes, a trial of "another
machine" joins the same storage, and the median pruner prunes the next trial at its first
evaluation; the summary, the best params file and the samplers."""

from __future__ import annotations

import contextlib
import io
import logging
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import optuna
import pandas as pd
import pytest
import yaml
from agents_helpers import LIDAR_TD3

from pic4rl_agents.tune import search as tune

from pic4rl_agents.tune import space as tune_space
from pic4rl_agents.tune.summary import write_summary
from pic4rl_agents.runs.config import ALGORITHM_NAMES, load_run_config

#: Trials of seconds: tiny nets, 200 steps, 2 evaluations of 1 episode each. Episodes of 30
#: steps (3 s at 0.5 m/s: 1.5 m) never reach a test pair's goal (4-8 m away): success is 0.
TINY_TRIAL = ["--max-steps", "200", "--n-evaluations", "2", "--eval-episodes", "1",
              "--n-startup-trials", "1",
              "--hyperparams", "policy.net_arch:[8]", "policy.critic_arch:[8]",
              "batch_size:16", "learning_starts:50", "buffer_size:2000", "tensorboard:false",
              "--env-kwargs", "episode_max_steps:30"]


def run_tune(argv: list[str]) -> tuple[int, str]:
    out = io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(io.StringIO()):
        code = tune.main(argv)
    return code, out.getvalue()


def test_two_tiny_trials_one_pruned_share_a_sqlite_study(tmp_path: Path) -> None:
    study_dir = tmp_path / "study"
    common = ["--base", str(LIDAR_TD3), "--study-dir", str(study_dir), "--study-name", "tiny",
              "--n-trials", "1", *TINY_TRIAL]
    code, out = run_tune(common)
    assert code == 0, out
    assert "trial 0 complete: success 0.00" in out
    storage = f"sqlite:///{study_dir / 'study.db'}"
    study = optuna.load_study(study_name="tiny", storage=storage)
    assert [t.state for t in study.trials] == [optuna.trial.TrialState.COMPLETE]
    assert study.trials[0].intermediate_values == {1: 0.0, 2: 0.0}

    # Another machine's trial in the same storage: sampled the same way, success 1.0 at both
    # evaluations. Against it the median at evaluation 1 is 0.5, and the next trial's 0 is
    # below it: pruned there (n_startup_trials 1, no warm-up with 2 evaluations).
    base = load_run_config([LIDAR_TD3])
    other = study.ask()
    tune.suggest(other, base, {"learning_rate": 0.00042})
    other.report(1.0, 1)
    other.report(1.0, 2)
    study.tell(other, 1.0)

    code, out = run_tune(common)
    assert code == 0, out
    assert "trial 2 pruned" in out and "best so far: trial 1 (1)" in out
    study = optuna.load_study(study_name="tiny", storage=storage)
    states = [t.state.name for t in study.trials]
    assert states == ["COMPLETE", "COMPLETE", "PRUNED"]
    assert study.trials[2].intermediate_values == {1: 0.0}

    trials = study_dir / "trials"
    first = pd.read_csv(trials / "trial_0" / "eval" / "0" / "evaluations.csv")
    assert first["steps"].tolist() == [100, 200]
    pruned = pd.read_csv(trials / "trial_2" / "eval" / "0" / "evaluations.csv")
    assert pruned["steps"].tolist() == [100]  # stopped at its first evaluation
    config = load_run_config([trials / "trial_2" / "config.yaml"]).train
    assert config.policy.net_arch == (8,) and config.eval.episodes == 1
    assert config.checkpoint.interval_steps == 0 and config.max_steps == 200

    table = pd.read_csv(study_dir / "trials.csv")
    assert table["state"].tolist() == states and "params_learning_rate" in table
    # As each trial used it: fixed (--hyperparams learning_starts:50), or the other's draw.
    used = [50, other.params["learning_starts"], 50]
    assert table["hyperparams.learning_starts"].tolist() == used
    assert table["params_learning_starts"].isna().tolist() == [True, False, True]
    best = yaml.safe_load((study_dir / "best_trial.yaml").read_text())
    assert best["number"] == 1 and best["value"] == 1.0

    # The best params file is a full training config: the base with the best trial's
    # parameters, its own budget and evaluations, loaded as pic4rl-train loads it.
    tuned = load_run_config([study_dir / "best_params.yaml"])
    assert tuned.train.learning_rate == 0.00042 and tuned.name == "tiny_best"
    assert tuned.train.max_steps == base.train.max_steps
    assert tuned.train.eval == base.train.eval  # not the trials' 2 evaluations of 1 episode
    assert tuned.env == load_run_config([LIDAR_TD3], env={"episode_max_steps": 30}).env
    assert tuned.train.action_noise_std == other.params["action_noise_std"]
    assert list(tuned.train.policy.net_arch) == tune_space.NET_ARCHS[other.params["net_arch"]]
    assert (study_dir / "eval_curves.png").is_file()


@pytest.mark.heavy
@pytest.mark.slow
@pytest.mark.ray
def test_trials_run_as_tasks_of_a_ray_cluster_sharing_the_study(tmp_path: Path) -> None:
    """``--address local``: a local Ray of 2 CPUs runs the 2 workers as tasks; both trials
    land in the one SQLite study, each with its own run directory."""
    pytest.importorskip("ray")
    study_dir = tmp_path / "study"
    code, out = run_tune(["--base", str(LIDAR_TD3), "--study-dir", str(study_dir),
                          "--study-name", "ray", "--n-trials", "2", "--n-jobs", "2",
                          "--address", "local", "--pruner", "none", *TINY_TRIAL])
    assert code == 0, out
    study = optuna.load_study(study_name="ray", storage=f"sqlite:///{study_dir / 'study.db'}")
    assert [t.state.name for t in study.trials] == ["COMPLETE", "COMPLETE"]
    assert sorted(p.name for p in (study_dir / "trials").iterdir()) == ["trial_0", "trial_1"]
    assert "2 trials in the study" in out


def test_a_resumed_study_draws_new_parameters(tmp_path: Path) -> None:
    """Two sessions of two trials on one study, as two runs of ``pic4rl-tune --seed 0``: the
    second session's trials draw anew (seeded by their numbers), and what ``--hyperparams``
    fixes is what trials.csv shows."""
    settings = tune.settings_from(tune.build_parser().parse_args([
        "--base", str(LIDAR_TD3), "--study-dir", str(tmp_path), "--study-name", "again",
        "--hyperparams", "learning_starts:200"]))
    drawn = []
    for _ in range(2):
        study = tune.create_study(settings, seed=0)
        for _ in range(2):
            trial = study.ask()
            tune.suggest(trial, settings.base, settings.fixed)
            study.tell(trial, 0.0)
            drawn.append(trial.params)
    assert all(a != b for i, a in enumerate(drawn) for b in drawn[i + 1:]), drawn
    assert all("learning_starts" not in params for params in drawn)
    write_summary(study, settings)
    table = pd.read_csv(tmp_path / "trials.csv")
    assert table["hyperparams.learning_starts"].tolist() == [200] * 4


def test_a_learning_start_beyond_the_trials_budget_is_warned(
        tmp_path: Path, caplog: pytest.LogCaptureFixture) -> None:
    settings = tune.settings_from(tune.build_parser().parse_args([
        "--base", str(LIDAR_TD3), "--study-dir", str(tmp_path), "--max-steps", "2000"]))
    with caplog.at_level(logging.WARNING, logger="pic4rl_agents.tune.settings"):
        settings.trial_run(3, {"algorithm": "td3", "learning_starts": 1000})
        assert not caplog.records
        settings.trial_run(4, {"algorithm": "td3", "learning_starts": 5000})
    assert "trial 4: learning_starts 5000 is not below its budget of 2000 steps" in caplog.text


def test_ctrl_c_ends_the_study_in_one_line_with_exit_130(tmp_path: Path) -> None:
    proc = subprocess.Popen(
        [sys.executable, "-m", "pic4rl_agents.tune.search", "--base", str(LIDAR_TD3), "--study-dir",
         str(tmp_path), "--n-trials", "1", *TINY_TRIAL, "--max-steps", "100000"],
        env={**os.environ, "PYTHONPATH": str(Path(tune.__file__).parents[2])},
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    deadline = time.monotonic() + 120
    # Ctrl-C once the trial trains (its env's monitor written), not while it starts up
    while not any((tmp_path / "trials" / "trial_0").glob("monitor/*.csv")):
        assert time.monotonic() < deadline and proc.poll() is None, proc.communicate()
        time.sleep(0.1)
    proc.send_signal(signal.SIGINT)
    out, err = proc.communicate(timeout=120)
    # 130 from the entry point; twice in loaded CI runs the process instead ended by the signal
    # after writing its line and summary (-SIGINT, which a shell reports as 130 too), a race
    # not reproduced on a quiet machine
    assert proc.returncode in (130, -signal.SIGINT), err
    assert "Traceback" not in out + err and "Trial 0 failed" not in err
    assert err.splitlines()[-1] == f"pic4rl-tune: interrupted; the summary is in {tmp_path}"
    assert (tmp_path / "trials.csv").is_file()


@pytest.mark.parametrize("algorithm", ALGORITHM_NAMES)
def test_every_algorithms_sampler_gives_a_valid_config(algorithm: str) -> None:
    base = load_run_config([LIDAR_TD3], train={"algorithm": algorithm, "epsilon.initial": 0.0})
    study = optuna.create_study(sampler=optuna.samplers.RandomSampler(seed=1))
    for _ in range(20):
        trial = study.ask()
        params = tune.suggest(trial, base, {})
        train = base.train.replace(**params)
        assert train.algorithm == algorithm
        assert trial.user_attrs["hyperparams"] == params
        if not train.off_policy:
            assert train.batch_size <= train.ppo.n_steps * train.n_envs
        else:
            assert 1 <= train.gradient_steps <= train.train_freq


@pytest.mark.bad_input
def test_bad_arguments_exit_2_naming_the_flag(tmp_path: Path,
                                              capsys: pytest.CaptureFixture[str]) -> None:
    assert tune.main(["--base", str(tmp_path / "none.yaml")]) == 2
    assert "--base" in capsys.readouterr().err
    assert tune.main(["--base", str(LIDAR_TD3), "--n-trials", "0"]) == 2
    assert "--n-trials 0" in capsys.readouterr().err
    assert tune.main(["--base", str(LIDAR_TD3), "--study-dir", str(tmp_path),
                      "--hyperparams", "learning_rat:0.1"]) == 2
    assert "learning_rate" in capsys.readouterr().err  # did you mean


@pytest.mark.bad_input
@pytest.mark.parametrize(("argv", "line"), [
    (["--hyperparams", "batch_size:abc"],
     "--hyperparams: batch_size: 'abc' is invalid; expected an integer"),
    (["--env-kwargs", "lidar.sectors:0"],
     "--env-kwargs: lidar.sectors: 0 is invalid; expected a positive number"),
])
def test_bad_arguments_name_the_flag_not_the_base_file(
        tmp_path: Path, capsys: pytest.CaptureFixture[str], argv: list[str], line: str) -> None:
    assert tune.main(["--base", str(LIDAR_TD3), "--study-dir", str(tmp_path / "s"), *argv]) == 2
    assert capsys.readouterr().err == f"pic4rl-tune: {line}\n"
    assert not (tmp_path / "s").exists()
