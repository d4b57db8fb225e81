"""The trainer's configuration: typed, frozen, from the ``trainer:`` section of a params file.

A training file holds the three nodes' sections side by side, as ``--params-file`` expects::

    sim:      {ros__parameters: {robot: jackal, world: indoor, ...}}      # pic4rl-sim
    nav_env:  {ros__parameters: {task: goToPose, sensor: lidar, ...}}     # the env
    trainer:  {ros__parameters: {algorithm: td3, max_steps: 100000, ...}} # this module

Names are dotted as in ROS (``epsilon.decay``); every key is checked with a "did you mean".
RL-Zoo-style ``key:value`` overrides from the command line land here too.
"""

from __future__ import annotations

import math
import os
import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import yaml

from pic4rl_bridge.config import (
    EnvConfig,
    dataclass_from_params,
    dataclass_params,
    env_config_from_params,
    node_section,
    read_params_file,
)
from pic4rl_bridge.errors import ConfigError, require
from pic4rl_sim.engine.sampling import PAIR_KINDS

TRAINER_NODE = "trainer"
ENV_NODE = "nav_env"
SIM_NODE = "sim"
OFF_POLICY = ("ddpg", "td3", "sac", "tqc")
ALGORITHM_NAMES = (*OFF_POLICY, "ppo")


@dataclass(frozen=True)
class PolicyConfig:
    """Network sizes: a dense MLP on LiDAR vectors; a CNN plus the goal vector on depth."""

    net_arch: tuple[int, ...] = (256, 256)  # actor (pi) hidden layers
    critic_arch: tuple[int, ...] = (256, 256)  # critic (qf, PPO's vf) hidden layers
    cnn_channels: tuple[int, ...] = (16, 32, 32)  # depth CNN: one conv layer each
    cnn_features: int = 128  # the CNN's output size, concatenated with the goal vector
    share_features_extractor: bool = False  # off-policy: actor and critic share the CNN
    activation: str = "relu"  # relu | tanh | elu
    log_std_init: float = 0.0  # ppo: the Gaussian's initial log std (0: std 1 action unit)


@dataclass(frozen=True)
class EpsilonConfig:
    """The paper's ε-greedy exploration: after ``learning_starts``, a uniform random action
    with probability ``ε_t = max(min, initial · decay^t)``, t the env steps since then."""

    initial: float = 0.0  # 0 disables it
    decay: float = 0.9999
    min: float = 0.0


@dataclass(frozen=True)
class EvalConfig:
    """Periodic evaluation on an in-process copy of the env (never the training sim), on
    sampled pairs of ``pair_kind`` (never the training pairs), due after ``interval_steps``
    env steps or ``interval_s`` seconds of training, whichever comes first."""

    interval_steps: int = 0  # 0: not by steps
    interval_s: float = 0.0  # seconds of training (evaluations excluded); 0: not by time
    episodes: int = 5
    seed: int = 1000  # the same episodes at every evaluation
    pair_kind: str = "paper"  # the eval env's episodes.pair_kind

    @property
    def enabled(self) -> bool:
        return self.interval_steps > 0 or self.interval_s > 0


@dataclass(frozen=True)
class CurriculumConfig:
    """Pairs that widen as the agent succeeds (Arena-rosnav's staged training): stage i draws
    pairs ``min_distance_m[i]``-``max_distance_m[i]`` apart with a detour of at most
    ``max_detour[i]``; the next stage follows when the success rate of the stage's last
    ``window`` episodes reaches ``up``, the previous one when it falls to ``down``."""

    min_distance_m: tuple[float, ...] = ()  # empty: no curriculum (the env's episodes)
    max_distance_m: tuple[float, ...] = ()
    max_detour: tuple[float, ...] = ()
    up: float = 0.8
    down: float = 0.3
    window: int = 50

    @property
    def enabled(self) -> bool:
        return bool(self.min_distance_m)


