"""The trainer's evaluation against env steps and the clock: ``eval/<session>/evaluations.csv``
rows at the configured step and time intervals, both clocks consistent with the time spent
evaluating, the same numbers in SB3's logs, the eval env on sampled test-kind pairs (never the
training pairs); and the evaluation curves of several runs in one PNG."""

from __future__ import annotations

import contextlib
import io
from pathlib import Path

import matplotlib
import numpy as np
import pandas as pd
import pytest
from agents_helpers import LIDAR_TD3, PNG_MAGIC, SHORT_EPISODES, TINY

from pic4rl_agents.training import curves

from pic4rl_agents.training import train
from pic4rl_agents.training.callbacks import CSV_COLUMNS, OUTCOME_COLUMNS
from pic4rl_agents.runs.config import EvalConfig, load_run_config
from pic4rl_agents.training.envs import eval_env_config
from pic4rl_bridge.config import EpisodesConfig
from pic4rl_bridge.errors import ConfigError

matplotlib.use("Agg")

STEPS = 300
EVERY_STEPS = 100
EVERY_S = 0.02  # short enough that time-based evaluations fall between the step-based ones
SLACK_S = 1.0  # one env step and its gradient step, on a busy machine


@pytest.fixture(scope="module")
def evaluated(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """300 TD3 steps, evaluated every 100 steps and every 0.02 s of training, 2 episodes each."""
    runs = tmp_path_factory.mktemp("runs")
    err = io.StringIO()
    with contextlib.redirect_stderr(err):
        code = train.main([
            "--hyperparams", *TINY, "tensorboard:true", "eval.episodes:2",
            f"eval.interval_steps:{EVERY_STEPS}", f"eval.interval_s:{EVERY_S}",
            "checkpoint.interval_steps:0", "--env-kwargs", *SHORT_EPISODES,
            "-n", str(STEPS), "--run", "evaluated", "--no-progress",
            "--ros-args", "--params-file", str(LIDAR_TD3), "-p", f"runs_dir:={runs}"])
    assert code == 0, err.getvalue()
    return runs / "evaluated"


def test_every_evaluation_is_a_row_at_the_configured_intervals(evaluated: Path) -> None:
    rows = pd.read_csv(evaluated / "eval" / "0" / "evaluations.csv")
    assert tuple(rows.columns) == CSV_COLUMNS
    steps = rows["steps"].to_numpy()
    assert (np.diff(steps) >= 0).all() and steps[-1] <= STEPS
    assert set(range(EVERY_STEPS, STEPS + 1, EVERY_STEPS)) <= set(steps)  # by steps
    assert len(rows) > STEPS // EVERY_STEPS  # and by time in between
    for column in ("wall_s", "train_wall_s"):
        assert (np.diff(rows[column]) > 0).all(), column
    # No more than interval_s of training passes without an evaluation (the first is
    # interval_s after training starts, whose clock includes building the envs).
    assert np.diff(rows["train_wall_s"]).max() <= EVERY_S + SLACK_S
    # wall_s = train_wall_s + the time spent in the evaluations before this one
    before = np.concatenate([[0.0], np.cumsum(rows["eval_s"])[:-1]])
    rounding = 0.0005 * (np.arange(len(rows)) + 2)  # the CSV's 3 decimals, summed
    assert (np.abs(rows["wall_s"] - rows["train_wall_s"] - before) <= rounding).all(), rows
    assert (rows["episodes"] == 2).all()
    rates = rows[["success_rate", *(f"{o}_rate" for o in OUTCOME_COLUMNS)]]
    np.testing.assert_allclose(rates.sum(axis=1), 1.0)
    assert ((rows["mean_length"] > 0) & (rows["mean_length"] <= 60)).all()


def test_the_logs_hold_the_same_evaluations_and_both_clocks(evaluated: Path) -> None:
    rows = pd.read_csv(evaluated / "eval" / "0" / "evaluations.csv")
    progress = pd.read_csv(evaluated / "logs" / "0" / "progress.csv")
    logged = progress.dropna(subset=["eval/success_rate"])
    assert logged["time/total_timesteps"].tolist() == rows["steps"].tolist()
    np.testing.assert_allclose(logged["time/wall_s"], rows["wall_s"], atol=0.001)
    np.testing.assert_allclose(logged["time/train_wall_s"], rows["train_wall_s"], atol=0.001)
    np.testing.assert_allclose(logged["eval/mean_reward"], rows["mean_reward"], atol=0.001)
    np.testing.assert_allclose(logged["eval/success_rate"], rows["success_rate"])
    assert list((evaluated / "logs" / "0").glob("events.out.tfevents.*"))
    npz = np.load(evaluated / "eval" / "0" / "evaluations.npz")
    assert npz["timesteps"].tolist() == rows["steps"].tolist()


def test_the_eval_env_samples_test_pairs_not_the_training_pairs() -> None:
    run = load_run_config([LIDAR_TD3])
    assert run.env.episodes.file and run.env.episodes.starting_episodes > 0  # the curriculum
    env = eval_env_config(run.env, EvalConfig(pair_kind="paper"))
    assert env.episodes == EpisodesConfig(pair_kind="paper")  # no file, no curriculum
    assert env.transport == "inprocess" and not env.record.enabled
    assert env.reward == run.env.reward and env.episode_max_steps == run.env.episode_max_steps


def test_bad_eval_settings_name_the_key() -> None:
    with pytest.raises(ConfigError, match=r"eval\.interval_s"):
        load_run_config([LIDAR_TD3], train={"eval.interval_s": -1.0})
    with pytest.raises(ConfigError, match=r"eval\.pair_kind"):
        load_run_config([LIDAR_TD3], train={"eval.pair_kind": "easy"})


# -- the curves --------------------------------------------------------------------------------


def write_evaluations(path: Path, steps: list[int], wall_s: list[float],
                      success: list[float]) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    rows = pd.DataFrame({column: 0.0 for column in CSV_COLUMNS}, index=range(len(steps)))
    rows["steps"], rows["wall_s"], rows["train_wall_s"] = steps, wall_s, np.array(wall_s) / 2
    rows["success_rate"] = success
    rows.to_csv(path, index=False)
    return path


def test_eval_curves_of_a_run_a_resumed_run_and_a_file(tmp_path: Path) -> None:
    one = tmp_path / "one"
    write_evaluations(one / "eval" / "0" / "evaluations.csv", [100, 200], [60.0, 120.0],
                      [0.1, 0.5])
    two = tmp_path / "two"
    for session in ("0", "1", "10"):
        write_evaluations(two / "eval" / session / "evaluations.csv", [1], [1.0], [0.0])
    assert list(curves.eval_curves(one)) == ["one"]
    assert list(curves.eval_curves(two)) == [f"two (session {s})" for s in ("0", "1", "10")]
    file = curves.eval_curves(one / "eval" / "0" / "evaluations.csv", "mine")
    assert list(file) == ["mine"] and file["mine"]["steps"].tolist() == [100, 200]
    assert list(curves.eval_curves(one / "eval" / "0" / "evaluations.csv")) == ["one"]
    with pytest.raises(ConfigError, match="no evaluations"):
        curves.eval_curves(tmp_path / "empty")


def test_plot_eval_curves_draws_success_against_minutes_and_steps(tmp_path: Path) -> None:
    import matplotlib.pyplot as plt

    table = pd.read_csv(write_evaluations(tmp_path / "a.csv", [100, 200, 400],
                                          [30.0, 90.0, 180.0], [0.0, 0.25, 0.9]))
    fig, (left, right) = plt.subplots(1, 2)
    curves.plot_eval_curves(left, {"a": table}, x="wall_s")
    curves.plot_eval_curves(right, {"a": table}, x="steps")
    np.testing.assert_allclose(left.lines[0].get_xdata(), [0.5, 1.5, 3.0])  # minutes
    np.testing.assert_allclose(left.lines[0].get_ydata(), [0.0, 25.0, 90.0])  # percent
    np.testing.assert_allclose(right.lines[0].get_xdata(), [100, 200, 400])
    assert left.get_xlabel().startswith("wall-clock") and right.get_xlabel() == "env steps"
    plt.close(fig)


def test_the_cli_writes_one_png_for_several_runs(tmp_path: Path, evaluated: Path,
                                                 capsys: pytest.CaptureFixture[str]) -> None:
    other = write_evaluations(tmp_path / "b" / "evaluations.csv", [150, 300], [0.5, 1.0],
                              [0.0, 0.5])
    out = tmp_path / "curves.png"
    assert curves.main([str(evaluated), f"B={other}", "-o", str(out)]) == 0
    assert out.read_bytes().startswith(PNG_MAGIC) and out.stat().st_size > 10_000
    assert curves.main([str(tmp_path / "nothing"), "-o", str(out)]) == 2
    assert "curves: " in capsys.readouterr().err
    bad = tmp_path / "bad.csv"
    bad.write_text("steps,reward\n1,2\n")
    assert curves.main([str(bad)]) == 2
    assert "not an evaluations.csv" in capsys.readouterr().err
