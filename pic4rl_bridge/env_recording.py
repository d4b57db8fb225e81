"""What ``NavEnv`` writes to bags: the run's recorder (the run's config beside its bags), each
episode's bag, opened once the episode's reset succeeded and holding the messages that reset
caused, and the facts the bag opens with."""

from __future__ import annotations

import time
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from pic4rl_base.geometry import Mount
from pic4rl_metrics.contract import EpisodeFacts, Outcome, parse_facts
from pic4rl_sim.interfaces import GOAL_POSE, PLAN, find

from .config import EnvConfig
from .episodes import PairSampler
from .readings.frame import SensorFrame
from .recorder import EpisodeBag, RunRecorder
from .robot_info import RobotInfo
from .scenario import robot_of
from .tasks.base import EpisodeContext
from .transports.transport import RawMessage, Transport


def run_params(config: EnvConfig) -> dict[str, Any]:
    """The run's config as a params file: loads back with ``load_env_config``. A run without
    a simulator (``EnvConfig.simulated``) has no ``sim:`` section: it names its robot."""
    env = config.to_params()
    if not config.simulated:
        return {"nav_env": {"ros__parameters": {**env, "robot": robot_of(config)}}}
    return {"sim": {"ros__parameters": dict(config.sim_params)},
            "nav_env": {"ros__parameters": env}}


class EnvRecording:
    """A run's bags under ``<bags_dir>/<run>/``: ``hold`` before a reset, ``open`` once it
    succeeded, ``end`` when the episode ends (with its outcome) or is cut short (without)."""

    def __init__(self, config: EnvConfig) -> None:
        rec = config.record
        run = rec.run or f"{config.task}_{time.strftime('%Y%m%d-%H%M%S')}"
        self.recorder = RunRecorder(Path(rec.bags_dir), run, storage=rec.storage,
                                    flush_interval_s=rec.flush_interval_s,
                                    config=run_params(config))
        self.bag: EpisodeBag | None = None

    @staticmethod
    def hold(transport: Transport) -> list[RawMessage]:
        """The list the messages of the reset to come go to, for the bag it opens."""
        held: list[RawMessage] = []
        transport.tap = held.append
        return held

    def open(self, transport: Transport, held: list[RawMessage], *, goal: bool = True) -> None:
        """The episode's bag, with the reset's ``held`` messages, then every message. An
        episode without a goal (``goal`` false: person monitoring) leaves out the goal and the
        plan to it that the simulator publishes at every reset: its bag, like a real robot's,
        gives the metrics no goal to judge, so its tables head with full runs."""
        bag = self.bag = self.recorder.begin(qos=transport.offered_qos)
        for raw in held:
            if goal or find(raw.topic) not in (GOAL_POSE, PLAN):
                bag.write(raw)
        transport.tap = bag.write

    def end(self, transport: Transport, outcome: Outcome | None, stamp_ns: int,
            reason: str | None = None) -> None:
        """Close the episode's bag: with its outcome (and the ``reason`` the env cut it short),
        or, cut short by its caller, without one."""
        bag, self.bag = self.bag, None
        if bag is None:
            return
        transport.flush()
        transport.tap = None
        if outcome is None:
            bag.abort()
        else:
            bag.close(outcome, stamp_ns, reason)


def episode_facts(config: EnvConfig, robot: RobotInfo, frame: SensorFrame,
                  context: EpisodeContext, *, seed: int, task: str, world: str,
                  recording: EnvRecording | None, index: int, sampler: PairSampler | None,
                  task_facts: Mapping[str, Any]) -> EpisodeFacts:
    """An episode's bag facts: of episode ``index`` (its bag's name when ``recording``), with
    the start-goal path lengths when recorded (the search takes time). The env's
    ``warning_tolerance_m`` (closer is unsafe) is the contract's ``safety_margin_m``; the
    task's facts are decoded by the contract."""
    bag = recording.bag if recording is not None else None
    lengths: tuple[float | None, float | None] = (None, None)
    if context.goal is not None and sampler is not None and bag is not None:
        lengths = sampler.path_lengths(context.start, context.goal)
    c = config
    mount = frame.scan.mount if frame.scan is not None else None  # the collision test's
    facts = EpisodeFacts(
        agent=c.agent, task=task, world=world, robot=robot.name,
        run=recording.recorder.run_dir.name if recording is not None else "",
        episode=bag.path.name if bag is not None else str(index), seed=seed,
        footprint=robot.footprint,
        start=tuple(context.start),
        goal=context.goal,
        goal_tolerance_m=c.goal_tolerance_m, collision_tolerance_m=c.collision_tolerance_m,
        safety_margin_m=c.warning_tolerance_m, max_speed_mps=robot.max_linear_m_s,
        shortest_path_m=lengths[0], straight_line_m=lengths[1],
        reference_path_m=_reference_path_m(sampler),
        scan_mount=None if mount is None else Mount(mount.x, mount.y, mount.yaw),
        time_budget_s=c.episode_max_steps * robot.control_dt_s,
    )
    parsed, given = parse_facts(task_facts, source=f"task {c.task}")
    return facts.merged(parsed, given=given)


def _reference_path_m(sampler: PairSampler | None) -> float | None:
    """The simulated world's reference path length (m), where it has one (``barn``)."""
    length = sampler.world.params.get("reference_path_length_m") if sampler is not None else None
    return None if length is None else float(length)