@dataclass(frozen=True)
class CheckpointConfig:
    interval_steps: int = 10_000  # 0: only the final model
    replay_buffer: bool = True  # saved beside each checkpoint, so a resume keeps experience


@dataclass(frozen=True)
class PpoConfig:
    n_steps: int = 1024  # rollout length per env
    n_epochs: int = 10
    ent_coef: float = 0.0
    gae_lambda: float = 0.95
    clip_range: float = 0.2


@dataclass(frozen=True)
class TrainConfig:
    """Everything ``pic4rl-train`` needs besides the env's and the sim's sections."""

    algorithm: str = "td3"  # ddpg | td3 | sac | ppo | tqc (sb3-contrib)
    run: str = ""  # runs_dir/<run>; empty: <algorithm>_<sensor>
    runs_dir: str = "runs"
    seed: int = 0
    max_steps: int = 100_000  # env steps in all (SB3's total_timesteps)
    max_wall_s: float = 0.0  # also stop after this many seconds of the session; 0: no limit
    n_envs: int = 1  # > 1: one sim each, in vec_env
    vec_env: str = "subproc"  # n_envs > 1: subproc (a process each) | dummy (all in this one)
    device: str = "cpu"  # torch device: cpu | cuda | auto
    torch_threads: int = 1  # per process; 0: torch's default
    learning_rate: float = 3e-4
    gamma: float = 0.99
    batch_size: int = 256
    buffer_size: int = 200_000
    learning_starts: int = 2_000  # warm-up: uniformly random actions
    train_freq: int = 1  # env steps (per env) between updates
    gradient_steps: int = 1
    tau: float = 0.005
    reward_scale: float = 1.0  # learner's reward = this x env's (logs, bags keep the env's)
    action_noise_std: float = 0.1  # ddpg/td3 Gaussian noise, in normalised action units
    policy: PolicyConfig = field(default_factory=PolicyConfig)
    epsilon: EpsilonConfig = field(default_factory=EpsilonConfig)
    ppo: PpoConfig = field(default_factory=PpoConfig)
    eval: EvalConfig = field(default_factory=EvalConfig)
    checkpoint: CheckpointConfig = field(default_factory=CheckpointConfig)
    curriculum: CurriculumConfig = field(default_factory=CurriculumConfig)
    tensorboard: bool = True
    reward_window: int = 50  # episodes in the reward curve's moving average

    def __post_init__(self) -> None:
        require(self.algorithm in ALGORITHM_NAMES, "algorithm", self.algorithm,
                f"one of {', '.join(ALGORITHM_NAMES)}")
        require(self.vec_env in ("subproc", "dummy"), "vec_env", self.vec_env,
                "subproc or dummy")
        require(self.device in ("cpu", "cuda", "auto"), "device", self.device,
                "cpu, cuda or auto")
        require(self.policy.activation in ("relu", "tanh", "elu"), "policy.activation",
                self.policy.activation, "relu, tanh or elu")
        positive = {"max_steps": self.max_steps, "n_envs": self.n_envs,
                    "batch_size": self.batch_size, "buffer_size": self.buffer_size,
                    "train_freq": self.train_freq, "gradient_steps": self.gradient_steps,
                    "learning_rate": self.learning_rate, "reward_scale": self.reward_scale,
                    "eval.episodes": self.eval.episodes,
                    "reward_window": self.reward_window, "policy.cnn_features":
                    self.policy.cnn_features, "ppo.n_steps": self.ppo.n_steps,
                    "ppo.n_epochs": self.ppo.n_epochs}
        for key, value in positive.items():
            require(math.isfinite(value) and value > 0, key, value, "a positive number")
        non_negative = {"learning_starts": self.learning_starts,
                        "torch_threads": self.torch_threads,
                        "action_noise_std": self.action_noise_std,
                        "eval.interval_steps": self.eval.interval_steps,
                        "eval.interval_s": self.eval.interval_s,
                        "max_wall_s": self.max_wall_s,
                        "checkpoint.interval_steps": self.checkpoint.interval_steps}
        for key, value in non_negative.items():
            require(math.isfinite(value) and value >= 0, key, value, "a number >= 0")
        for key, value in {"gamma": self.gamma, "tau": self.tau}.items():
            require(0 < value <= 1, key, value, "a number in (0, 1]")
        require(self.eval.pair_kind in PAIR_KINDS, "eval.pair_kind", self.eval.pair_kind,
                f"one of {', '.join(PAIR_KINDS)}")
        eps = self.epsilon
        require(0 <= eps.initial <= 1, "epsilon.initial", eps.initial, "a probability in [0, 1]")
        require(0 < eps.decay <= 1, "epsilon.decay", eps.decay, "a factor in (0, 1]")
        require(0 <= eps.min <= 1, "epsilon.min", eps.min, "a probability in [0, 1]")
        require(self.algorithm != "ppo" or eps.initial == 0, "epsilon.initial", eps.initial,
                "0 for ppo (ε-greedy replaces actions, which an on-policy algorithm cannot "
                "learn from; PPO explores through its stochastic policy)")
        cur = self.curriculum
        stages = len(cur.min_distance_m)
        require(len(cur.max_distance_m) == stages and len(cur.max_detour) == stages,
                "curriculum.max_distance_m", list(cur.max_distance_m),
                f"as many stages as curriculum.min_distance_m ({stages}), and so many "
                "curriculum.max_detour")
        for low, high, detour in zip(cur.min_distance_m, cur.max_distance_m, cur.max_detour):
            require(0 <= low < high, "curriculum.max_distance_m", list(cur.max_distance_m),
                    "distances (m) above each stage's min_distance_m")
            require(detour >= 1, "curriculum.max_detour", list(cur.max_detour),
                    "ratios >= 1 (shortest path / straight line)")
        require(0 <= cur.down < cur.up <= 1, "curriculum.up", cur.up,
                f"a success rate in (curriculum.down={cur.down}, 1]")
        require(cur.window > 0, "curriculum.window", cur.window, "a positive number of episodes")
        for key in ("policy.net_arch", "policy.critic_arch", "policy.cnn_channels"):
            sizes = getattr(self.policy, key.split(".")[1])
            require(len(sizes) > 0 and all(s > 0 for s in sizes), key, list(sizes),
                    "a non-empty list of positive layer sizes")

    @property
    def off_policy(self) -> bool:
        return self.algorithm in OFF_POLICY

    def to_params(self) -> dict[str, Any]:
        return dataclass_params(self)

    def replace(self, **overrides: Any) -> TrainConfig:
        """A copy with dotted ``overrides`` applied (``{"epsilon.decay": 0.999}``)."""
        return train_config_from_params({**self.to_params(), **overrides})


