"""The training and testing envs: ``NavEnv`` in SB3's ``Monitor``, vectorised.

One env lives in the trainer's process (the paper's training(env(Node)) shape: through ROS it
uses the trainer's node); ``n_envs > 1`` run in ``SubprocVecEnv`` workers (or all in this
process, ``vec_env: dummy``), each with its own sim: through ROS the sims sit in namespaces
``env_0``, ``env_1``, ... (``pic4rl-run`` starts them), in process each env builds its own
engine. The config is resolved once, here (``pic4rl_bridge.scenario.Scenario``: the sim's
typed config, the robot, the worlds), and every env is made from that one resolution.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

import gymnasium as gym
from stable_baselines3.common.monitor import Monitor
from stable_baselines3.common.vec_env import DummyVecEnv, SubprocVecEnv, VecEnv

from pic4rl_agents.runs.config import CurriculumConfig, EvalConfig
from pic4rl_base.schema import to_params
from pic4rl_bridge.config import EnvConfig, EpisodesConfig
from pic4rl_bridge.errors import ConfigError
from pic4rl_bridge.recording import make_env
from pic4rl_bridge.scenario import Scenario

from .curriculum import STAGE_KEY, Curriculum

#: The ``info`` key (a monitor column) naming who drove an ended episode, one of ``DRIVERS``.
DRIVER_KEY = "driver"
#: Who drives a training episode: imitation's expert (behaviour cloning), the student's actor
#: in a DAgger round (the expert only labels), RL (the learner and its exploration noise), or
#: ``mixed``: more than one of them, an episode across the change from one phase to the next.
DRIVERS = ("expert", "student", "rl", "mixed")
#: Monitor columns beside r, l, t: what the reward curve, the summary and the progress bar show.
INFO_KEYWORDS = ("is_success", "outcome", DRIVER_KEY)


class Driven(gym.Wrapper):
    """Tags each ended episode's ``info`` with who drove it (``DRIVER_KEY``): the driver set by
    ``set_driver`` (``rl`` until then) for every step of the episode, else ``mixed``.
    Imitation sets it through the vector env (``set_driver``), so the monitor, the reward
    curve and the summary keep the expert's episodes apart from the agent's."""

    def __init__(self, env: gym.Env) -> None:
        super().__init__(env)
        self.driver = "rl"
        self._drove: set[str] = set()

    def set_driver(self, driver: str) -> None:
        if driver not in DRIVERS[:3]:
            raise ValueError(f"driver: {driver!r} is invalid; expected one of "
                             f"{', '.join(DRIVERS[:3])}")
        self.driver = driver

    def reset(self, **kwargs: Any) -> Any:
        self._drove = set()
        return self.env.reset(**kwargs)

    def step(self, action: Any) -> Any:
        obs, reward, terminated, truncated, info = self.env.step(action)
        self._drove.add(self.driver)
        if terminated or truncated:
            info[DRIVER_KEY] = self.driver if len(self._drove) == 1 else "mixed"
        return obs, reward, terminated, truncated, info


def set_driver(env: VecEnv, driver: str) -> None:
    """Who drives ``env``'s (``make_vec_env``'s) episodes from now on: ``expert``,
    ``student`` or ``rl``."""
    env.env_method("set_driver", driver)


def env_namespace(config: EnvConfig, rank: int, n_envs: int) -> str:
    """The ROS namespace of env ``rank``: the config's alone, or ``<it>/env_<rank>``."""
    if n_envs == 1:
        return config.ros.namespace
    return f"{config.ros.namespace.rstrip('/')}/env_{rank}"


def env_for_rank(config: EnvConfig, rank: int, n_envs: int) -> EnvConfig:
    if config.transport != "ros" or n_envs == 1:
        return config
    return config.replace(**{"ros.namespace": env_namespace(config, rank, n_envs)})


def eval_env_config(env: EnvConfig, evaluation: EvalConfig) -> EnvConfig:
    """The evaluation env of a run whose env is ``env``: in process, not recording, and every
    ``episodes.*`` key back at its default (no training pairs, no curriculum) but
    ``episodes.pair_kind`` and ``episodes.world_variants``, the evaluation's (its worlds
    walked in order): pairs sampled from the seed, like a test's."""
    defaults = {f"episodes.{k}": v for k, v in to_params(EpisodesConfig()).items()}
    return env.replace(**{**defaults, "episodes.pair_kind": evaluation.pair_kind,
                          "episodes.world_variants": evaluation.world_variants,
                          "episodes.ordered": bool(evaluation.world_variants),
                          "transport": "inprocess", "record.enabled": False})


