"""Expert-guided training: DAgger labels the states the student drives into (the expert drives
behaviour cloning's), imitation's transitions land in the replay buffer, the regression lowers
the actor's error on the labels, and a tiny imitation + fine-tune run gives an SB3 model like
any other, in process and through ROS 2 (``pic4rl-run``, a sim node in its own process)."""

from __future__ import annotations

import copy
import time
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import torch
import yaml
from agents_helpers import (CONFIG, imitation_on, label_error, Launcher, LIDAR_TD3, ROS_ARGS,
                            TINY)
from ros_helpers import next_domain
from stable_baselines3.common.callbacks import BaseCallback, CallbackList
from stable_baselines3.common.logger import configure
from stable_baselines3.common.utils import obs_as_tensor

from pic4rl_agents.training import train
from pic4rl_agents.models.algorithms import ALGORITHMS, new_model, load_model
from pic4rl_agents.runs.config import (ImitationConfig, load_run_config,
                                        train_config_from_params)
from pic4rl_agents.runs.overrides import parse_overrides
from pic4rl_agents.training.envs import make_vec_env
from pic4rl_agents.training.callbacks import WallClockLimit
from pic4rl_agents.training.imitation import EXPERT, STUDENT, Imitation, actor_loss
from pic4rl_bridge.errors import ConfigError

IMITATION = ["imitation.enabled:true", "imitation.bc_steps:40", "imitation.dagger_rounds:1",
             "imitation.dagger_steps:40", "imitation.gradient_steps:20",
             "imitation.critic_warmup_steps:10"]


def _setup_run(algorithm: str = "td3"):
    return load_run_config([LIDAR_TD3], train={**parse_overrides(TINY, flag="test"),
                                               "algorithm": algorithm},
                           env={"episode_max_steps": 30, "min_linear_m_s": 0.0})


def _setup(algorithm: str = "td3", n_envs: int = 2):
    run = _setup_run(algorithm)
    env = make_vec_env(run.env, n_envs=n_envs, seed=0, vec_env="dummy")
    model = new_model(run.train, env)
    model.set_logger(configure(None, []))
    callback = CallbackList([])
    callback.init_callback(model)
    config = ImitationConfig(enabled=True, bc_steps=40, dagger_rounds=1, dagger_steps=40,
                             gradient_steps=50, critic_warmup_steps=10)
    return run, env, model, Imitation(config, env, run.env, model, callback, batch_size=16)


def test_dagger_labels_the_states_the_student_drives_into() -> None:
    """The expert drives behaviour cloning's steps (its actions are its labels); in a DAgger
    round the student's own deterministic actions drive, and the expert labels each state
    it leads to; all of them are aggregated, and every transition is in the replay buffer."""
    _, env, model, imitation = _setup()
    try:
        assert imitation.collect(40, EXPERT) and imitation.collect(40, STUDENT)
        obs, labels, drivers = imitation.data.arrays()
        assert (drivers == EXPERT).sum() == 40 and (drivers == STUDENT).sum() == 40
        assert obs.shape == (80, *env.observation_space.shape) and labels.shape == (80, 2)
        assert np.all(np.abs(labels) <= 1.0)
        buffer = model.replay_buffer
        assert buffer.size() == 40  # 40 steps of 2 envs each: 80 transitions
        stored = buffer.actions[:buffer.size()].reshape(-1, 2)  # (step, env) order, as obs
        student = drivers == STUDENT
        np.testing.assert_allclose(stored[~student], labels[~student], atol=1e-6)
        acted, _ = model.predict(obs[student], deterministic=True)
        np.testing.assert_allclose(stored[student], acted, atol=1e-5)
        assert not np.allclose(stored[student], labels[student], atol=0.05)  # an untrained one
        assert model.num_timesteps == 80
    finally:
        env.close()


