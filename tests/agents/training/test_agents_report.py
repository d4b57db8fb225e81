"""What training reports: who drove each training episode (the expert, the student, RL), a
``summary.yaml`` that leads with the last evaluation and never gives the expert's success as
the agent's, a reward curve drawn per driver, a progress bar whose ETA follows the budget that
ends the run first and that names the phase, and one printed line per evaluation."""

from __future__ import annotations

import re
from pathlib import Path

import gymnasium as gym
import numpy as np
import pandas as pd
import pytest
import yaml
from agents_helpers import LIDAR_TD3, TINY, label_error
from stable_baselines3.common.evaluation import evaluate_policy

from pic4rl_agents.runs.config import load_run_config
from pic4rl_agents.models.algorithms import load_model, new_model
from pic4rl_agents.training import train
from pic4rl_agents.training.callbacks import evaluation_line
from pic4rl_agents.training.curves import episode_table, reward_series
from pic4rl_agents.training.envs import DRIVER_KEY, Driven, eval_env_config, make_vec_env
from pic4rl_agents.training.progress import binding_budget
from pic4rl_agents.training.summary import session_summary

IMITATION = ["imitation.enabled:true", "imitation.gradient_steps:20",
             "imitation.critic_warmup_steps:10"]
SHORT_PAIRS = ["episode_max_steps:60", "min_linear_m_s:0.0", "episodes.min_distance_m:0.6",
               "episodes.max_distance_m:1.2", "episodes.max_detour:1.2"]


def _train(tmp_path: Path, name: str, steps: int, hyperparams: list[str],
           progress: bool = False) -> Path:
    args = ["--run", name, "--hyperparams", f"runs_dir:{tmp_path}", *TINY, *IMITATION,
            *hyperparams, "checkpoint.interval_steps:0", "-n", str(steps),
            "--env-kwargs", *SHORT_PAIRS, "--ros-args", "--params-file", str(LIDAR_TD3)]
    assert train.main(args if progress else ["--no-progress", *args]) == 0
    return tmp_path / name


# -- who drove ------------------------------------------------------------------------------


class _Steps(gym.Env):
    """Episodes of ``length`` steps, nothing else."""

    observation_space = gym.spaces.Box(0.0, 1.0, (1,))
    action_space = gym.spaces.Box(-1.0, 1.0, (1,))

    def __init__(self, length: int) -> None:
        self.length, self.t = length, 0

    def reset(self, *, seed: int | None = None, options: dict | None = None):
        self.t = 0
        return np.zeros(1, np.float32), {}

    def step(self, action):
        self.t += 1
        return np.zeros(1, np.float32), 0.0, False, self.t >= self.length, {}


def _drive(env: Driven, steps: int) -> list[str]:
    ended = []
    for _ in range(steps):
        *_, terminated, truncated, info = env.step(np.zeros(1))
        if terminated or truncated:
            ended.append(info[DRIVER_KEY])
            env.reset()
    return ended


def test_each_ended_episode_names_who_drove_it_and_a_change_mid_episode_is_mixed() -> None:
    env = Driven(_Steps(length=4))
    env.reset()
    assert _drive(env, 4) == ["rl"]  # the default: no imitation
    env.set_driver("expert")
    assert _drive(env, 6) == ["expert"]  # 2 steps into the next episode
    env.set_driver("student")
    assert _drive(env, 6) == ["mixed", "student"]
    with pytest.raises(ValueError, match="driver: 'teacher' is invalid"):
        env.set_driver("teacher")


# -- summary.yaml ---------------------------------------------------------------------------


def _episodes(drivers: list[tuple[str, int, int]]) -> pd.DataFrame:
    """Episodes of (driver, how many, how many of them succeeded first); reward 1000 for a
    success, -150 else."""
    rows = []
    for driver, n, succeeded in drivers:
        rows += [{"r": 1000.0 if i < succeeded else -150.0, "l": 10, "t": 0.0,
                  "is_success": i < succeeded, "outcome": "goal" if i < succeeded else "collision",
                  DRIVER_KEY: driver} for i in range(n)]
    return pd.DataFrame(rows)


