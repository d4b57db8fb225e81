"""``RecordEpisodes``: bag recording as a Gymnasium wrapper, so that any env, a user's too, is
recorded the one way the metrics judge, and no env has to know about bags.

The wrapper writes each episode to its own rosbag2, ``<bags_dir>/<run>/episode_NNNN/``, the
run's config beside them (``pic4rl_bridge.recorder``). What it needs of the env it wraps (the
innermost one, ``env.unwrapped``) is ``Recordable``: ``NavEnv`` offers it, and so can a user's
env. ``make_env`` is the registered envs' entry point (``gymnasium.make``): a ``NavEnv``, in
``RecordEpisodes`` when its config's ``record.enabled`` asks (``record.*`` settings)."""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Mapping
from pathlib import Path
from typing import Any, Protocol

import gymnasium as gym

from pic4rl_metrics.contract import EpisodeFacts, Outcome
from pic4rl_sim.interfaces import GOAL_POSE, PLAN, find

from .config import EnvConfig
from .env import NavEnv
from .errors import RecorderError
from .recorder import EpisodeBag, RunRecorder
from .scenario import robot_of
from .transports.transport import RawMessage, Tap


class Recordable(Protocol):
    """What ``RecordEpisodes`` needs of an env. ``flush`` and ``offered_qos`` may be left out.

    - ``tap``: set by the wrapper around each ``reset`` and episode; the env calls it with
      every message of the episode as on the wire (``RawMessage``: topic, type, CDR, bag time
      in ns), from those its reset causes on.
    - ``stamp_ns``: the bag time (ns) of the latest reset or step.
    - ``episode_facts()``: the facts of the episode just reset (``EpisodeFacts``: its start,
      goal, footprint, ...); its ``run`` and ``episode`` are the bag's.
    - ``flush()``: deliver to ``tap`` every message up to ``stamp_ns`` (an episode ends).
    - ``offered_qos(topic)``: how a topic's publisher offered it (``None``: not known).

    At an episode's end ``info["outcome"]`` is one of the contract's outcomes; an ``aborted``
    one's ``info["reason"]`` is the bag's ``end_reason``, a ``collision``'s
    ``info["collision_rule"]`` its ``collision_rule``.
    """

    tap: Tap | None
    stamp_ns: int

    def episode_facts(self) -> EpisodeFacts: ...