@pytest.mark.parametrize("algorithm", ["td3", "sac"])
def test_the_regression_fits_the_labels(algorithm: str) -> None:
    _, env, model, imitation = _setup(algorithm, n_envs=1)
    try:
        imitation.collect(60, EXPERT)
        obs, labels, _ = imitation.data.arrays()

        before = label_error(model, obs, labels)
        imitation.fit(300)
        assert label_error(model, obs, labels) < 0.5 * before
        with torch.no_grad():  # the loss the fit lowers is the actor's own
            loss = actor_loss(model, obs_as_tensor(obs, model.device), torch.as_tensor(labels))
        assert float(loss) == pytest.approx(imitation.losses[-1], rel=1.0)
        if algorithm == "td3":  # RL's target actor starts as the imitated one
            for a, b in zip(model.actor.parameters(), model.actor_target.parameters()):
                assert torch.equal(a, b)
    finally:
        env.close()


def test_the_critic_warms_up_with_the_actor_frozen() -> None:
    _, env, model, imitation = _setup()
    try:
        imitation.collect(40, EXPERT)
        actor = [p.detach().clone() for p in model.actor.parameters()]
        critic = [p.detach().clone() for p in model.critic.parameters()]
        imitation.warm_up_critic(5)
        assert all(torch.equal(a, p) for a, p in zip(actor, model.actor.parameters()))
        assert not all(torch.equal(c, p) for c, p in zip(critic, model.critic.parameters()))
        assert all(p.requires_grad for p in model.actor.parameters())
    finally:
        env.close()


def test_the_critic_warm_up_stops_when_the_wall_clock_budget_is_spent() -> None:
    _, env, model, imitation = _setup()
    try:
        imitation.collect(40, EXPERT)
        spent = WallClockLimit(1.0, time.perf_counter() - 2.0)  # started 2 s ago, 1 s budget
        imitation.callback.callbacks.append(spent)
        critic = [p.detach().clone() for p in model.critic.parameters()]
        assert imitation.warm_up_critic(500, chunk=5) is False
        assert all(torch.equal(c, p) for c, p in zip(critic, model.critic.parameters()))
        spent.start = time.perf_counter()  # a fresh budget: all of it runs
        assert imitation.warm_up_critic(10, chunk=5) is True
        assert not all(torch.equal(c, p) for c, p in zip(critic, model.critic.parameters()))
    finally:
        env.close()


class _ClockAfter(WallClockLimit):
    """A 10 s wall-clock budget that is spent after ``calls`` env steps (of every env)."""

    def __init__(self, calls: int) -> None:
        super().__init__(10.0, time.perf_counter())
        self.calls = calls

    def over(self) -> bool:
        return self.n_calls >= self.calls


class _StopAfter(BaseCallback):
    """Not a budget: a stop (as a signal's or an evaluation's) after ``calls`` env steps."""

    def __init__(self, calls: int) -> None:
        super().__init__()
        self.calls = calls

    def _on_step(self) -> bool:
        return self.n_calls < self.calls


def _cut_short(stop: BaseCallback) -> tuple[float, float, Imitation, bool]:
    """Cloning of 200 steps of 2 envs that ``stop`` ends after 30: the actor's error on the 60
    states' labels after the run and before it (unfitted), the imitation, what it returned."""
    _, env, model, _ = _setup()
    callback = CallbackList([stop])
    callback.init_callback(model)
    config = ImitationConfig(enabled=True, bc_steps=400, dagger_rounds=0, gradient_steps=300,
                             critic_warmup_steps=10)
    imitation = Imitation(config, env, _setup_run().env, model, callback, batch_size=16)
    unfitted = copy.deepcopy(model.actor.state_dict())
    try:
        done = imitation.run()
    finally:
        env.close()
    obs, labels, drivers = imitation.data.arrays()
    assert len(labels) == 60 and (drivers == EXPERT).all() and model.num_timesteps == 60
    after = label_error(model, obs, labels)
    model.actor.load_state_dict(unfitted)
    return after, label_error(model, obs, labels), imitation, done


def test_a_wall_clock_that_ends_a_round_leaves_the_actor_fitted_on_it() -> None:
    """The clock ends cloning 30 of its 200 steps in: the actor is fitted on the 60 labelled
    states gathered (one fit, at most 300 gradient steps and 1 s, a tenth of the 10 s budget),
    so its error on their labels is under half the unfitted actor's (before the fix: equal,
    the round's data thrown away and a random actor saved)."""
    after, before, imitation, done = _cut_short(_ClockAfter(30))
    assert done is False and imitation.refitted and len(imitation.losses) == 1
    assert after < 0.5 * before


