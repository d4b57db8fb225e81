"""The trainer's configuration: typed, frozen, from the ``trainer:`` section of a params file.

A training file holds the three nodes' sections side by side (``pic4rl_base.params_file``).
Each field carries its description, unit and range (``pic4rl_base.schema``); names are dotted
as in ROS (``epsilon.decay``); every key is checked with a "did you mean". Command-line
overrides (``pic4rl_agents.runs.overrides``) are applied over the files by ``load_run_config``.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from pic4rl_agents.models.algorithm_table import ALGORITHM_TABLE
from pic4rl_base import params_file
from pic4rl_base.params_file import ENV_NODE, SIM_NODE, TRAINER_NODE
from pic4rl_base.schema import (NON_NEGATIVE, POSITIVE, PROBABILITY, ParamEnum, Range, check,
                                from_params, param, section, to_params)
from pic4rl_bridge.config import EnvConfig, env_config_from_params
from pic4rl_bridge.errors import ConfigError, require
from pic4rl_bridge.settings.tasks import EXPERT_TASKS
from pic4rl_sim.engine.sampling import PAIR_KINDS, check_pair_filter

#: ``trainer.algorithm``'s choices: the algorithm table's names.
Algorithm = ParamEnum("Algorithm", [(name.upper(), name) for name in ALGORITHM_TABLE],
                      module=__name__, qualname="Algorithm")


class VecEnvKind(ParamEnum):
    SUBPROC = "subproc"
    DUMMY = "dummy"


class Device(ParamEnum):
    CPU = "cpu"
    CUDA = "cuda"
    AUTO = "auto"


class Activation(ParamEnum):
    RELU = "relu"
    TANH = "tanh"
    ELU = "elu"


OFF_POLICY = tuple(name for name, entry in ALGORITHM_TABLE.items() if entry.off_policy)
ALGORITHM_NAMES = tuple(a.value for a in Algorithm)
_CHOICES = " | ".join(name if entry.distribution == "stable-baselines3"
                      else f"{name} ({entry.distribution})"
                      for name, entry in ALGORITHM_TABLE.items())
#: A run's params file sections.
NODES = (TRAINER_NODE, ENV_NODE, SIM_NODE)
Dotted = Mapping[str, Any] | None  # a section's overrides: {"epsilon.decay": 0.999}
_LAYERS = "a non-empty list of positive layer sizes"


@dataclass(frozen=True)
class PolicyConfig:
    """Network sizes: a dense MLP on LiDAR vectors; a CNN plus the goal vector on depth."""

    net_arch: tuple[int, ...] = param((256, 256), doc="actor (pi) hidden layers")
    critic_arch: tuple[int, ...] = param((256, 256), doc="critic (qf, PPO's vf) hidden layers")
    cnn_channels: tuple[int, ...] = param((16, 32, 32), doc="each image's CNN (depth, memory): "
                                          "one conv layer each")
    cnn_features: int = param(128, doc="the CNN's output size, concatenated with the goal "
                              "vector", range=POSITIVE)
    share_features_extractor: bool = param(False, doc="off-policy: actor and critic share the "
                                           "CNN")
    activation: Activation = param(Activation.RELU, doc="relu | tanh | elu")
    log_std_init: float = param(0.0, doc="ppo: the Gaussian's initial log std (0: std 1 action "
                                "unit)")


@dataclass(frozen=True)
class EpsilonConfig:
    """The paper's ε-greedy exploration: after ``learning_starts``, a uniform random action
    with probability ``ε_t = max(min, initial · decay^t)``, t the env steps since then."""

    initial: float = param(0.0, doc="0 disables it", range=PROBABILITY)
    decay: float = param(0.9999, doc="factor per env step", range=Range(0.0, 1.0, lo_open=True))
    min: float = param(0.0, doc="the floor of ε", range=PROBABILITY)


@dataclass(frozen=True)
class EvalConfig:
    """Periodic evaluation on an in-process copy of the env (never the training sim), on
    sampled pairs of ``pair_kind`` (never the training pairs), due after ``interval_steps``
    env steps or ``interval_s`` seconds of training, whichever comes first."""

    interval_steps: int = param(0, doc="0: not by steps", range=NON_NEGATIVE)
    interval_s: float = param(0.0, doc="seconds of training (evaluations excluded); 0: not by "
                              "time", unit="s", range=NON_NEGATIVE)
    episodes: int = param(5, doc="episodes per evaluation", range=POSITIVE)
    seed: int = param(1000, doc="the same episodes at every evaluation")
    pair_kind: str = param("paper", doc="the eval env's episodes.pair_kind",
                           choices=tuple(PAIR_KINDS))
    world_variants: str = param("", doc="the eval env's episodes.world_variants, walked in order "
                                "(held-out worlds); empty: the sim's world_variant")
    video_episodes: int = param(0, doc="videos of each evaluation's first episodes, driven "
                                "again with rendering on: MP4s in <run>/videos/, GIFs in "
                                "TensorBoard; 0: none", range=NON_NEGATIVE)

    @property
    def enabled(self) -> bool:
        return self.interval_steps > 0 or self.interval_s > 0


@dataclass(frozen=True)
class CurriculumConfig:
    """Pairs that widen as the agent succeeds (Arena-rosnav's staged training): stage i draws
    pairs ``min_distance_m[i]``-``max_distance_m[i]`` apart with a detour of at most
    ``max_detour[i]``; the next stage follows when the success rate of the stage's last
    ``window`` episodes reaches ``up``, the previous one when it falls to ``down``."""

    min_distance_m: tuple[float, ...] = param((), doc="each stage's least start-goal "
                                              "distance (m); empty: no curriculum (the env's "
                                              "episodes)")
    max_distance_m: tuple[float, ...] = param((), doc="each stage's greatest start-goal "
                                              "distance (m)")
    max_detour: tuple[float, ...] = param((), doc="each stage's greatest shortest path / "
                                          "straight line")
    up: float = param(0.8, doc="success rate that moves to the next stage")
    down: float = param(0.3, doc="success rate that moves back a stage")
    window: int = param(50, doc="the stage's last episodes the rates are taken over")

    @property
    def enabled(self) -> bool:
        return bool(self.min_distance_m)


@dataclass(frozen=True)
class CheckpointConfig:
    interval_steps: int = param(10_000, doc="0: only the final model", range=NON_NEGATIVE)
    replay_buffer: bool = param(True, doc="saved beside each checkpoint, so a resume keeps "
                                "experience")


@dataclass(frozen=True)
class ImitationConfig:
    """Expert-guided training before RL (``pic4rl_agents.training.imitation``): cloning
    ``bc_steps`` env steps the expert drives, then ``dagger_rounds`` rounds of DAgger (the
    student drives ``dagger_steps`` env steps, the expert labels every state, the labels are
    aggregated and the actor regressed on all of them), then RL from the imitation-initialised
    actor for the rest of ``max_steps`` / ``max_wall_s``, after ``critic_warmup_steps``
    gradient steps on the critic alone, with ``rl_gradient_steps`` of regression on the labels
    per 1000 env steps decaying to none over ``rl_decay_steps``. Every env step of imitation
    counts in ``max_steps``, and the expert's time in every clock."""

    enabled: bool = param(False, doc=f"imitation before RL ({', '.join(OFF_POLICY)})")
    expert: str = param("planner", doc="the expert that labels states, one of its task's "
                        "experts in the task table (pic4rl_bridge.settings.tasks; "
                        "docs/agents.md, imitation)", choices=tuple(EXPERT_TASKS))
    bc_steps: int = param(5_000, doc="env steps driven by the expert (behaviour cloning's "
                          "data)", range=NON_NEGATIVE)
    dagger_rounds: int = param(10, doc="DAgger rounds after behaviour cloning",
                               range=NON_NEGATIVE)
    dagger_steps: int = param(5_000, doc="env steps driven by the student per round",
                              range=POSITIVE)
    gradient_steps: int = param(2_000, doc="actor regression steps after each round (and after "
                                "behaviour cloning)", range=POSITIVE)
    learning_rate: float = param(1e-3, doc="the regression's Adam step size", range=POSITIVE)
    replay: bool = param(True, doc="off-policy: imitation's transitions (with their rewards) "
                         "go to the replay buffer and stay there for RL")
    critic_warmup_steps: int = param(5_000, doc="before RL: critic gradient steps on the "
                                     "replay buffer with the actor frozen", range=NON_NEGATIVE)
    rl_gradient_steps: int = param(0, doc="during RL: actor regression steps on the labels "
                                   "per 1000 env steps, at RL's start (a behaviour-cloning term "
                                   "that keeps the actor near the expert while the critic is "
                                   "new)", range=NON_NEGATIVE)
    rl_decay_steps: int = param(100_000, doc="RL env steps over which rl_gradient_steps falls "
                                "linearly to 0", range=POSITIVE)


@dataclass(frozen=True)
class PpoConfig:
    n_steps: int = param(1024, doc="rollout length per env", range=POSITIVE)
    n_epochs: int = param(10, doc="passes over each rollout", range=POSITIVE)
    ent_coef: float = param(0.0, doc="entropy bonus")
    gae_lambda: float = param(0.95, doc="GAE's λ")
    clip_range: float = param(0.2, doc="PPO's clipping of the policy ratio")


@dataclass(frozen=True)
class TrainConfig:
    """Everything ``pic4rl-train`` needs besides the env's and the sim's sections."""

    algorithm: Algorithm = param(Algorithm("td3"), doc=_CHOICES)
    run: str = param("", doc="runs_dir/<run>; empty: <algorithm>_<sensor>")
    runs_dir: str = param("runs", doc="where runs go")
    seed: int = param(0, doc="seed of the learner and the envs")
    trained_agent: str = param("", doc="a new run starts from this trained model's networks (a "
                               "model .zip, or a folder's model.zip; relative: from the working "
                               "directory, else beside the params file; "
                               "RL Zoo's --trained-agent) with this config's hyperparameters and "
                               "an empty replay buffer; a resume ignores it")
    max_steps: int = param(100_000, doc="env steps in all (SB3's total_timesteps)",
                           range=POSITIVE)
    max_wall_s: float = param(0.0, doc="also stop after this many seconds of the session; 0: "
                              "no limit", unit="s", range=NON_NEGATIVE)
    n_envs: int = param(1, doc="> 1: one sim each, in vec_env", range=POSITIVE)
    vec_env: VecEnvKind = param(VecEnvKind.SUBPROC, doc="n_envs > 1: subproc (a process each) | "
                                "dummy (all in this one)")
    device: Device = param(Device.CPU, doc="torch device: cpu | cuda | auto")
    torch_threads: int = param(1, doc="per process; 0: torch's default", range=NON_NEGATIVE)
    learning_rate: float = param(3e-4, doc="the optimisers' step size", range=POSITIVE)
    gamma: float = param(0.99, doc="discount factor", range=Range(0.0, 1.0, lo_open=True))
    batch_size: int = param(256, doc="samples per gradient step", range=POSITIVE)
    buffer_size: int = param(200_000, doc="replay buffer size (off-policy)", range=POSITIVE)
    learning_starts: int = param(2_000, doc="warm-up: uniformly random actions",
                                 range=NON_NEGATIVE)
    train_freq: int = param(1, doc="env steps (per env) between updates", range=POSITIVE)
    gradient_steps: int = param(1, doc="gradient steps per update", range=POSITIVE)
    tau: float = param(0.005, doc="target networks' soft-update factor",
                       range=Range(0.0, 1.0, lo_open=True))
    reward_scale: float = param(1.0, doc="learner's reward = this x env's (logs, bags keep the "
                                "env's)", range=POSITIVE)
    action_noise_std: float = param(0.1, doc="ddpg/td3 Gaussian noise, in normalised action "
                                    "units", range=NON_NEGATIVE)
    ent_coef: str = param("auto", doc="sac/tqc entropy coefficient: auto (learned, from 1), "
                          "auto_<x> (learned, from x) or a number (fixed)")
    policy: PolicyConfig = section(PolicyConfig)
    epsilon: EpsilonConfig = section(EpsilonConfig)
    ppo: PpoConfig = section(PpoConfig)
    eval: EvalConfig = section(EvalConfig)
    checkpoint: CheckpointConfig = section(CheckpointConfig)
    curriculum: CurriculumConfig = section(CurriculumConfig)
    imitation: ImitationConfig = section(ImitationConfig)
    tensorboard: bool = param(True, doc="write TensorBoard logs")
    reward_window: int = param(50, doc="episodes in the reward curve's moving average",
                               range=POSITIVE)

    def __post_init__(self) -> None:
        check(self)
        eps = self.epsilon
        require(self.off_policy or eps.initial == 0, "epsilon.initial", eps.initial,
                f"0 for {self.algorithm} (ε-greedy replaces actions, which an on-policy "
                "algorithm cannot learn from; PPO explores through its stochastic policy)")
        cur = self.curriculum
        stages = len(cur.min_distance_m)
        require(len(cur.max_distance_m) == stages and len(cur.max_detour) == stages,
                "curriculum.max_distance_m", list(cur.max_distance_m),
                f"as many stages as curriculum.min_distance_m ({stages}), and so many "
                "curriculum.max_detour")
        for low, high, detour in zip(cur.min_distance_m, cur.max_distance_m, cur.max_detour):
            check_pair_filter(low, high, detour, prefix="curriculum.")
        require(not self.imitation.enabled or self.off_policy, "imitation.enabled", True,
                f"false for {self.algorithm} (imitation initialises an off-policy actor: "
                f"{', '.join(OFF_POLICY)})")
        require(0 <= cur.down < cur.up <= 1, "curriculum.up", cur.up,
                f"a success rate in (curriculum.down={cur.down}, 1]")
        require(cur.window > 0, "curriculum.window", cur.window, "a positive number of episodes")
        require(_valid_ent_coef(self.ent_coef), "ent_coef", self.ent_coef,
                "auto, auto_<x> or a number > 0 (SB3's ent_coef)")
        for key in ("policy.net_arch", "policy.critic_arch", "policy.cnn_channels"):
            sizes = getattr(self.policy, key.split(".")[1])
            require(len(sizes) > 0 and all(s > 0 for s in sizes), key, list(sizes), _LAYERS)

    @property
    def off_policy(self) -> bool:
        return self.algorithm in OFF_POLICY

    def to_params(self) -> dict[str, Any]:
        return to_params(self)

    def replace(self, **overrides: Any) -> TrainConfig:
        """A copy with dotted ``overrides`` applied (``{"epsilon.decay": 0.999}``)."""
        return train_config_from_params({**self.to_params(), **overrides})


def _valid_ent_coef(value: str) -> bool:
    text = value[len("auto_"):] if value.startswith("auto_") else value
    if text == "auto":
        return True
    try:
        return float(text) > 0
    except ValueError:
        return False


def train_config_from_params(params: Mapping[str, Any]) -> TrainConfig:
    return from_params(TrainConfig, params, where=f"{TRAINER_NODE} parameters")


@dataclass(frozen=True)
class RunConfig:
    """A training or testing run's three sections, as read from its params files."""

    train: TrainConfig
    env: EnvConfig
    sources: tuple[str, ...] = ()  # the params files, in order
    overridden: bool = False  # command-line overrides were applied over them

    @property
    def name(self) -> str:
        return self.train.run or f"{self.train.algorithm}_{self.env.sensor_label}"

    @property
    def origin(self) -> str:
        """Its sensor and sources, for messages: ``sensor lidar, from a.yaml + command line``."""
        parts = [*self.sources, *(["command line"] if self.overridden else [])]
        return f"sensor {self.env.sensor_label}, from {' + '.join(parts) or 'the defaults'}"

    def sections(self) -> dict[str, dict[str, Any]]:  # as params_file.load gives them
        return {SIM_NODE: dict(self.env.sim_params), ENV_NODE: self.env.to_params(),
                TRAINER_NODE: self.train.to_params()}

    def to_yaml(self) -> str:
        """The params file of this run (all three sections): ``pic4rl-train`` and
        ``pic4rl-test`` read it back as it is, and ``pic4rl-sim`` reads its ``sim:``."""
        return params_file.dump(self.sections())

    def replace(self, *, train: Dotted = None, env: Dotted = None,
                sim: Dotted = None) -> RunConfig:
        """A copy with dotted overrides per section, by ``load_run_config``'s rule."""
        return run_config(self.sections(), self.sources, train=train, env=env, sim=sim,
                          overridden=self.overridden)


def load_run_config(paths: Sequence[str | Path], *, train: Dotted = None, env: Dotted = None,
                    sim: Dotted = None) -> RunConfig:
    """The ``trainer``, ``nav_env`` and ``sim`` sections of ``paths`` (later files win, key by
    key, as ROS merges several ``--params-file``), then dotted overrides per section (checked
    by the caller with ``check_overrides``, which names their flags)."""
    return run_config(params_file.load(paths, NODES), tuple(str(p) for p in paths),
                      train=train, env=env, sim=sim)


def run_config(sections: Mapping[str, Mapping[str, Any]], sources: Sequence[str] = (), *,
               train: Dotted = None, env: Dotted = None, sim: Dotted = None,
               overridden: bool | None = None) -> RunConfig:
    """The typed run of flat ``sections`` (read once) and dotted overrides per section."""
    overridden = bool(train or env or sim) if overridden is None else overridden
    overrides = {TRAINER_NODE: train or {}, ENV_NODE: env or {}, SIM_NODE: sim or {}}
    merged = params_file.merge({node: {} for node in NODES}, sections, overrides)
    where = " + ".join([*sources, *(["command line"] if overridden else [])])
    try:
        train_config = train_config_from_params(merged[TRAINER_NODE])
        env_config = env_config_from_params(merged[ENV_NODE], sim_params=merged[SIM_NODE])
    except ConfigError as err:
        raise ConfigError(f"{where or 'command line'}: {err}") from err
    return RunConfig(train_config, env_config, tuple(sources), overridden)