def train_config_from_params(params: Mapping[str, Any]) -> TrainConfig:
    return dataclass_from_params(TrainConfig, params, where=f"{TRAINER_NODE} parameters")


@dataclass(frozen=True)
class RunConfig:
    """A training or testing run's three sections, as read from its params files."""

    train: TrainConfig
    env: EnvConfig
    sources: tuple[str, ...] = ()  # the params files, in order

    @property
    def name(self) -> str:
        return self.train.run or f"{self.train.algorithm}_{self.env.sensor}"

    def to_yaml(self) -> str:
        """The params file of this run (all three sections): ``pic4rl-train`` and
        ``pic4rl-test`` read it back as it is, and ``pic4rl-sim`` reads its ``sim:``."""
        sections = {SIM_NODE: dict(self.env.sim_params), ENV_NODE: self.env.to_params(),
                    TRAINER_NODE: self.train.to_params()}
        doc = {name: {"ros__parameters": params} for name, params in sections.items()}
        return yaml.safe_dump(doc, sort_keys=False)


def ros_domain(env: EnvConfig | None) -> str:
    """The ROS domain an env talks in: its ``ros.domain_id``, else ``ROS_DOMAIN_ID`` (or 0)."""
    if env is not None and env.ros.domain_id >= 0:
        return str(env.ros.domain_id)
    return os.environ.get("ROS_DOMAIN_ID", "0")


