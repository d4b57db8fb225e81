"""Recording is a wrapper: ``RecordEpisodes`` records a user's own env (a tiny Gymnasium env
offering ``pic4rl_bridge.recording.Recordable``, no ROS graph, no simulator) to bags that
``pic4rl_metrics`` judges, with the env unaware of bags; ``NavEnv`` imports nothing of the
recorder, and ``gymnasium.make`` wraps it when ``record.enabled`` asks.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
import pytest
from import_helpers import imports
from test_recorder import (
    DT_NS,
    FACTS,
    LENGTH,
    T0_NS,
    _raw,
    _twist,
    goal_pose,
    odometry,
    read_bag,
    scan,
)

import pic4rl_bridge
from pic4rl_bridge.errors import RecorderError
from pic4rl_bridge.recording import RecordEpisodes
from pic4rl_metrics import compute, read_episode
from pic4rl_metrics.contract import EpisodeFacts, Outcome, parse_facts

ROOT = Path(__file__).resolve().parents[2]


class LineEnv(gym.Env[np.ndarray, np.ndarray]):
    """A robot on a line: the action is its speed (m/s), the goal is 2 m ahead. It offers a
    recorder its messages (``tap``), their clock (``stamp_ns``) and its facts; it knows no bag."""

    observation_space = gym.spaces.Box(-10.0, 10.0, (1,), np.float32)
    action_space = gym.spaces.Box(0.0, 1.0, (1,), np.float32)

    def __init__(self, *, goal: bool = True) -> None:
        self.tap: Any = None
        self.stamp_ns, self.x, self.goal = T0_NS, 0.0, goal

    def _send(self, vx: float) -> None:
        if self.tap is not None:
            for topic in ("/ground_truth", "/odom"):
                self.tap(odometry(topic, self.stamp_ns, self.x, vx))
            self.tap(scan(self.stamp_ns))

    def reset(self, *, seed: int | None = None,
              options: dict[str, Any] | None = None) -> tuple[np.ndarray, dict[str, Any]]:
        super().reset(seed=seed)
        self.stamp_ns, self.x = T0_NS, 0.0
        if self.tap is not None:
            self.tap(goal_pose(self.stamp_ns, 2.0, 0.0))
        self._send(0.0)
        return np.array([self.x], np.float32), {}

    def step(self, action: np.ndarray) -> tuple[np.ndarray, float, bool, bool, dict[str, Any]]:
        vx = float(action[0])
        self.stamp_ns += DT_NS
        self.x += vx * DT_NS * 1e-9
        if self.tap is not None:
            self.tap(_raw("/cmd_vel", _twist(vx), self.stamp_ns))
        self._send(vx)
        done = self.x >= 2.0 - 1e-9
        info = {"outcome": "goal"} if done else {}
        return np.array([self.x], np.float32), 1.0 if done else 0.0, done, False, info

    def episode_facts(self) -> EpisodeFacts:
        facts = {**FACTS, "goal": FACTS["goal"] if self.goal else None}
        return parse_facts(facts, source="LineEnv")[0]


def drive(env: gym.Env, steps: int) -> dict[str, Any]:
    env.reset(seed=0)
    info: dict[str, Any] = {}
    for _ in range(steps):
        _, _, terminated, truncated, info = env.step(
            np.full(env.action_space.shape, 0.5, np.float32))
        if terminated or truncated:
            break
    return info


def test_a_users_env_wrapped_gives_bags_the_metrics_judge(tmp_path: Path) -> None:
    """0.5 m/s for 4 s to the goal 2 m ahead: success, 2 m, the facts named after the bag."""
    env = RecordEpisodes(LineEnv(), tmp_path, "mine", config={"speed_mps": 0.5})
    try:
        assert drive(env, 100)["outcome"] == "goal"
        drive(env, 3)  # cut short by the close: its bag has no outcome
    finally:
        env.close()
    first, second = tmp_path / "mine" / "episode_0000", tmp_path / "mine" / "episode_0001"
    row = compute([first]).frame.iloc[0]
    assert row["error"] == "" and row["outcome"] == "goal" and row["success"] == 1.0
    assert row["path_length_m"] == pytest.approx(2.0, abs=LENGTH) and row["n_poses"] == 41
    facts = read_episode(first).facts
    assert (facts.run, facts.episode, facts.seed) == ("mine", "episode_0000", 7)
    assert facts.outcome_stamp_ns == T0_NS + 40 * DT_NS
    messages, custom, _ = read_bag(second)
    assert "outcome" not in custom and len(messages["/odom"]) == 4
    assert (tmp_path / "mine" / "config.yaml").read_text() == "speed_mps: 0.5\n"
    assert env.env.tap is None  # the env is left as it was found


def test_an_abort_closes_the_bag_with_its_reason_and_a_goalless_bag_has_no_goal(
        tmp_path: Path) -> None:
    env = RecordEpisodes(LineEnv(goal=False), tmp_path, "r")
    try:
        drive(env, 5)
        env.abort("the policy raised")
    finally:
        env.close()
    messages, custom, _ = read_bag(tmp_path / "r" / "episode_0000")
    assert custom["outcome"] == "aborted" and custom["end_reason"] == "the policy raised"
    assert "/goal_pose" not in messages and len(messages["/cmd_vel"]) == 5


def test_an_env_without_the_interface_or_an_outcome_is_refused_in_one_line(
        tmp_path: Path) -> None:
    with pytest.raises(RecorderError, match=r"^CartPoleEnv: cannot be recorded: it has no "
                                            r"'tap'; expected pic4rl_bridge.recording"):
        RecordEpisodes(gym.make("CartPole-v1"), tmp_path, "r")

    class Silent(LineEnv):
        def step(self, action: np.ndarray) -> tuple[Any, float, bool, bool, dict[str, Any]]:
            obs, reward, terminated, truncated, _ = super().step(action)
            return obs, reward, terminated, truncated, {}

    env = RecordEpisodes(Silent(), tmp_path, "r")
    with pytest.raises(RecorderError, match=r"^info\['outcome'\]: None at the episode's end"):
        drive(env, 100)
    env.close()


def test_the_env_imports_nothing_of_the_recorder() -> None:
    path = ROOT / "pic4rl_bridge" / "env.py"
    found = {base for base, _, _ in imports(path, "pic4rl_bridge.env")}
    assert "pic4rl_bridge.env_facts" in found
    assert not found & {"pic4rl_bridge.recorder", "pic4rl_bridge.recording"}, found


def chain(env: gym.Env) -> list[type]:
    """The types of ``env``'s wrappers, outermost first, then the env's."""
    found = [type(env)]
    while isinstance(env, gym.Wrapper):
        env = env.env
        found.append(type(env))
    return found


def test_gymnasium_make_records_when_the_config_asks(tmp_path: Path) -> None:
    env_id = next(iter(pic4rl_bridge.ENV_IDS))
    config = ROOT / "config" / "env_goto_lidar.yaml"
    plain = gym.make(env_id, config=config, overrides={"episode_max_steps": 2})
    plain.close()
    assert RecordEpisodes not in chain(plain) and not (tmp_path / "g").exists()
    env = gym.make(env_id, config=config, overrides={
        "episode_max_steps": 2, "record.enabled": True, "record.bags_dir": str(tmp_path),
        "record.run": "g"})
    try:
        assert RecordEpisodes in chain(env)
        drive(env, 2)
    finally:
        env.close()
    facts = read_episode(tmp_path / "g" / "episode_0000").facts
    assert facts.outcome is Outcome.TIMEOUT and (facts.run, facts.episode) == ("g",
                                                                               "episode_0000")
    assert (tmp_path / "g" / "config.yaml").is_file()