EVALUATIONS = pd.DataFrame({
    "steps": [2000, 4000, 6000], "wall_s": [60.0, 121.0, 182.5], "train_wall_s": [55, 110, 160],
    "eval_s": [5.0, 5.0, 5.0], "episodes": [5, 5, 5], "success_rate": [0.2, 0.4, 0.0],
    "mean_reward": [100.0, 300.0, -150.0], "mean_length": [50.0, 60.0, 20.0],
    "collision_rate": [0.6, 0.2, 1.0], "timeout_rate": [0.2, 0.4, 0.0],
    "diverged_rate": [0.0, 0.0, 0.0]})


def test_the_summary_leads_with_the_evaluation_and_keeps_the_experts_success_apart() -> None:
    """120 expert episodes all successful, then 4 student episodes (1 success) and 40 RL ones
    (10 successes): the agent's last 100 are its 44 (11 successes: 0.25), never the expert's
    1.0; the summary opens with the last evaluation (0/5, 5 collisions, at 6,000 steps) and
    names the saved models (the best: the 4,000-step evaluation, highest mean reward)."""
    run = load_run_config([LIDAR_TD3])
    episodes = _episodes([("expert", 120, 120), ("student", 4, 1), ("rl", 40, 10)])
    summary = session_summary(run, 0, 7724, 7724, 300.0, episodes, EVALUATIONS,
                              best_model=Path("best/0/best_model.zip"), model=Path("model.zip"))
    assert list(summary)[:2] == ["evaluation", "saved_models"]
    assert summary["evaluation"] == {
        "steps": 6000, "wall_s": 182.5, "episodes": 5, "success_rate": 0.0,
        "collision_rate": 1.0, "timeout_rate": 0.0, "diverged_rate": 0.0,
        "mean_reward": -150.0, "steps_before_saved": 1724}
    assert summary["saved_models"] == {
        "last": {"file": "model.zip", "steps": 7724},
        "best": {"file": "best/0/best_model.zip", "steps": 4000, "success_rate": 0.4,
                 "mean_reward": 300.0}}
    by_driver = summary["episodes_by_driver"]
    assert list(by_driver) == ["expert", "student", "rl"]
    assert by_driver["expert"] == {"episodes": 120, "last_100_success_rate": 1.0,
                                   "last_100_mean_reward": 1000.0}
    assert by_driver["student"]["last_100_success_rate"] == 0.25
    assert by_driver["rl"]["last_100_success_rate"] == 0.25
    assert summary["episodes"] == 164
    assert summary["agent_last_100_success_rate"] == 0.25
    assert summary["agent_last_100_mean_reward"] == pytest.approx((11 * 1000 - 33 * 150) / 44,
                                                                  abs=0.05)
    assert "last_100_success_rate" not in summary


def test_a_run_that_never_left_imitation_does_not_report_the_experts_success(
        tmp_path: Path) -> None:
    """Behaviour cloning's 1,000 expert steps are more than the run's 200: every training
    episode is the expert's. The summary says so (no agent success rate), and opens with the
    last evaluation, that of the saved model, equal to evaluations.csv's last row."""
    run = _train(tmp_path, "bc", 200, ["imitation.bc_steps:1000", "eval.interval_steps:100"])
    summary = yaml.safe_load((run / "summary.yaml").read_text())
    episodes = episode_table(run / "monitor")
    assert len(episodes) >= 2 and set(episodes[DRIVER_KEY]) == {"expert"}
    assert list(summary)[0] == "evaluation"
    evaluations = pd.read_csv(run / "eval" / "0" / "evaluations.csv")
    # at 200 steps the budget's fit of the round's labels, then the saved model's evaluation
    assert evaluations["steps"].tolist() == [100, 200, 200]
    last = evaluations.iloc[-1]
    evaluation = summary["evaluation"]
    assert evaluation["steps"] == last["steps"] == 200 and evaluation["steps_before_saved"] == 0
    for key in ("success_rate", "collision_rate", "timeout_rate"):
        assert evaluation[key] == pytest.approx(last[key], abs=1e-3)
    assert evaluation["wall_s"] == pytest.approx(last["wall_s"], abs=0.06)
    assert summary["saved_models"]["last"] == {"file": "model.zip", "steps": 200}
    assert list(summary["episodes_by_driver"]) == ["expert"]
    expert = summary["episodes_by_driver"]["expert"]
    assert expert["episodes"] == len(episodes)
    assert expert["last_100_success_rate"] == pytest.approx(episodes["is_success"].mean(),
                                                            abs=1e-3)
    assert summary["agent_last_100_success_rate"] is None
    assert summary["agent_last_100_mean_reward"] is None