_FLOAT = re.compile(r"^[-+]?(\d+\.?\d*|\.\d+)[eE][-+]?\d+$")


def yaml_value(text: str) -> Any:
    """A command-line value as ROS reads it: YAML, plus ``1e-3`` as a number (YAML 1.1 wants
    ``1.0e-3``; RL Zoo users write ``1e-3``)."""
    value = yaml.safe_load(text) if text.strip() else ""
    if isinstance(value, str) and _FLOAT.match(value.strip()):
        return float(value)
    return value


def parse_overrides(items: Sequence[str], *, flag: str) -> dict[str, Any]:
    """RL-Zoo-style ``key:value`` items (values read as YAML: ``0.001``, ``[64, 64]``, ``sac``)
    as a dict of dotted names."""
    out: dict[str, Any] = {}
    for item in items:
        key, sep, text = item.partition(":")
        if not sep or not key.strip():
            raise ConfigError(f"{flag} {item!r}: expected key:value (e.g. learning_rate:0.001)")
        try:
            out[key.strip()] = yaml_value(text)
        except yaml.YAMLError as err:
            raise ConfigError(f"{flag} {item!r}: the value is not valid YAML: {err}") from err
    return out


def load_run_config(paths: Sequence[str | Path], *, train: Mapping[str, Any] | None = None,
                    env: Mapping[str, Any] | None = None,
                    sim: Mapping[str, Any] | None = None) -> RunConfig:
    """The ``trainer``, ``nav_env`` and ``sim`` sections of ``paths`` (later files win, key by
    key, as ROS merges several ``--params-file``), then dotted overrides per section."""
    merged: dict[str, dict[str, Any]] = {TRAINER_NODE: {}, ENV_NODE: {}, SIM_NODE: {}}
    for path in paths:
        data = read_params_file(path)
        sections = {node: node_section(data, node, source=str(path)) for node in merged}
        if sections[SIM_NODE] is None and "/**" in data:  # a sim-only file (sim_*.yaml)
            sections[SIM_NODE] = node_section({"/**": data["/**"]}, "/**", source=str(path))
        if all(section is None for section in sections.values()):
            raise ConfigError(f"{path}: no section for {', '.join(merged)} (expected "
                              f"'{TRAINER_NODE}: ros__parameters: ...' and so on)")
        pairs = (sections[ENV_NODE] or {}).get("episodes.file")
        if isinstance(pairs, str) and pairs:
            sections[ENV_NODE]["episodes.file"] = beside(pairs, Path(path))  # type: ignore[index]
        for node, section in sections.items():
            merged[node].update(section or {})
    merged[TRAINER_NODE].update(train or {})
    merged[ENV_NODE].update(env or {})
    merged[SIM_NODE].update(sim or {})
    where = ", ".join(str(p) for p in paths) or "command line"
    try:
        train_config = train_config_from_params(merged[TRAINER_NODE])
        env_config = env_config_from_params(merged[ENV_NODE], sim_params=merged[SIM_NODE])
    except ConfigError as err:
        raise ConfigError(f"{where}: {err}") from err
    return RunConfig(train_config, env_config, tuple(str(p) for p in paths))


def beside(file: str, params_file: Path) -> str:
    """A relative path named in a params file: as given when it exists from the working
    directory (ROS's rule), else the file beside the params file, so that a shipped config
    works from any directory."""
    if Path(file).is_absolute() or Path(file).exists():
        return file
    beside = params_file.parent / file
    return str(beside.resolve()) if beside.exists() else file