def check_no_test_world(scenario: Scenario) -> None:
    """``ConfigError`` when a training or evaluation env would run one of a benchmark's test
    worlds (``HELD_OUT``: BARN's 50, the dynamic BARN's 60; docs/results.md): its
    ``episodes.world_variants``, or without them the sim's ``world_variant`` (both as
    ``scenario`` resolved them)."""
    from pic4rl_sim.engine.worlds.held_out import HELD_OUT

    if scenario.sim is None or scenario.sim.world.kind not in HELD_OUT:
        return
    held = HELD_OUT[scenario.sim.world.kind]
    key, variants = "episodes.world_variants", scenario.variants
    if not variants:
        key, variants = "sim world_variant", (scenario.sim.world.variant,)
    banned = sorted(set(variants) & set(held.variants()))
    if banned:
        raise ConfigError(f"{key}: holds {held.name} test world(s) "
                          f"{', '.join(map(str, banned[:5]))}{' ...' if len(banned) > 5 else ''}"
                          f"; {held.instead}")


def _make(scenario: Scenario, monitor_file: str | None, node: Any = None,
          reward_scale: float = 1.0, curriculum: CurriculumConfig | None = None) -> gym.Env:
    """A monitored ``NavEnv`` (recorded when its ``record.enabled``), its pairs from
    ``curriculum``'s stage when one is given: the monitor logs the env's own (the paper's)
    rewards, and the learner sees them times ``reward_scale`` (rewards of order 1 suit SB3's
    defaults)."""
    env: gym.Env = make_env(scenario, node=node)
    keywords = INFO_KEYWORDS
    if curriculum is not None and curriculum.enabled:
        env, keywords = Curriculum(env, curriculum), (*INFO_KEYWORDS, STAGE_KEY)
    env = Monitor(Driven(env), monitor_file, info_keywords=keywords)
    if reward_scale != 1.0:
        env = gym.wrappers.TransformReward(env, lambda r: reward_scale * r)
    return env


def make_vec_env(config: EnvConfig | Scenario, *, n_envs: int = 1, seed: int = 0,
                 monitor_dir: Path | None = None, prefix: str = "", node: Any = None,
                 reward_scale: float = 1.0, curriculum: CurriculumConfig | None = None,
                 vec_env: str = "subproc") -> VecEnv:
    """``n_envs`` monitored ``NavEnv``s (seeds ``seed + rank``), each writing
    ``<monitor_dir>/<prefix><rank>.monitor.csv``; ``node``: the trainer's rclpy node, used by
    a single ROS env; the learner's rewards are the env's times ``reward_scale``; each env's
    pairs follow ``curriculum`` when given. ``vec_env``: ``subproc`` runs each env in a worker
    process, ``dummy`` all of them in this one (cheaper when an env step costs less than the
    workers' messages, as in process on two cores). Not SB3's ``make_vec_env``: it gives every
    rank the same env kwargs (ours differ by ROS namespace and node) and names monitor files
    ``<rank>`` (ours are ``<session>_<rank>``, which a resume and the reward curve read).
    ``config`` is resolved once (a ``Scenario`` given is used as it is), before any env."""
    scenario = config if isinstance(config, Scenario) else Scenario(config)
    check_no_test_world(scenario)  # no env ever sees a test world

    def factory(rank: int) -> Callable[[], gym.Env]:
        mine = scenario.for_env(env_for_rank(scenario.config, rank, n_envs))
        file = str(monitor_dir / f"{prefix}{rank}") if monitor_dir is not None else None

        def make() -> gym.Env:
            return _make(mine, file, node if n_envs == 1 else None, reward_scale, curriculum)
        return make

    if monitor_dir is not None:
        monitor_dir.mkdir(parents=True, exist_ok=True)
    fns = [factory(rank) for rank in range(n_envs)]
    if n_envs == 1 or vec_env == "dummy":
        vec: VecEnv = DummyVecEnv(fns)
    else:
        vec = SubprocVecEnv(fns, start_method="forkserver")
    vec.seed(seed)
    return vec