def test_a_clock_that_ends_cloning_saves_the_clone_and_the_summary_judges_it(
        tmp_path: Path) -> None:
    """An 8 s clock ends behaviour cloning (100,000 expert steps) mid-round: the saved actor
    is fitted on the states the expert drove (the replay buffer's, its actions the labels),
    its error on them under half that of an unfitted actor (a new model of the same seed;
    before the fix, the saved actor was that one). The summary's evaluation is of the saved
    model: evaluations.csv's last row, at the saved steps after the periodic ones, and
    model.zip driven again on the same seeded episode gives its reward and length."""
    run = _train(tmp_path, "cut", 1_000_000, [
        "max_wall_s:8", "imitation.bc_steps:100000", "imitation.gradient_steps:5000",
        "imitation.learning_rate:0.003", "eval.interval_steps:400",
        "checkpoint.replay_buffer:true"])
    summary = yaml.safe_load((run / "summary.yaml").read_text())
    steps = summary["total_steps"]
    assert set(episode_table(run / "monitor")[DRIVER_KEY]) == {"expert"}
    config = load_run_config([run / "config.yaml"])
    model = load_model(run / "model.zip", "td3")
    model.load_replay_buffer(run / "replay_buffer.pkl")
    buffer = model.replay_buffer
    obs = buffer.observations[:buffer.size(), 0]
    labels = buffer.actions[:buffer.size(), 0]
    env = make_vec_env(config.env, seed=0, vec_env="dummy")
    try:
        unfitted = new_model(config.train, env)
    finally:
        env.close()
    fitted, random = label_error(model, obs, labels), label_error(unfitted, obs, labels)
    assert fitted < 0.5 * random, (fitted, random)

    evaluations = pd.read_csv(run / "eval" / "0" / "evaluations.csv")
    periodic = list(range(400, steps + 1, 400))
    assert evaluations["steps"].tolist() == [*periodic, steps]  # the last: the saved model
    last = evaluations.iloc[-1]
    evaluation = summary["evaluation"]
    assert evaluation["steps"] == steps and evaluation["steps_before_saved"] == 0
    assert evaluation["mean_reward"] == pytest.approx(last["mean_reward"], abs=0.06)
    eval_env = make_vec_env(eval_env_config(config.env, config.train.eval),
                            seed=config.train.eval.seed, vec_env="dummy")
    try:
        eval_env.seed(config.train.eval.seed)
        rewards, lengths = evaluate_policy(model, eval_env, n_eval_episodes=1,
                                           deterministic=True, return_episode_rewards=True)
    finally:
        eval_env.close()
    assert lengths == [last["mean_length"]]
    assert rewards[0] == pytest.approx(last["mean_reward"], abs=1e-3)


# -- the reward curve -----------------------------------------------------------------------


def test_the_reward_curve_averages_each_driver_apart() -> None:
    """Expert episodes of 1000, then RL episodes of -150: the RL line's moving average is
    -150 from its first episode (the expert's 1000s never enter it), at episodes 4-6."""
    episodes = _episodes([("expert", 3, 3), ("rl", 3, 0)])
    series = reward_series(episodes, window=50)
    assert list(series) == ["rl", "expert"]
    assert series["rl"]["episode"].tolist() == [4, 5, 6]
    assert series["rl"]["mean"].tolist() == [-150.0] * 3
    assert series["expert"]["mean"].tolist() == [1000.0] * 3


# -- progress and the console ---------------------------------------------------------------