def test_a_stop_that_is_no_budget_leaves_the_actor_as_it_was() -> None:
    """A signal's or an evaluation's stop: that evaluation judged the actor, which stays."""
    after, before, imitation, done = _cut_short(_StopAfter(30))
    assert done is False and not imitation.refitted and imitation.losses == []
    assert after == before


def test_a_fit_stops_at_its_time_bound_after_one_step_at_least() -> None:
    _, env, model, imitation = _setup(n_envs=1)
    try:
        imitation.collect(20, EXPERT)
        assert imitation.fit(7) == 7 and imitation.fit(1000, max_s=0.0) == 1
        assert imitation.fit(0) == 0
    finally:
        env.close()


def test_imitation_then_fine_tuning_gives_an_sb3_model(tmp_path: Path) -> None:
    """80 imitation steps, a critic warm-up, then TD3 to 160 steps: one run directory like
    any other (model, evaluations, summary), the model loads, and the RL phase updated it."""
    args = ["--no-progress", "--run", "il", "--hyperparams", f"runs_dir:{tmp_path}", *TINY,
            *IMITATION, "eval.interval_steps:80", "checkpoint.interval_steps:0",
            "-n", "160", "--env-kwargs", "episode_max_steps:30", "min_linear_m_s:0.0",
            "--ros-args", "--params-file", str(LIDAR_TD3)]
    assert train.main(args) == 0
    run = tmp_path / "il"
    model = load_model(run / "model.zip", "td3")
    assert isinstance(model, ALGORITHMS["td3"]) and model.num_timesteps == 160
    summary = yaml.safe_load((run / "summary.yaml").read_text())
    assert summary["total_steps"] == 160
    evaluations = pd.read_csv(run / "eval" / "0" / "evaluations.csv")
    assert list(evaluations["steps"]) == [80, 160]
    progress = pd.read_csv(run / "logs" / "0" / "progress.csv")
    assert progress["train/n_updates"].max() > 10  # the warm-up's 10, then RL's own
    config = yaml.safe_load((run / "config.yaml").read_text())
    assert config["trainer"]["ros__parameters"]["imitation.enabled"] is True


MEMORY = ["imitation.expert:explorer", "policy.cnn_channels:[4, 8]", "policy.cnn_features:16"]
MEMORY_ENV = ["memory.enabled:true", "memory.size_px:32", "memory.resolution_m:0.3"]


EXPLORER_TRAIN = {**parse_overrides(TINY, flag="test"), "imitation.expert": "explorer"}
EXPLORER_ENV = {"episode_max_steps": 30, "min_linear_m_s": 0.0}


def _explorer_imitation(env_args: dict):
    """One env of ``env_args``, a fresh TD3 model and imitation of the explorer on it."""
    run = load_run_config([LIDAR_TD3], train=EXPLORER_TRAIN, env=env_args)
    env = make_vec_env(run.env, n_envs=1, seed=0, vec_env="dummy")
    model = new_model(run.train, env)
    model.set_logger(configure(None, []))
    callback = CallbackList([])
    callback.init_callback(model)
    imitation = Imitation(ImitationConfig(enabled=True, expert="explorer", bc_steps=10),
                          env, run.env, model, callback, batch_size=16)
    return env, model, callback, imitation


def test_the_explorer_expert_marks_the_frames_the_student_saw() -> None:
    """imitation.expert explorer: one grid per env, marked with each step's frame (the
    student's scan and pose), reset with the episode."""
    from pic4rl_bridge.baselines.explorer import ExplorerController

    env, model, callback, imitation = _explorer_imitation(EXPLORER_ENV)
    try:
        expert = imitation.experts[0]
        assert isinstance(expert, ExplorerController)
        seen, observe = [], expert.plan.observe
        expert.plan.observe = lambda frame: (seen.append(frame), observe(frame))[1]  # type: ignore
        imitation.collect(10, EXPERT)
        assert len(seen) == 10 and len(expert.grid.cells) > 0 and expert.path is not None
        assert all(a.stamp_ns < b.stamp_ns for a, b in zip(seen, seen[1:]))  # one per step
        again = ExplorerController(expert.robot)
        for frame in seen:  # the same frames give the same grid: nothing else went in
            again.observe(frame)
        assert np.array_equal(np.sort(again.grid.cells, axis=0),
                              np.sort(expert.grid.cells, axis=0))
    finally:
        env.close()