class RecordEpisodes(gym.Wrapper[Any, Any, Any, Any]):
    """Each episode of ``env`` (``Recordable``) to its own bag under ``<bags_dir>/<run>/``,
    ``config`` (any YAML-able mapping) beside them as ``config.yaml``. A bag opens once the
    reset succeeded, with the messages the reset caused (an episode without a goal leaves out
    the goal and the plan the simulator publishes at each reset: its bag gives the metrics no
    goal to judge), and closes with the outcome; a ``reset`` or ``close`` during an episode
    closes its bag without one."""

    def __init__(self, env: gym.Env[Any, Any], bags_dir: str | Path, run: str, *,
                 storage: str = "sqlite3", flush_interval_s: float = 1.0,
                 config: Mapping[str, Any] | None = None) -> None:
        super().__init__(env)
        source = env.unwrapped
        missing = [name for name in ("tap", "stamp_ns", "episode_facts")
                   if not hasattr(source, name)]
        if missing:
            raise RecorderError(f"{type(source).__name__}: cannot be recorded: it has no "
                                f"{missing[0]!r}; expected pic4rl_bridge.recording.Recordable")
        self.recorder = RunRecorder(Path(bags_dir), run, storage=storage,
                                    flush_interval_s=flush_interval_s, config=config)
        self.bag: EpisodeBag | None = None

    @property
    def _source(self) -> Recordable:
        return self.env.unwrapped  # type: ignore[return-value]  # checked in __init__

    def reset(self, *, seed: int | None = None,
              options: dict[str, Any] | None = None) -> tuple[Any, dict[str, Any]]:
        self._end(None)
        source = self._source
        held: list[RawMessage] = []
        source.tap = held.append
        try:
            obs, info = self.env.reset(seed=seed, options=options)
        finally:
            source.tap = None
        facts = source.episode_facts()
        bag = self.bag = self.recorder.begin(qos=getattr(source, "offered_qos", None))
        for raw in held:
            if facts.goal is not None or find(raw.topic) not in (GOAL_POSE, PLAN):
                bag.write(raw)
        source.tap = bag.write
        bag.facts(dataclasses.replace(facts, run=self.recorder.run_dir.name,
                                      episode=bag.path.name), source.stamp_ns)
        return obs, info

    def step(self, action: Any) -> tuple[Any, Any, bool, bool, dict[str, Any]]:
        obs, reward, terminated, truncated, info = self.env.step(action)
        if (terminated or truncated) and self.bag is not None:
            word = info.get("outcome")
            try:
                outcome = Outcome(word)
            except ValueError:
                self._end(None)
                raise RecorderError(f"info['outcome']: {word!r} at the episode's end is "
                                    f"invalid; expected one of "
                                    f"{', '.join(o.value for o in Outcome)}") from None
            self._end(outcome, info.get("reason") if outcome is Outcome.ABORTED else None,
                      info.get("collision_rule"))
        return obs, reward, terminated, truncated, info

    def abort(self, reason: str) -> None:
        """End the episode now, ``aborted`` (a policy failed): the env's ``abort`` if it has
        one, then the bag closed with ``reason``."""
        abort = getattr(self._source, "abort", None)
        if abort is not None:
            abort(reason)
        self._end(Outcome.ABORTED, reason)

    def close(self) -> None:
        self._end(None)
        super().close()

    def _end(self, outcome: Outcome | None, reason: str | None = None,
             rule: str | None = None) -> None:
        """Close the episode's bag: with its ``outcome`` (and ``reason``, or a collision's
        ``rule``), else without one."""
        bag, self.bag = self.bag, None
        if bag is None:
            return
        source = self._source
        flush = getattr(source, "flush", None)
        if flush is not None:
            flush()
        source.tap = None
        if outcome is None:
            bag.abort()
        else:
            bag.close(outcome, source.stamp_ns, reason, rule)


def run_params(config: EnvConfig) -> dict[str, Any]:
    """The run's config as a params file: loads back with ``load_env_config``. A run without
    a simulator (``EnvConfig.simulated``) has no ``sim:`` section: it names its robot."""
    env = config.to_params()
    if not config.simulated:
        return {"nav_env": {"ros__parameters": {**env, "robot": robot_of(config)}}}
    return {"sim": {"ros__parameters": dict(config.sim_params)},
            "nav_env": {"ros__parameters": env}}


def record_from_config(env: NavEnv) -> RecordEpisodes:
    """``env`` in ``RecordEpisodes`` as its config's ``record.*`` says: the run
    ``record.run`` (empty: ``<task>_<YYYYmmdd-HHMMSS>``), the config beside its bags. ``env``
    is closed if its recorder cannot start."""
    rec, config = env.config.record, env.config
    run = rec.run or f"{config.task}_{time.strftime('%Y%m%d-%H%M%S')}"
    try:
        return RecordEpisodes(env, rec.bags_dir, run, storage=rec.storage,
                              flush_interval_s=rec.flush_interval_s, config=run_params(config))
    except BaseException:
        env.close()
        raise


def make_env(config: Any = None, **kwargs: Any) -> gym.Env[Any, Any]:
    """A ``NavEnv(config, **kwargs)``, recorded (``record_from_config``) when its
    ``record.enabled``; ``config``: a ``Scenario`` resolved at the edge (``make_vec_env``'s),
    taken as it is, or anything else ``NavEnv`` takes."""
    env = NavEnv(config, **kwargs)
    return record_from_config(env) if env.config.record.enabled else env


make_env.metadata = NavEnv.metadata  # type: ignore[attr-defined]  # gymnasium.make's render modes