def test_the_eta_follows_the_budget_that_ends_the_run_first() -> None:
    # 1,000 steps, 60 s in, at 16 steps/s: 5 M steps would take 87 h; the 300 s clock binds,
    # 240 s left, ending at 1,000 + 240 x 16 = 4,840 steps, a fifth of the clock spent
    wall = binding_budget(1000, 5_000_000, 60.0, max_wall_s=300.0, steps_per_s=16.0)
    assert wall.binding == "max_wall_s" and wall.total_steps == 4840
    assert wall.fraction == pytest.approx(0.2) and wall.eta_s == pytest.approx(240.0)
    # 1,000 more steps take 62.5 s: the step budget binds, half of it done
    steps = binding_budget(1000, 2000, 60.0, max_wall_s=300.0, steps_per_s=16.0)
    assert steps.binding == "max_steps" and steps.total_steps == 2000
    assert steps.fraction == pytest.approx(0.5) and steps.eta_s == pytest.approx(62.5)
    # no clock budget
    only_steps = binding_budget(11_000, 20_000, 100.0, steps_per_s=10.0)
    assert only_steps.binding == "max_steps" and only_steps.eta_s == pytest.approx(900.0)
    assert only_steps.fraction == pytest.approx(0.55)
    # before the speed is known: the clock's time left, the steps' total
    start = binding_budget(0, 5_000_000, 2.0, max_wall_s=300.0)
    assert start.binding == "max_wall_s" and start.eta_s == pytest.approx(298.0)
    assert start.total_steps == 5_000_000
    assert binding_budget(0, 1000, 0.0).eta_s is None
    # the clock spent: nothing left, whatever the steps
    over = binding_budget(7724, 5_000_000, 301.0, max_wall_s=300.0, steps_per_s=25.0)
    assert over.fraction == 1.0 and over.eta_s == 0.0 and over.total_steps == 7724


def test_an_evaluation_line_counts_the_outcomes_and_names_the_best() -> None:
    row = {"steps": 6000, "wall_s": 182.5, "episodes": 5, "success_rate": 0.6,
           "collision_rate": 0.2, "timeout_rate": 0.2, "diverged_rate": 0.0}
    best = {"steps": 4000, "success_rate": 0.8}
    assert evaluation_line(row, best) == (
        "eval at 6,000 steps (3.0 min): success 3/5 (60%), collisions 1, timeouts 1; "
        "best 80% at 4,000 steps")
    diverged = {**row, "collision_rate": 0.0, "diverged_rate": 0.2}
    assert "collisions 0, timeouts 1, diverged 1;" in evaluation_line(diverged, best)


def test_the_bar_names_each_phase_and_each_evaluation_prints_a_line(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """Cloning (40 steps), one DAgger round (40), the critic's warm-up, then RL to 160 steps,
    an evaluation every 40: the bar's description names each phase, and each evaluation is
    one line with the numbers of its evaluations.csv row."""
    run = _train(tmp_path, "phases", 160, [
        "imitation.bc_steps:40", "imitation.dagger_rounds:1", "imitation.dagger_steps:40",
        "eval.interval_steps:40"], progress=True)
    err = capsys.readouterr().err.replace("\r", "\n")  # the bar redraws after a carriage return
    for phase in ("cloning", "DAgger round 1/1", "critic warm-up", "RL"):
        assert f"phases [{phase}]:" in err, phase
    lines = re.findall(r"^pic4rl-train: (eval at .*)$", err, re.MULTILINE)
    rows = pd.read_csv(run / "eval" / "0" / "evaluations.csv")
    assert rows["steps"].tolist() == [40, 80, 120, 160] and len(lines) == 4
    best: dict = {}
    for line, (_, row) in zip(lines, rows.iterrows()):
        if not best or row["success_rate"] > best["success_rate"]:
            best = row.to_dict()
        assert line == evaluation_line(row.to_dict(), best)
    drivers = episode_table(run / "monitor")[DRIVER_KEY]
    assert set(drivers) <= {"expert", "student", "rl", "mixed"} and "rl" in set(drivers)


def test_a_run_the_clock_ends_fills_its_bar_with_the_steps_it_drove(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """5 M steps and a 6 s clock: the bar's total is the steps the clock allows, not 5 M, and
    the bar ends full, saying which budget ended the run."""
    args = ["--run", "clock", "--hyperparams", f"runs_dir:{tmp_path}", *TINY, "max_wall_s:6",
            "eval.interval_steps:0", "checkpoint.interval_steps:0", "-n", "5000000",
            "--env-kwargs", "episode_max_steps:40", "--ros-args", "--params-file",
            str(LIDAR_TD3)]
    assert train.main(args) == 0
    err = capsys.readouterr().err.replace("\r", "\n")
    steps = yaml.safe_load((tmp_path / "clock" / "summary.yaml").read_text())["total_steps"]
    last_bar = [line for line in err.splitlines() if line.startswith("clock [RL]:")][-1]
    assert f"| {steps}/{steps} [" in last_bar and "ends=max_wall_s 6 s" in last_bar
    assert "5000000" not in last_bar