def test_the_explorer_expert_labels_along_the_plan_the_student_points_along() -> None:
    """goal_input explorer beside imitation.expert explorer: the expert's plan and the env's
    (the observation's target) are one, built from the same frames; plan settings that differ
    between the baselines: section and nav_env's explorer.* are refused, naming both."""
    env_args = {**EXPLORER_ENV, "goal_input": "explorer"}
    env, model, callback, imitation = _explorer_imitation(env_args)
    try:
        imitation.collect(8, EXPERT)
        plan = env.envs[0].unwrapped._context.extra["explorer"].path
        assert plan is not None and np.array_equal(plan, imitation.experts[0].path)
        other = load_run_config([LIDAR_TD3], train=EXPLORER_TRAIN,
                                env={**env_args, "explorer.margin_m": 0.2})
        with pytest.raises(ConfigError, match=r"explorer\.\*.*same plan settings"):
            Imitation(ImitationConfig(enabled=True, expert="explorer"), env, other.env, model,
                      callback, batch_size=16)
    finally:
        env.close()


def test_imitation_with_memory_then_fine_tuning_gives_a_loadable_model(tmp_path: Path) -> None:
    """The explorer labels, the observation holds the memory crop (a Dict through the CNN
    extractor): 80 imitation steps then TD3 to 160, a model that loads and acts."""
    args = ["--no-progress", "--run", "mem", "--hyperparams", f"runs_dir:{tmp_path}", *TINY,
            *IMITATION, *MEMORY, "eval.interval_steps:0", "checkpoint.interval_steps:0",
            "-n", "160", "--env-kwargs", "episode_max_steps:30", "min_linear_m_s:0.0",
            *MEMORY_ENV, "--ros-args", "--params-file", str(LIDAR_TD3)]
    assert train.main(args) == 0
    model = load_model(tmp_path / "mem" / "model.zip", "td3")
    assert model.num_timesteps == 160
    space = model.observation_space
    assert set(space.spaces) == {"memory", "lidar"} and space["memory"].shape == (1, 32, 32)
    action, _ = model.predict(space.sample(), deterministic=True)
    assert action.shape == (2,)


@pytest.mark.integration
@pytest.mark.slow
def test_imitation_with_memory_trains_through_ros(tmp_path: Path) -> None:
    args = ["train", "--hyperparams", *TINY, *IMITATION, *MEMORY, "checkpoint.interval_steps:0",
            "eval.interval_steps:0", "--env-kwargs", "episode_max_steps:30",
            "min_linear_m_s:0.0", *MEMORY_ENV, "-n", "120", "--run", "mem_ros",
            "--no-progress", "--ros-args", "--params-file", str(LIDAR_TD3),
            "-p", f"runs_dir:={tmp_path}", *ROS_ARGS]
    launcher = Launcher.start(args, tmp_path / "launcher.log", next_domain())
    try:
        assert launcher.wait(300) == 0, launcher.output
        assert launcher.left() == []
    finally:
        launcher.stop(interrupt=False)
    model = load_model(tmp_path / "mem_ros" / "model.zip", "td3")
    assert model.num_timesteps == 120 and "memory" in model.observation_space.spaces


def test_imitation_needs_an_off_policy_algorithm() -> None:
    with pytest.raises(ConfigError, match="imitation.enabled"):
        load_run_config([LIDAR_TD3], train={"algorithm": "ppo", "epsilon.initial": 0.0,
                                            "imitation.enabled": True})


