"""The vineyard's expert-guided training: the centre-line follower is the expert of a vineyard
env and of no other, its labels drive the row, the CNN on depth alone learns them, and
imitation then RL on the shipped recipe gives an SB3 model."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from agents_helpers import CONFIG, imitation_on, label_error, LIDAR_TD3, TINY

from pic4rl_agents.training import train
from pic4rl_agents.models.algorithms import ALGORITHMS, load_model
from pic4rl_agents.runs.config import ImitationConfig, load_run_config
from pic4rl_agents.training.envs import make_vec_env
from pic4rl_agents.training.imitation import EXPERT, make_expert
from pic4rl_agents.runs.overrides import parse_overrides
from pic4rl_bridge.errors import ConfigError
from pic4rl_bridge.baselines.row_followers import CenterlineFollower

RECIPE = CONFIG / "train_vineyard_sac.yaml"


def test_the_centre_line_follower_is_the_vineyard_expert_only() -> None:
    vineyard = load_run_config([RECIPE]).env
    assert isinstance(make_expert("centerline", vineyard), CenterlineFollower)
    with pytest.raises(ConfigError, match="imitation.expert: planner drives goToPose; the "
                                          "env's task is 'vineyard'"):
        make_expert("planner", vineyard)
    with pytest.raises(ConfigError, match="imitation.expert: centerline drives vineyard"):
        make_expert("centerline", load_run_config([LIDAR_TD3]).env)


def test_the_cnn_on_depth_learns_the_experts_labels() -> None:
    run = load_run_config([RECIPE], train=parse_overrides(TINY, flag="test"),
                          env={"episode_max_steps": 300})
    env = make_vec_env(run.env, n_envs=1, seed=0, vec_env="dummy")
    try:
        config = ImitationConfig(enabled=True, expert="centerline", bc_steps=300)
        imitation = imitation_on(run, env, config, batch_size=32)
        assert imitation.collect(300, EXPERT)
        obs, labels, _ = imitation.data.arrays()
        assert obs.shape == (300, 1, 30, 40) and obs.dtype == np.uint8  # the image alone
        assert (labels[:, 0] > 0.9).mean() > 0.8  # the expert drives on at full speed
        assert labels[:, 1].std() > 0.01  # and steers along the bent rows

        before = label_error(imitation.model, obs, labels)
        imitation.fit(300)
        assert label_error(imitation.model, obs, labels) < 0.5 * before
    finally:
        env.close()


def test_imitation_then_rl_on_the_vineyard_recipe(tmp_path: Path) -> None:
    imitation = ["imitation.bc_steps:60", "imitation.dagger_rounds:1",
                 "imitation.dagger_steps:60", "imitation.gradient_steps:20",
                 "imitation.critic_warmup_steps:10"]
    args = ["--no-progress", "--run", "vy", "--hyperparams", f"runs_dir:{tmp_path}", *TINY,
            *imitation, "n_envs:2", "eval.interval_steps:120", "eval.interval_s:0",
            "checkpoint.interval_steps:0", "-n", "240", "--env-kwargs", "episode_max_steps:50",
            "--ros-args", "--params-file", str(RECIPE)]
    assert train.main(args) == 0
    model = load_model(tmp_path / "vy" / "model.zip", "sac")
    assert isinstance(model, ALGORITHMS["sac"]) and model.num_timesteps == 240
    assert model.observation_space.shape == (1, 30, 40)  # no goal, no pose
    progress = pd.read_csv(tmp_path / "vy" / "logs" / "0" / "progress.csv")
    assert progress["train/n_updates"].max() > 10  # the warm-up's 10, then RL's own
