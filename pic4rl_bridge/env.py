"""``NavEnv``: the Gymnasium navigation env, over ROS 2 or in process.

One config file (``sim:`` and ``nav_env:`` sections) says which task, robot, world and transport;
the task turns decoded sensor frames into observations, rewards and outcomes; the transport
moves the robot. It records nothing: it offers what a recorder needs (``tap``, ``stamp_ns``,
``episode_facts``, ...) and ``pic4rl_bridge.recording.RecordEpisodes`` wraps it. ``terminated``
is goal or collision, ``truncated`` the time limit (``episode_max_steps``), a simulator whose
physics diverged (outcome ``diverged``) or a needed topic gone silent (``aborted``, the robot
stopped; ``ros.max_sensor_age_s``): ``info["reason"]`` says why. ``info["reward_terms"]``
holds each scaled term.

``reset(seed=s)`` restarts the episode sequence: the same seed gives the same episodes (world,
start, goal, sensor noise) and, with the same actions, the same observations and rewards
through either transport.
"""

from __future__ import annotations

import dataclasses
import logging
import math
from collections.abc import Iterable, Mapping, Sequence
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np

from pic4rl_base.geometry import Pose2D
from pic4rl_metrics.contract import EpisodeFacts, Outcome
from pic4rl_sim.engine.sampling import PairKind

from .config import EnvConfig, TransportName, env_config_from_params, load_env_config
from .env_facts import episode_facts
from .episodes import (EpisodeSchedule, PairSampler, check_pairs, load_goals_and_poses,
                       resolve_pair_kind)
from .errors import BridgeError, ConfigError, EpisodeRejected, StaleSensor
from .readings.frame import SensorFrame
from .readings.sensor_table import BY_NAME
from .scenario import Scenario
from .settings.tasks import task_spec
from .tasks.base import EpisodeContext, make_task
from .transports.transport import EpisodeRequest, OfferedQos, Tap, Transport

log = logging.getLogger(__name__)
Config = Scenario | EnvConfig | str | Path | Mapping[str, Any] | None


def _scenario(config: Config, overrides: Mapping[str, Any], sim: Mapping[str, Any],
              sim_defaults: Mapping[str, Any]) -> Scenario:
    """The env's ``Scenario``: the one given (resolved at the edge), else resolved here."""
    if isinstance(config, Scenario):
        if not (overrides or sim or sim_defaults):
            return config.for_env()
        config = config.config
    if config is None or isinstance(config, EnvConfig):
        base = config or EnvConfig()
    elif isinstance(config, (str, Path)):
        base = load_env_config(config)
    else:
        params = dict(config)  # the sim's popped before the call: not an env parameter
        base = env_config_from_params(params, sim_params=params.pop("sim", {}))
    merged = EnvConfig.replace(base, **overrides) if overrides else base
    if not (merged.sim_params or sim or merged.transport == TransportName.INPROCESS.value):
        sim_defaults = {}  # a real robot: no simulator for the registered env's defaults
    if sim or sim_defaults:
        merged = dataclasses.replace(merged,
                                     sim_params={**sim_defaults, **merged.sim_params, **sim})
    return Scenario(merged)


_PAIR_OPTIONS = ("pair_kind", "min_distance_m", "max_distance_m", "max_detour")


def _parse_options(options: Mapping[str, Any]) -> dict[str, Any]:
    """``reset`` options checked: ``start`` → Pose2D, ``goal`` → (x, y), ``seed`` → int,
    the pair filters as ``episodes.*`` takes them."""
    known = ("start", "goal", "seed", *_PAIR_OPTIONS)
    unknown = set(options) - set(known)
    if unknown:
        raise ConfigError(f"reset options: unknown key {min(unknown)!r}; expected "
                          f"{', '.join(known)}")
    parsed: dict[str, Any] = {}
    for key, size, expected in (("start", 3, "[x, y, yaw] (m, m, rad)"), ("goal", 2, "[x, y] (m)")):
        if options.get(key) is None:
            continue
        try:
            values = [float(v) for v in options[key]]
        except (TypeError, ValueError):
            values = []
        if len(values) != size or not all(math.isfinite(v) for v in values):
            raise ConfigError(f"reset options: {key}: {options[key]!r} is invalid; "
                              f"expected {expected}")
        parsed[key] = Pose2D(*values) if key == "start" else (values[0], values[1])
    if "seed" in options:
        seed = options["seed"]
        if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
            raise ConfigError(f"reset options: seed: {seed!r} is invalid; expected an int >= 0")
        parsed["seed"] = int(seed)
    pair = {key: options[key] for key in _PAIR_OPTIONS if options.get(key) is not None}
    if pair and ("start" in parsed or "goal" in parsed):
        raise ConfigError(f"reset options: {min(pair)!r} draws the pair; it cannot go "
                          "with start or goal")
    for key in _PAIR_OPTIONS[1:]:
        value = pair.get(key, 0.0)
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not (
                math.isfinite(value) and value >= 0):
            raise ConfigError(f"reset options: {key}: {value!r} is invalid; expected a "
                              "number >= 0 (0: the kind's)")
    if pair:
        parsed["pairs"] = pair
    return parsed