@pytest.mark.integration
@pytest.mark.slow
def test_imitation_trains_through_ros(tmp_path: Path) -> None:
    args = ["train", "--hyperparams", *TINY, *IMITATION, "checkpoint.interval_steps:0",
            "eval.interval_steps:0", "--env-kwargs", "episode_max_steps:30",
            "min_linear_m_s:0.0", "-n", "120", "--run", "il_ros", "--no-progress",
            "--ros-args", "--params-file", str(LIDAR_TD3), "-p", f"runs_dir:={tmp_path}",
            *ROS_ARGS]
    launcher = Launcher.start(args, tmp_path / "launcher.log", next_domain())
    try:
        assert launcher.wait(300) == 0, launcher.output
        assert launcher.left() == []
    finally:
        launcher.stop(interrupt=False)
    model = load_model(tmp_path / "il_ros" / "model.zip", "td3")
    assert model.num_timesteps == 120
    config = yaml.safe_load((tmp_path / "il_ros" / "config.yaml").read_text())
    assert config["nav_env"]["ros__parameters"]["transport"] == "ros"


def test_the_heading_expert_labels_the_person_envs_own_action() -> None:
    """In a hybrid person env the expert labels ω alone, end to end (vx, vy, ω); it drives
    personMonitoring only, and the planner goToPose only."""
    from pic4rl_agents.training.imitation import make_expert
    from pic4rl_bridge.config import load_env_config
    from pic4rl_bridge.baselines.follow import HeadingController

    person = load_env_config(CONFIG / "env_person_omni.yaml")
    for control, size in (("hybrid", 1), ("end_to_end", 3)):
        expert = make_expert("dwa_heading", person.replace(**{"person.control": control}))
        assert isinstance(expert, HeadingController) and expert.hybrid == (size == 1)
    with pytest.raises(ConfigError, match="dwa_heading drives personMonitoring; the env's task is "
                                          "'goToPose' \\(use planner\\)"):
        make_expert("dwa_heading", load_run_config([LIDAR_TD3]).env)
    with pytest.raises(ConfigError, match="planner drives goToPose; .*'personMonitoring' "
                                          "\\(use dwa_heading\\)"):
        make_expert("planner", person)
    with pytest.raises(ConfigError, match="'nobody' is invalid; expected one of planner, "
                                          "explorer, predictive, centerline, dwa_heading"):
        make_expert("nobody", person)


def test_the_old_spelling_of_the_heading_expert_is_refused_with_its_new_name() -> None:
    """Imitation's person-following expert is named as its baseline, ``dwa_heading``: the old
    ``heading`` in a params file or on the command line is one line naming the new name."""
    for params in ({"imitation": {"expert": "heading"}}, {"imitation.expert": "heading"}):
        with pytest.raises(ConfigError) as err:
            train_config_from_params(params)
        assert str(err.value) == ("imitation.expert: 'heading' is invalid; "
                                  "expected its new name 'dwa_heading'")
    config = train_config_from_params({"imitation.expert": "dwa_heading"})
    assert config.imitation.expert == "dwa_heading"


def test_a_map_aware_expert_drives_each_episode_s_world() -> None:
    """With a world drawn per episode (the dynamic BARN's training scenes 1 and 2, 5-step
    episodes), the predictive planner that labels is made anew on each episode's world: the
    one the env's reset reports, not the config's first."""
    run = load_run_config([CONFIG / "train_dynbarn_td3_history.yaml"],
                          train={**parse_overrides(TINY, flag="test"), "n_envs": 1},
                          env={"episode_max_steps": 5, "episodes.world_variants": "1,2"})
    env = make_vec_env(run.env, n_envs=1, seed=0, vec_env="dummy")
    try:
        config = ImitationConfig(enabled=True, expert="predictive", bc_steps=5, dagger_rounds=0)
        imitation = imitation_on(run, env, config)
        worlds = []
        for _ in range(4):  # an episode each
            assert imitation.collect(5, EXPERT)
            scenario = env.get_attr("scenario")[0]
            expert = imitation.experts[0]
            assert expert.world.moving is not None  # the dynamic BARN's, with its movers
            assert expert.world.name == "dynbarn" and expert.world.seed == scenario.world.seed
            worlds.append(scenario.variant)
        assert set(worlds) == {1, 2}
    finally:
        env.close()
