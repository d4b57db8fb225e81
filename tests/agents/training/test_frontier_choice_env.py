"""The learned frontier choice's decision-level env and its policy plugin, on the real explore
env in process: one decision drives the explorer for as many control steps as it takes, so an
episode's decisions add up to the explore episode's steps and rewards; the shipped policy is
judged by ``pic4rl-test`` as a plugin, its bags recorded."""

from __future__ import annotations

import math
from pathlib import Path

import gymnasium as gym
import pytest

from pic4rl_agents.testing.plan import TestPlan
from pic4rl_agents.testing.tester import drive_and_judge
from pic4rl_agents.training.frontier_choice import (
    CHECKPOINT,
    FIRST_BIAS,
    VALIDATION_VARIANTS,
    FrontierChoiceEnv,
    main,
    new_model,
    train,
)
from pic4rl_bridge.baselines.frontier_choice import CHOICES
from pic4rl_bridge.errors import ConfigError
from pic4rl_metrics import read_episode

REPO = Path(__file__).resolve().parents[3]
EXPLORE = str(REPO / "config" / "env_explore.yaml")
STEPS = 200


class Rewards(gym.Wrapper):
    """Keeps the inner env's rewards, step by step."""

    def reset(self, **kwargs):
        self.rewards = []
        return self.env.reset(**kwargs)

    def step(self, action):
        out = self.env.step(action)
        self.rewards.append(out[1])
        return out


def test_decisions_add_up_to_the_explore_episode():
    import pic4rl_bridge  # noqa: F401

    inner = Rewards(gym.make("pic4rl/ExploreLidar-v0", config=EXPLORE,
                             overrides={"episode_max_steps": STEPS, "reward.step": -0.1}))
    env = FrontierChoiceEnv(inner)
    observation, _ = env.reset(seed=3)
    assert env.observation_space.contains(observation)
    decisions, steps, total, done = 0, 0, 0.0, False
    while not done:
        observation, reward, terminated, truncated, info = env.step(decisions % CHOICES)
        assert env.observation_space.contains(observation) and info["control_steps"] >= 1
        decisions, steps, total = decisions + 1, steps + info["control_steps"], total + reward
        done = terminated or truncated
    assert truncated and steps == len(inner.rewards) == STEPS  # no target reached in 20 s
    assert decisions > 3 and total == pytest.approx(sum(inner.rewards), abs=1e-9)
    assert env.nav._context.extra["seen"].grid.area_m2 > 20.0
    env.close()


def test_the_shipped_policy_is_judged_as_a_plugin(tmp_path: Path):
    assert (CHECKPOINT / "model.zip").is_file()
    plan = TestPlan(agents=("pic4rl_agents.training.frontier_choice:FrontierPPO",), episodes=1,
                    bags_dir=tmp_path / "bags", run="r", params_files=(EXPLORE,),
                    env_overrides={"episode_max_steps": STEPS}, progress=False)
    result = drive_and_judge(plan)
    assert result.outcomes["frontier_ppo"] == ["timeout"] and not result.failed
    bag = next((result.run_dir / "frontier_ppo").glob("episode_*"))
    episode = read_episode(bag)
    assert episode.facts.agent == "frontier_ppo" and episode.facts.free_area_m2 > 0
    assert len(episode.inputs["cmd"].vx) == STEPS


def test_the_untrained_policy_favours_the_nearest_candidate():
    """The action head's bias: at the start the nearest candidate is chosen with probability
    e^2 / (e^2 + 5) (the output layer's weights start near zero), the others alike."""
    import torch

    env = FrontierChoiceEnv(gym.make("pic4rl/ExploreLidar-v0", config=EXPLORE,
                                     overrides={"episode_max_steps": STEPS}))
    model = new_model(env, seed=0)
    observation, _ = env.reset(seed=1)
    with torch.no_grad():
        obs = torch.as_tensor(observation[None])
        probs = model.policy.get_distribution(obs).distribution.probs[0].numpy()
    first = math.exp(FIRST_BIAS) / (math.exp(FIRST_BIAS) + CHOICES - 1)
    assert probs[0] == pytest.approx(first, abs=0.03)
    assert probs[1:] == pytest.approx([(1 - first) / (CHOICES - 1)] * (CHOICES - 1), abs=0.02)
    env.close()


@pytest.mark.heavy
def test_a_short_training_run_writes_its_policy_curve_and_validation(tmp_path: Path):
    # 1.2 min: a loaded CI machine made 107 of the rollout's 128 decisions in 0.8 min
    summary = train(tmp_path, minutes=1.2, n_envs=1, seed=0, validation=1)
    assert summary["decisions"] >= 128  # at least one PPO rollout
    assert (tmp_path / "model.zip").is_file() and (tmp_path / "0.monitor.csv").is_file()
    (episode,) = summary["validation"]
    assert episode["variant"] == VALIDATION_VARIANTS[0] and 0.0 < episode["coverage"] <= 1.05
    assert episode["outcome"] in ("goal", "timeout", "collision")


def test_a_training_run_never_writes_into_a_folder_that_holds_something(tmp_path: Path):
    """Nothing recorded is overwritten: a folder with files is refused before any training,
    and the command line says so in one line with status 2."""
    (tmp_path / "model.zip").write_bytes(b"a user's policy")
    with pytest.raises(ConfigError, match=r"--out .*: not empty"):
        train(tmp_path, minutes=0.1, n_envs=1, seed=0, validation=0)
    assert main(["--out", str(tmp_path), "--minutes", "0.1"]) == 2
    assert (tmp_path / "model.zip").read_bytes() == b"a user's policy"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["model.zip"]
