"""``trainer.trained_agent`` (``pic4rl-train -i``): a new run that starts from a trained
model's networks, with its own hyperparameters and an empty replay buffer, and the trained
run left as it was; a model that does not fit is refused naming the key."""

from __future__ import annotations

import contextlib
import dataclasses
import hashlib
import io
from pathlib import Path
from typing import Any

import pytest
import torch
from agents_helpers import (
    CONFIG,
    DEPTH_TD3,
    LIDAR_TD3,
    ROOT,
    SHORT_EPISODES,
    TINY,
    TRAINED_STEPS,
    TrainedRun,
)

from pic4rl_agents.models.algorithms import load_model, new_model
from pic4rl_agents.runs.config import load_run_config
from pic4rl_agents.runs.overrides import parse_overrides
from pic4rl_agents.training import train
from pic4rl_agents.training.envs import make_vec_env
from pic4rl_bridge.errors import ConfigError


def config(path: Path, *extra: str, params_file: Path = LIDAR_TD3) -> Any:
    """The tiny training config of ``params_file`` starting from ``path``."""
    train_ = parse_overrides([*TINY, *extra], flag="--hyperparams")
    return load_run_config([params_file], train={**train_, "trained_agent": str(path)})


def same_policy(a: Any, b: Any) -> bool:
    state_a, state_b = a.policy.state_dict(), b.policy.state_dict()
    return state_a.keys() == state_b.keys() and all(
        torch.equal(state_a[k], state_b[k]) for k in state_a)


def test_a_new_model_starts_from_the_trained_networks_with_its_own_settings(
        trained_run: TrainedRun) -> None:
    assert trained_run.code == 0, trained_run.stderr
    run = config(trained_run.run_dir, "learning_rate:0.0001", "seed:7")
    env = make_vec_env(run.env)
    try:
        trained = load_model(trained_run.run_dir / "model.zip", "td3")
        fresh = new_model(dataclasses.replace(run.train, trained_agent=""), env)
        model = new_model(run.train, env)
        assert not same_policy(fresh, trained)  # seed 7's initial networks differ
        assert same_policy(model, trained)  # actor, critic and both targets
        assert model.num_timesteps == 0 and model.replay_buffer.size() == 0
        assert model.learning_rate == 0.0001 and model.seed == 7
        assert trained.num_timesteps == TRAINED_STEPS
    finally:
        env.close()


@pytest.mark.bad_input
@pytest.mark.parametrize(("extra", "params_file", "message"), [
    (("policy.net_arch:[8]",), LIDAR_TD3,
     r"^trainer\.trained_agent: .*model\.zip: its networks do not fit this run's policy"),
    ((), DEPTH_TD3, r"^trainer\.trained_agent: .*model\.zip was trained on the observation "
                    r"space .* but this run's env"),
], ids=["other networks", "other env"])
def test_a_model_that_does_not_fit_is_refused_naming_the_key(
        trained_run: TrainedRun, extra: tuple[str, ...], params_file: Path, message: str) -> None:
    run = config(trained_run.run_dir, *extra, params_file=params_file)
    env = make_vec_env(run.env)
    try:
        with pytest.raises(ConfigError, match=message):
            new_model(run.train, env)
    finally:
        env.close()


@pytest.mark.bad_input
def test_a_missing_trained_agent_exits_2_naming_it_and_writes_nothing(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(tmp_path)
    err = io.StringIO()
    with contextlib.redirect_stderr(err):
        code = train.main(["-i", "nowhere", "--ros-args", "--params-file", str(LIDAR_TD3)])
    assert code == 2
    assert err.getvalue() == ("pic4rl-train: -i/--trained-agent: nowhere: no such model (expected "
                              "a model .zip or a folder holding model.zip)\n")
    assert list(tmp_path.iterdir()) == []


def test_pic4rl_train_i_trains_a_new_run_from_the_agent_leaving_it_as_it_was(
        trained_run: TrainedRun, tmp_path: Path) -> None:
    """Fewer steps than the warm-up: no update, so the new run saves the trained networks."""
    before = {p: hashlib.sha256(p.read_bytes()).hexdigest()
              for p in sorted(trained_run.run_dir.rglob("*")) if p.is_file()}
    err = io.StringIO()
    with contextlib.redirect_stderr(err):
        code = train.main(["-i", str(trained_run.run_dir), "--hyperparams", *TINY,
                           "learning_starts:1000", "checkpoint.interval_steps:0",
                           "eval.interval_steps:0", "--env-kwargs", *SHORT_EPISODES,
                           "-n", "40", "--run", "tuned", "--no-progress", "--ros-args",
                           "--params-file", str(LIDAR_TD3), "-p", f"runs_dir:={tmp_path}"])
    assert code == 0, err.getvalue()
    tuned = load_model(tmp_path / "tuned" / "model.zip", "td3")
    assert tuned.num_timesteps == 40
    assert same_policy(tuned, load_model(trained_run.run_dir / "model.zip", "td3"))
    saved = load_run_config([tmp_path / "tuned" / "config.yaml"])
    assert saved.train.trained_agent == str(trained_run.run_dir)
    assert before == {p: hashlib.sha256(p.read_bytes()).hexdigest()
                      for p in sorted(trained_run.run_dir.rglob("*")) if p.is_file()}


def test_the_shipped_recipe_finds_its_agent_from_any_directory(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """``trained_agent`` is one of the params file's relative files (``FILE_KEYS``): not in the
    working directory, it is found beside the params file."""
    monkeypatch.chdir(tmp_path)
    run = load_run_config([CONFIG / "train_crowd_td3_lidar.yaml"])
    assert Path(run.train.trained_agent) == ROOT / "checkpoints" / "td3_lidar"