class NavEnv(gym.Env[Any, np.ndarray]):
    """A robot navigation task as a Gymnasium env.

    ``config``: a ``Scenario`` (resolved once, at the edge: used as it is when nothing below
    is given), a config file path, an ``EnvConfig``, or a mapping of dotted env parameters (the
    sim's under ``"sim"``). ``task``, ``sensor``, ``sensors``, ``transport`` and then
    ``overrides`` (dotted: ``{"reward.goal": 500.0}``) apply on top; the sim's parameters are
    ``sim_defaults`` (the registered env's), then the config's, then ``sim``. ``node``: an
    rclpy node for the ROS transport (default: its own, in its own context).
    ``render_mode="rgb_array"``: ``render()`` returns a picture (``pic4rl_bridge.render``),
    the top-down view or, with ``render_view="mujoco"``, MuJoCo's camera; ``metadata``'s
    ``render_fps`` is one frame per control period.
    """

    metadata = {"render_modes": ["rgb_array"], "render_fps": 10}  # noqa: RUF012 - Gymnasium's way

    def __init__(self, config: Config = None, *, task: str | None = None,
                 sensor: str | None = None, sensors: Sequence[str] | None = None,
                 transport: str | None = None, sim: Mapping[str, Any] | None = None,
                 sim_defaults: Mapping[str, Any] | None = None,
                 overrides: Mapping[str, Any] | None = None, render_mode: str | None = None,
                 render_view: str = "top", node: Any = None) -> None:
        if render_mode not in (None, *self.metadata["render_modes"]):
            raise ConfigError(f"render_mode: {render_mode!r} is invalid; expected 'rgb_array' "
                              "or None")
        self.render_mode = render_mode
        given = {k: v for k, v in (("task", task), ("sensor", sensor), ("sensors", sensors),
                                   ("transport", transport)) if v is not None}
        self.scenario = _scenario(config, {**given, **(overrides or {})}, sim or {},
                                  sim_defaults or {})
        self.config = self.scenario.config
        self._task_spec = task_spec(self.config.task)
        self.task = make_task(self.config, self.scenario.robot, self.scenario.world)
        self.observation_space, self.action_space = (self.task.observation_space,
                                                     self.task.action_space)
        e = self.config.episodes
        self._pairs = load_goals_and_poses(e.file) if e.file else None
        if self._pairs is not None:  # drawn in this world, every start free for this robot
            check_pairs(self._pairs, e.file, self.scenario)
        self._schedule = EpisodeSchedule(e, pairs=self._pairs, ordered=e.ordered)
        self._kind = resolve_pair_kind(e.pair_kind, min_distance_m=e.min_distance_m,
                                       max_distance_m=e.max_distance_m, max_detour=e.max_detour)
        self._sampler = PairSampler.for_scenario(self.scenario)
        if self._kind is not None and self._sampler is None:
            raise ConfigError(f"episodes.pair_kind: {e.pair_kind!r} with filters needs a "
                              "simulated world (a 'sim:' section); a real robot's goals come "
                              "from its operator or episodes.file")
        sensors = self.task.required & BY_NAME.keys()
        crowd = self.scenario.sim is not None and self.scenario.sim.engine.crowd.count > 0
        sensors |= {s for s, on in (("scan", self.scenario.spec.lidar), ("people", crowd)) if on}
        self.transport = self._make_transport(frozenset(sensors), node)
        self.metadata = {**self.metadata,
                         "render_fps": round(1.0 / self.scenario.robot.control_dt_s, 6)}
        self._view = self._make_view(render_view, sensors) if render_mode is not None else None
        self._episode = 0
        self._frame: SensorFrame | None = None
        self._context: EpisodeContext | None = None
        self._streak = self._steps = 0
        self._seed_used = 0  # the simulator seed of the current episode
        self._done = True

    def _make_transport(self, sensors: frozenset[str], node: Any) -> Transport:
        if self.config.transport == TransportName.ROS.value:
            from .transports.ros_transport import RosTransport

            return RosTransport(self.config, self.scenario, sensors, node=node)
        from .transports.inprocess import InProcessTransport

        return InProcessTransport(self.config, self.scenario, sensors)

    def _make_view(self, view: str, sensors: set[str]) -> Any:
        from .render import make_view

        try:
            return make_view(view, self.scenario, self.transport, self.config.goal_tolerance_m,
                             depth="depth" in sensors)
        except BaseException:
            self.transport.close()
            raise

    @property
    def frame(self) -> SensorFrame | None:
        """The latest decoded sensor data (``None`` before any reset), for controllers."""
        return self._frame

    def reset(self, *, seed: int | None = None,
              options: dict[str, Any] | None = None) -> tuple[Any, dict[str, Any]]:
        """Start the next episode. ``options``: ``start`` ([x, y, yaw]), ``goal`` ([x, y]),
        ``seed`` (the simulator's episode seed) override the schedule for this episode;
        ``pair_kind``, ``min_distance_m``, ``max_distance_m``, ``max_detour`` draw its pair
        (``pair_kind`` given: that kind's values, else the config's; then these)."""
        super().reset(seed=seed)
        if seed is not None:  # a seeded reset restarts the sequence of episodes
            self._episode = 0
            self._schedule = EpisodeSchedule(self.config.episodes, pairs=self._pairs,
                                             ordered=self.config.episodes.ordered)
        given = _parse_options(options or {})
        request = self._schedule.next_request(self._episode, self.np_random)
        request = dataclasses.replace(request, **{k: given[k] for k in ("seed", "start", "goal")
                                                  if k in given})
        if self.scenario.select(request.world_variant):  # the episode's world, pairs and task
            self._sampler = PairSampler.for_scenario(self.scenario)
            self.task = make_task(self.config, self.scenario.robot, self.scenario.world)
        kind = self._kind if "pairs" not in given else self._pair_kind(given["pairs"])
        if "pairs" in given:  # the drawn pair replaces the schedule's
            request = EpisodeRequest(request.seed, world_variant=request.world_variant)
        frame = self._start(request, kind, redraw="start" not in given and "goal" not in given)
        self._frame, self._context = frame, self.task.begin(frame)
        self._last_action = np.zeros(self.action_space.shape, dtype=np.float32)
        self._streak = self._steps = 0
        self._done = False
        if self._view is not None:
            self._view.begin(frame, self._context)
        self._episode += 1
        obs = self.task.observe(frame, self._context, self._last_action)
        info = {"episode": self._episode - 1, "seed": self._seed_used, "goal": self._context.goal,
                "start": list(self._context.start), "world_variant": self.scenario.variant}
        return obs, info

    def _pair_kind(self, options: Mapping[str, Any]) -> PairKind | None:
        """The pair filter of ``reset``'s options (see ``reset``)."""
        e = self.config.episodes
        name = options.get("pair_kind", e.pair_kind)
        base = (0.0, 0.0, 0.0) if "pair_kind" in options else (
            e.min_distance_m, e.max_distance_m, e.max_detour)
        values = [float(options.get(key, b)) for key, b in zip(_PAIR_OPTIONS[1:], base)]
        kind = resolve_pair_kind(str(name), min_distance_m=values[0], max_distance_m=values[1],
                                 max_detour=values[2], prefix="reset options: ")
        if kind is not None and self._sampler is None:
            raise ConfigError("reset options: pair filters need a simulated world")
        return kind

    def _start(self, first: EpisodeRequest, kind: PairKind | None, *,
               redraw: bool) -> SensorFrame:
        """The first frame of an episode, redrawing rejected requests (a start or goal given
        to ``reset(options=...)`` is not redrawn). A request the simulator would sample gets
        a pair of ``kind`` drawn from its seed instead (``None``: the simulator samples)."""
        reasons = []
        requests: Iterable[EpisodeRequest] = (
            self._schedule.attempts(first, self.np_random) if redraw else [first])
        if kind is not None and first.start is None and first.goal is None:
            requests = self._sampler.attempts(  # type: ignore[union-attr]  # checked with kind
                first.seed, kind, self.np_random, self.config.episodes.max_attempts)
        for request in requests:  # redraws stay in the episode's world
            request = dataclasses.replace(request, world_variant=first.world_variant)
            try:
                frame = self.transport.reset(request)
            except EpisodeRejected as err:
                reasons.append(str(err))
                log.info("episode %d: %s; drawing another", self._episode, err)
                continue
            self._seed_used = request.seed
            return frame
        raise EpisodeRejected(f"episode {self._episode}: {len(reasons)} start/goal pairs "
                              f"refused; the last: {reasons[-1]}")

    def step(self, action: np.ndarray) -> tuple[Any, float, bool, bool, dict[str, Any]]:
        if self._done or self._frame is None or self._context is None:
            raise BridgeError("step() after the episode ended: call reset() first")
        action = np.clip(np.asarray(action, dtype=np.float32).reshape(self.action_space.shape),
                         -1.0, 1.0)
        try:
            frame, stale = self.transport.step(self.task.command_at(action, self._frame)), None
        except StaleSensor as err:  # the robot was stopped: the episode ends where it was
            frame, stale = self._frame, str(err)
        judgement = self.task.judge(self._frame, frame, self._context, self._streak)
        fault = stale or self.transport.fault
        if fault is not None:  # put back at its start, or blind: nothing to judge
            judgement = dataclasses.replace(
                judgement, terms=dict.fromkeys(judgement.terms, 0.0), outcome=None)
        self._frame, self._streak, self._last_action = frame, judgement.collision_streak, action
        if self._view is not None:
            self._view.track(frame)
        self._steps += 1
        terminated = judgement.outcome is not None
        truncated = not terminated and (fault is not None
                                        or self._steps >= self.config.episode_max_steps)
        outcome = judgement.outcome or (Outcome.ABORTED if stale else Outcome.DIVERGED if fault
                                        else Outcome.TIMEOUT if truncated else None)
        obs = self.task.observe(frame, self._context, action)
        info = judgement.info(self._steps, outcome)
        if fault is not None:
            info["reason"] = fault
            log.error("episode %d %s: %s", self._episode - 1,
                      "aborted, the robot stopped" if stale else "ended", fault)
        self._done = outcome is not None
        return obs, judgement.reward, terminated, truncated, info

    def render(self) -> np.ndarray | None:
        """The picture of the current step (``render_mode="rgb_array"``), else None."""
        if self._view is None:
            return None
        if self._frame is None or self._context is None:
            raise BridgeError("render() before the first reset()")
        return self._view.render(self._frame, self._context)

    def close(self) -> None:
        for part in (getattr(self, "_view", None), getattr(self, "transport", None)):
            if part is not None:
                part.close()

    def abort(self, reason: str) -> None:
        """End the episode now, ``aborted``; ``reason`` (a policy failed) is a recorder's."""
        self._done = True

    @property
    def tap(self) -> Tap | None:
        """Gets each message of the episode from its reset on, as on the wire (``RawMessage``)."""
        return self.transport.tap

    @tap.setter
    def tap(self, tap: Tap | None) -> None:
        self.transport.tap = tap

    @property
    def stamp_ns(self) -> int:
        """The bag time (ns) of the latest frame; 0 before the first reset."""
        return self._frame.stamp_ns if self._frame is not None else 0

    def offered_qos(self, topic: str) -> OfferedQos | None:
        """How ``topic`` (absolute) was offered by its publisher; ``None`` when not known."""
        return self.transport.offered_qos(topic)

    def flush(self) -> None:
        """Deliver to ``tap`` every message stamped up to the latest frame."""
        self.transport.flush()

    def episode_facts(self) -> EpisodeFacts:
        """The current episode's bag facts, with its start-goal path lengths (searched now)."""
        if self._frame is None or self._context is None:
            raise BridgeError("episode_facts() before the first reset()")
        return episode_facts(
            self.config, self.scenario, self._frame, self._context, seed=self._seed_used,
            task=self._task_spec.fact_name(self.config.sensor_label),
            world=self.transport.world_name, index=self._episode - 1, sampler=self._sampler,
            task_facts=self.task.facts(self._context))
