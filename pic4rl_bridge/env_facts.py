"""What ``NavEnv`` tells a recorder of each episode: its facts, as the bag contract states them
(``pic4rl_metrics.contract.EpisodeFacts``), from the env's config, scenario (robot, crowd),
world and task."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from pic4rl_metrics.contract import EpisodeFacts, parse_facts

from .config import EnvConfig
from .episodes import PairSampler
from .readings.frame import SensorFrame
from .scenario import Scenario
from .tasks.base import EpisodeContext


def episode_facts(config: EnvConfig, scenario: Scenario, frame: SensorFrame,
                  context: EpisodeContext, *, seed: int, task: str, world: str,
                  index: int, sampler: PairSampler | None,
                  task_facts: Mapping[str, Any]) -> EpisodeFacts:
    """The facts of episode ``index`` (named so; a recorder names it after its bag, and its
    run), with the start-goal path lengths (a search: only a recorder asks). The env's
    ``warning_tolerance_m`` (closer is unsafe) is the contract's ``safety_margin_m``; the
    task's facts are decoded by the contract. With a simulated crowd, its people's radius
    (``person_radius_m``: the social metrics measure from their bodies' edge)."""
    lengths: tuple[float | None, float | None] = (None, None)
    if context.goal is not None and sampler is not None:
        lengths = sampler.path_lengths(context.start, context.goal)
    c, robot = config, scenario.robot
    crowd = scenario.sim.engine.crowd if scenario.sim is not None else None
    mount = frame.scan.mount if frame.scan is not None else None  # the collision test's
    facts = EpisodeFacts(
        agent=c.agent, task=task, world=world, robot=robot.name,
        run="", episode=str(index), seed=seed,
        footprint=robot.footprint,
        start=tuple(context.start),
        goal=context.goal,
        goal_tolerance_m=c.goal_tolerance_m, collision_tolerance_m=c.collision_tolerance_m,
        safety_margin_m=c.warning_tolerance_m, max_speed_mps=robot.max_linear_m_s,
        shortest_path_m=lengths[0], straight_line_m=lengths[1],
        reference_path_m=_reference_path_m(sampler),
        scan_mount=mount,
        time_budget_s=c.episode_max_steps * robot.control_dt_s,
        person_radius_m=crowd.radius_m if crowd is not None and crowd.count > 0 else None,
    )
    parsed, given = parse_facts(task_facts, source=f"task {c.task}")
    return facts.merged(parsed, given=given)


def _reference_path_m(sampler: PairSampler | None) -> float | None:
    """The simulated world's reference path length (m), where it has one (``barn``)."""
    length = sampler.world.params.get("reference_path_length_m") if sampler is not None else None
    return None if length is None else float(length)
