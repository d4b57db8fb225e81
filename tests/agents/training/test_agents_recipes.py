"""Every training recipe (``config/train_*.yaml``: the shipped ones and any added later) loads
and trains a few hundred steps, in process and through ROS 2 (``pic4rl-run train``: a sim
process per env, at most two, the trainer talking to them over DDS; about 12 s a recipe).

A recipe keeps what makes it one: its algorithm, networks, env (sensor, normalisation,
rewards, pairs), curriculum, reward scale and vector env. Only what costs time shrinks: the
batch, the replay buffer, the warm-up, PPO's rollouts, the episodes (60 steps, so several end)
and the evaluations (one episode every 100 steps, so ``evaluations.csv`` gets rows).
"""

from __future__ import annotations

import contextlib
import io
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pandas as pd
import pytest
import yaml
from agents_helpers import CONFIG, ROS_ARGS, ROS_TIMEOUT_S, SHORT_EPISODES, Launcher

from pic4rl_agents.training import train
from pic4rl_agents.models.algorithms import load_model
from pic4rl_agents.training.callbacks import CSV_COLUMNS
from pic4rl_agents.runs.config import RunConfig, load_run_config
from pic4rl_agents.training.curriculum import STAGE_KEY
from pic4rl_agents.training.curves import episode_table

RECIPES = sorted(CONFIG.glob("train_*.yaml"))
STEPS = 300
EVAL_EVERY = 100
EPISODE_STEPS = int(SHORT_EPISODES[0].split(":")[1])
#: Through ROS every env is a sim process: more than the machine's two cores gain nothing.
ROS_MAX_ENVS = 2


def recipe(path: Path) -> RunConfig:
    return load_run_config([path])


def train_args(path: Path, runs: Path, *, n_envs: int | None = None) -> list[str]:
    """``pic4rl-train`` arguments for a short run of the recipe at ``path`` into ``runs``."""
    hyper = ["batch_size:32", "buffer_size:5000", "learning_starts:50", "eval.episodes:1",
             f"eval.interval_steps:{EVAL_EVERY}", "eval.interval_s:0",
             "checkpoint.interval_steps:0", "tensorboard:false"]
    if recipe(path).train.algorithm == "ppo":
        hyper += ["ppo.n_steps:64", "ppo.n_epochs:2"]
    envs = ["--n-envs", str(n_envs)] if n_envs is not None else []
    return ["--hyperparams", *hyper, "--env-kwargs", *SHORT_EPISODES, "-n", str(STEPS),
            "--run", path.stem, "--no-progress", *envs,
            "--ros-args", "--params-file", str(path), "-p", f"runs_dir:={runs}"]


def check_run(run_dir: Path, path: Path, *, n_envs: int, **env_changes: Any) -> None:
    """The run trained the recipe at ``path`` (its env changed by ``env_changes`` and the
    short episodes alone) for ``STEPS`` steps and logged its episodes and evaluations."""
    shipped, run = recipe(path), load_run_config([run_dir / "config.yaml"])
    assert run.train.algorithm == shipped.train.algorithm
    assert run.train.reward_scale == shipped.train.reward_scale
    assert run.train.curriculum == shipped.train.curriculum
    assert run.train.policy == shipped.train.policy
    assert run.train.vec_env == shipped.train.vec_env and run.train.n_envs == n_envs
    expected = shipped.env.replace(episode_max_steps=EPISODE_STEPS, **env_changes)
    assert run.env == expected

    summary = yaml.safe_load((run_dir / "summary.yaml").read_text())
    assert summary["transport"] == expected.transport and summary["n_envs"] == n_envs
    assert summary["algorithm"] == shipped.train.algorithm
    assert summary["sensor"] == shipped.env.sensor
    model = load_model(run_dir / "model.zip", shipped.train.algorithm)
    assert model.num_timesteps == summary["total_steps"] >= STEPS

    episodes = episode_table(run_dir / "monitor")
    # at least each env's timeouts (an imitation recipe's expert rarely ends one sooner)
    assert summary["episodes"] == len(episodes) >= n_envs * (STEPS // n_envs // EPISODE_STEPS)
    assert episodes["l"].between(1, EPISODE_STEPS).all()
    assert set(episodes["outcome"]) <= {"goal", "collision", "timeout"}
    if shipped.train.curriculum.enabled:  # pairs from the curriculum's first stage
        assert (episodes[STAGE_KEY] == 0).all()
    else:
        assert STAGE_KEY not in episodes.columns

    evaluations = pd.read_csv(run_dir / "eval" / "0" / "evaluations.csv")
    assert tuple(evaluations.columns) == CSV_COLUMNS
    due = max(EVAL_EVERY // n_envs, 1) * n_envs  # env steps between two evaluations
    periodic = [due * (i + 1) for i in range(model.num_timesteps // due)]
    # then the saved model's, when training went on past the last or max_steps cut
    # imitation short (its round's labels fitted after that step's evaluation)
    imitation = shipped.train.imitation
    cut = imitation.enabled and (imitation.bc_steps + imitation.dagger_rounds
                                 * imitation.dagger_steps > model.num_timesteps)
    final = [model.num_timesteps] if model.num_timesteps % due or cut else []
    assert evaluations["steps"].tolist() == periodic + final and len(periodic) >= 1
    assert (evaluations["episodes"] == 1).all()
    assert evaluations["mean_length"].between(1, EPISODE_STEPS).all()
    assert evaluations["wall_s"].is_monotonic_increasing


def test_the_recipes_cover_both_sensors() -> None:
    assert {recipe(path).env.sensor for path in RECIPES} == {"lidar", "depth"}


@pytest.mark.heavy
@pytest.mark.slow
@pytest.mark.parametrize("path", RECIPES, ids=lambda p: p.stem)
def test_each_recipe_trains_in_process(path: Path, tmp_path: Path) -> None:
    err = io.StringIO()
    with contextlib.redirect_stderr(err):
        code = train.main(train_args(path, tmp_path))
    assert code == 0, err.getvalue()
    check_run(tmp_path / path.stem, path, n_envs=recipe(path).train.n_envs)


@pytest.mark.heavy
@pytest.mark.slow
@pytest.mark.integration
@pytest.mark.parametrize("path", RECIPES, ids=lambda p: p.stem)
def test_each_recipe_trains_through_ros(
        path: Path, launch: Callable[..., Launcher], tmp_path: Path) -> None:
    n_envs = min(recipe(path).train.n_envs, ROS_MAX_ENVS)
    args = train_args(path, tmp_path, n_envs=n_envs)
    launcher = launch("train", *args, *ROS_ARGS)
    assert launcher.wait(300) == 0, launcher.output
    assert launcher.left() == [], launcher.output
    check_run(tmp_path / path.stem, path, n_envs=n_envs, transport="ros",
              **{"ros.timeout_s": ROS_TIMEOUT_S})
