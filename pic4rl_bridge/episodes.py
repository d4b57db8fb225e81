"""Where each episode starts and ends: PIC4rl-gym's goals-and-poses files and its curriculum.

PIC4rl-gym trains from a JSON of start poses and goals, drawing a new pair every
``change_goal_and_pose`` episodes (walking them in order when testing), and for the first
``starting_episodes`` starts at ``initial_pose`` with a random goal near it: the paper's
curriculum, central area first, obstacles after. Without a file the simulator samples a free
pair from the episode's seed. The schedule draws everything from the caller's rng, so one seed
gives one sequence of episodes.

Pairs of a kind (``episodes.pair_kind``; ``pic4rl_sim.engine.sampling.PAIR_KINDS``) other than plain
``any`` are drawn here, by ``PairSampler`` from the episode's seed, and sent to the simulator
as an explicit start and goal: both transports then run the same pair, and the simulator's own
sampling stays as it was. With ``episodes.world_variants`` each episode first draws its world
(or walks them in order when ``ordered``).
"""

from __future__ import annotations

import dataclasses
import functools
import json
import logging
import math
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from pic4rl_base.goal import Goal
from pic4rl_base.geometry import Pose2D
from pic4rl_sim.engine.sampling import (PAIR_KINDS, PairKind, check_free, check_pair_filter,
                                        sample_pairs, sample_start_goal)
from pic4rl_sim.errors import SimError

from .config import EpisodesConfig
from .errors import ConfigError
from .scenario import parse_variants
from .transports.transport import EpisodeRequest

if TYPE_CHECKING:
    from pic4rl_sim.engine.paths import PathPlanner
    from pic4rl_sim.engine.worlds.spec import WorldSpec

    from .scenario import Scenario

_SEED_END = 2**31 - 1
log = logging.getLogger(__name__)


@dataclass(frozen=True)
class GoalsAndPoses:
    """A goals-and-poses file: pair ``i`` starts at ``poses[i]`` and ends at ``goals[i]`` (m, rad);
    ``initial_pose`` is the starting episodes' start (``None``: the file has none); ``world``
    (``kind:variant``) and ``robot_radius_m`` (the robot's bounding radius) say where and for
    whom the pairs were drawn (empty and ``None`` in a file that does not say)."""

    initial_pose: Pose2D | None
    goals: tuple[Goal, ...]
    poses: tuple[Pose2D, ...]
    world: str = ""
    robot_radius_m: float | None = None


def _numbers(path: Path, key: str, value: Any, expected: str, size: int) -> tuple[float, ...]:
    ok = isinstance(value, list) and len(value) == size and all(
        isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)
        for v in value)
    if not ok:
        raise ConfigError(f"{path}: {key}: {value!r} is invalid; expected {expected} "
                          "(finite numbers)")
    return tuple(float(v) for v in value)


def _points(path: Path, data: dict[str, Any], key: str, expected: str,
            size: int) -> list[tuple[float, ...]]:
    if key not in data:
        raise ConfigError(f"{path}: missing key {key!r}; expected a list of {expected}")
    items = data[key]
    if not isinstance(items, list) or not items:
        raise ConfigError(f"{path}: {key}: {items!r} is invalid; expected a non-empty list "
                          f"of {expected}")
    return [_numbers(path, f"{key}[{i}]", v, expected, size) for i, v in enumerate(items)]


def load_goals_and_poses(path: str | Path) -> GoalsAndPoses:
    """Read a PIC4rl-gym goals-and-poses JSON: ``goals`` [[x, y], ...], ``poses``
    [[x, y, yaw], ...] of the same length, optional ``initial_pose`` [x, y, yaw] (m, rad)."""
    path = Path(path)
    try:
        data = json.loads(path.read_text())
    except OSError as err:
        raise ConfigError(f"{path}: cannot read the goals-and-poses file: {err.strerror}") from err
    except ValueError as err:
        raise ConfigError(f"{path}: not valid JSON: {err}") from err
    if not isinstance(data, dict):
        raise ConfigError(f"{path}: expected an object with 'goals' and 'poses', "
                          f"got {type(data).__name__}")
    goals = _points(path, data, "goals", "[x, y]", 2)
    poses = _points(path, data, "poses", "[x, y, yaw]", 3)
    if len(goals) != len(poses):
        raise ConfigError(f"{path}: 'goals' has {len(goals)} entries but 'poses' has "
                          f"{len(poses)}; expected one pose per goal")
    initial, world = data.get("initial_pose"), data.get("world", "")
    if not isinstance(world, str) or (world and ":" not in world):
        raise ConfigError(f"{path}: world: {world!r} is invalid; expected 'kind:variant'")
    radius = data.get("robot_radius_m")
    return GoalsAndPoses(
        initial_pose=None if initial is None else Pose2D(
            *_numbers(path, "initial_pose", initial, "[x, y, yaw]", 3)),
        goals=tuple(Goal(g[0], g[1]) for g in goals),
        poses=tuple(Pose2D(*p) for p in poses), world=world,
        robot_radius_m=None if radius is None else _numbers(
            path, "robot_radius_m", [radius], "a radius in metres", 1)[0])


def check_pairs(pairs: GoalsAndPoses, path: str, scenario: Scenario) -> None:
    """``ConfigError`` in one line when the pairs of file ``path`` were drawn in another
    world than ``scenario``'s or a start is in collision there (closer to an obstacle than the
    robot's bounding radius, the simulator's own rule); a warning when the file records no
    world, or was drawn for a smaller robot. Nothing to check without a simulated world."""
    world, world_name = scenario.world, scenario.world_name
    robot_radius_m = scenario.robot.footprint.bounding_radius_m
    if world is None:
        return
    if not pairs.world:
        log.warning("%s: the file records no world; its pairs are taken to be in %s", path,
                    world_name)
    elif pairs.world != world_name:
        raise ConfigError(f"{path}: its pairs were drawn in world {pairs.world} but this env "
                          f"runs {world_name}; give the sim that world (e.g. --sim-kwargs "
                          f"world_variant:{pairs.world.rpartition(':')[2]}) or pairs of it")
    if pairs.robot_radius_m is not None and robot_radius_m > pairs.robot_radius_m + 1e-3:
        log.warning("%s: its pairs were drawn for a robot of radius %.3f m; this one's is "
                    "%.3f m", path, pairs.robot_radius_m, robot_radius_m)
    for i, pose in enumerate(pairs.poses):
        try:
            check_free(world, (pose.x, pose.y), clearance_m=robot_radius_m, what=f"poses[{i}]")
        except SimError as err:
            raise ConfigError(f"{path}: {err}: that start is in collision for this robot "
                              f"(radius {robot_radius_m:.3f} m)") from err


class EpisodeSchedule:
    """The ``EpisodeRequest`` of each episode (numbered from 0), and its replacements when the
    simulator rejects one. Episodes ``< starting_episodes`` start at ``initial_pose`` with a
    goal uniform in ± ``starting_goal_range_m`` around it; later ones use the file's pairs, a
    new one every ``change_goal_and_pose`` episodes (random, or in order when ``ordered``), or,
    without ``pairs``, whatever the simulator samples from the seed.

    The env calls ``next_request`` once per episode, in order, then tries the requests of
    ``attempts``; the schedule remembers the pair in use, so a redrawn pair is kept for the
    rest of its block."""

    def __init__(self, config: EpisodesConfig, *, pairs: GoalsAndPoses | None = None,
                 ordered: bool = False) -> None:
        if config.starting_episodes > 0 and (pairs is None or pairs.initial_pose is None):
            where = config.file or "episodes.file (empty)"
            raise ConfigError(f"{where}: missing key 'initial_pose'; episodes.starting_episodes"
                              f" = {config.starting_episodes} needs a start [x, y, yaw]")
        self.config = config
        self.pairs = pairs
        self.ordered = ordered
        self.variants = parse_variants(config.world_variants)
        self.variant: int | None = None  # the world variant in use
        self.index: int | None = None  # the file pair in use
        self._block: int | None = None  # its block of change_goal_and_pose episodes
        self._skipped = 0  # ordered pairs skipped by redraws
        self._starting = False  # whether the last request was a starting episode's

    def next_request(self, episode: int, rng: np.random.Generator) -> EpisodeRequest:
        """The request of ``episode`` (>= 0); draws its seed first, then a goal or pair."""
        if episode < 0:
            raise ValueError(f"episode: {episode} is invalid; expected an integer >= 0")
        seed = int(rng.integers(0, _SEED_END))
        if self.variants:  # its world (no pairs file, no starting episodes: Scenario's check)
            n = len(self.variants)
            self.variant = self.variants[episode % n if self.ordered else int(rng.integers(n))]
        self._starting = episode < self.config.starting_episodes
        if self._starting:
            return self._starting_request(seed, rng)
        if self.pairs is None:
            return EpisodeRequest(seed, world_variant=self.variant)
        block = (episode - self.config.starting_episodes) // self.config.change_goal_and_pose
        if block != self._block:
            self._block = block
            n = len(self.pairs.goals)
            self.index = (block + self._skipped) % n if self.ordered else int(rng.integers(n))
        return self._pair_request(seed)

    def redraw(self, request: EpisodeRequest, rng: np.random.Generator) -> EpisodeRequest:
        """A replacement for the rejected ``request`` (the last one this schedule made, or a
        replacement of it): another goal near the initial pose, another pair (the next one
        when ``ordered``; a different one when random and there are two or more), or, for a
        sampled episode, a new seed."""
        if self._starting:
            return self._starting_request(request.seed, rng)
        if self.pairs is None or self.index is None:
            return EpisodeRequest(int(rng.integers(0, _SEED_END)), world_variant=self.variant)
        n = len(self.pairs.goals)
        if self.ordered:
            self._skipped += 1
            self.index = (self.index + 1) % n
        elif n > 1:
            other = int(rng.integers(n - 1))
            self.index = other + (other >= self.index)
        return self._pair_request(request.seed)

    def attempts(self, first: EpisodeRequest,
                 rng: np.random.Generator) -> Iterator[EpisodeRequest]:
        """``first``, then redraws: ``config.max_attempts`` requests in all. The env resets
        with each until one is not rejected, and gives up when the generator ends."""
        request = first
        for attempt in range(self.config.max_attempts):
            if attempt:
                request = self.redraw(request, rng)
            yield request

    def _starting_request(self, seed: int, rng: np.random.Generator) -> EpisodeRequest:
        start = self.pairs.initial_pose  # type: ignore[union-attr]  # checked in __init__
        dx, dy = rng.uniform(-1.0, 1.0, size=2) * self.config.starting_goal_range_m
        return EpisodeRequest(seed, start, (start.x + float(dx), start.y + float(dy)))

    def _pair_request(self, seed: int) -> EpisodeRequest:
        pairs, i = self.pairs, self.index
        assert pairs is not None and i is not None  # set by next_request
        return EpisodeRequest(seed, pairs.poses[i], pairs.goals[i])


def save_goals_and_poses(pairs: GoalsAndPoses, path: str | Path, *, comment: str = "",
                         overwrite: bool = False, exact: bool = False) -> Path:
    """Write ``pairs`` as a goals-and-poses JSON (mm, mrad; ``exact``: every digit, as a copy
    needs), read back by ``load_goals_and_poses``; an existing file is kept unless ``overwrite``."""
    path = Path(path)
    if path.exists() and not overwrite:
        raise ConfigError(f"{path}: exists; choose another name or pass overwrite=True")
    doc: dict[str, Any] = {"comment": comment} if comment else {}
    keep = float if exact else functools.partial(round, ndigits=3)
    if pairs.world:
        doc["world"] = pairs.world
    if pairs.robot_radius_m is not None:
        radius = pairs.robot_radius_m
        doc["robot_radius_m"] = float(radius) if exact else round(radius, 4)
    if pairs.initial_pose is not None:
        doc["initial_pose"] = [keep(v) for v in pairs.initial_pose]
    doc["goals"] = [[keep(x), keep(y)] for x, y in pairs.goals]
    doc["poses"] = [[keep(p.x), keep(p.y), keep(p.yaw)] for p in pairs.poses]
    path.write_text(json.dumps(doc, separators=(",", ":")))
    return path


def resolve_pair_kind(name: str, *, min_distance_m: float = 0.0, max_distance_m: float = 0.0,
                      max_detour: float = 0.0, prefix: str = "episodes.") -> PairKind | None:
    """The kind ``name`` with the non-zero values given instead of its own; ``None`` for plain
    ``any`` (the simulator samples the pair). A filter the values make invalid is a
    ``ConfigError`` naming the caller's key (``<prefix>max_distance_m``) and the kind."""
    if name not in PAIR_KINDS:
        raise ConfigError(f"pair_kind: {name!r} is invalid; expected one of "
                          f"{', '.join(PAIR_KINDS)}")
    kind = PAIR_KINDS[name]
    given = {key: value for key, value in (("min_distance_m", min_distance_m),
                                           ("max_distance_m", max_distance_m),
                                           ("max_detour", max_detour)) if value}
    if name == "any" and not given:
        return None
    values = {"min_distance_m": kind.min_distance_m or 0.0,
              "max_distance_m": kind.max_distance_m, "max_detour": kind.max_detour} | given
    try:
        check_pair_filter(**values, prefix=prefix)
    except ConfigError as err:  # a range the other way round
        raise ConfigError(f"pair_kind {name!r}: {err}") from err
    return dataclasses.replace(kind, **given)


class PairSampler:
    """Start-goal pairs of a kind in a simulated world, as the simulator would sample them
    (its clearance and minimum distance), with a path check; the path planner (the robot's
    circumscribed radius, 5 cm cells) is built on first use and kept."""

    def __init__(self, world: WorldSpec, *, robot_radius_m: float, clearance_m: float,
                 min_goal_distance_m: float, world_name: str = "") -> None:
        self.world = world
        self.world_name = world_name  # kind:variant, recorded in the pairs files it draws
        self.robot_radius_m = robot_radius_m
        self.clearance_m = clearance_m
        self.min_goal_distance_m = min_goal_distance_m
        self._planner: PathPlanner | None = None

    @classmethod
    def for_scenario(cls, scenario: Scenario) -> PairSampler | None:
        """The sampler of a simulated scenario; ``None`` for a real robot (no world)."""
        if scenario.sim is None or scenario.world is None:
            return None
        radius, engine = scenario.robot.footprint.bounding_radius_m, scenario.sim.engine
        return cls(scenario.world, robot_radius_m=radius,
                   clearance_m=radius + engine.clearance_m,
                   min_goal_distance_m=engine.min_goal_distance_m,
                   world_name=scenario.world_name)

    @property
    def planner(self) -> PathPlanner:
        if self._planner is None:
            from pic4rl_sim.engine.paths import planner_for

            self._planner = planner_for(self.world, robot_radius_m=self.robot_radius_m)
        return self._planner

    def draw(self, rng: np.random.Generator, kind: PairKind) -> tuple[Pose2D, tuple[float, float]]:
        """One pair of ``kind`` from ``rng``; ``ConfigError`` when the world has none."""
        low = kind.min_distance_m if kind.min_distance_m is not None else self.min_goal_distance_m
        try:
            return sample_start_goal(self.world, rng, clearance_m=self.clearance_m,
                                     min_distance_m=low, max_distance_m=kind.max_distance_m,
                                     max_detour=kind.max_detour, planner=self.planner)
        except (SimError, ConfigError) as err:  # no pair of the kind in this world
            raise ConfigError(f"episodes: pairs of {kind}: {err}") from err

    def request(self, seed: int, kind: PairKind) -> EpisodeRequest:
        """The episode of ``seed`` with a pair of ``kind`` drawn from that seed alone."""
        start, goal = self.draw(np.random.default_rng(seed), kind)
        return EpisodeRequest(seed, start, goal)

    def attempts(self, seed: int, kind: PairKind, rng: np.random.Generator,
                 count: int) -> Iterator[EpisodeRequest]:
        """``count`` requests with pairs of ``kind``: from ``seed``, then, after the simulator
        refused one, from new seeds of ``rng``."""
        for attempt in range(count):
            yield self.request(int(rng.integers(0, _SEED_END)) if attempt else seed, kind)

    def path_lengths(self, start: tuple[float, ...], goal: tuple[float, float]
                     ) -> tuple[float, float]:
        """(shortest collision-free path, straight line) from ``start`` to ``goal`` (m);
        the shortest is ``inf`` when there is no path, and free when the draw just searched
        it (the planner keeps its last answers)."""
        return self.planner.length(start[:2], goal), math.dist(start[:2], goal)

    def goals_and_poses(self, count: int, *, seed: int, kind: PairKind,
                        initial_pose: Pose2D | None = None) -> GoalsAndPoses:
        """``count`` pairs of ``kind`` drawn from ``seed`` (the same on every machine), for
        ``save_goals_and_poses``: training pairs or a fixed test set."""
        try:
            pairs = sample_pairs(self.world, count, np.random.default_rng(seed),
                                 clearance_m=self.clearance_m, kind=kind, planner=self.planner,
                                 min_goal_distance_m=self.min_goal_distance_m)
        except (SimError, ConfigError) as err:
            raise ConfigError(f"episodes: pairs of {kind}: {err}") from err
        return GoalsAndPoses(initial_pose, tuple(g for _, g in pairs),
                             tuple(Pose2D(*s) for s, _ in pairs), world=self.world_name,
                             robot_radius_m=self.robot_radius_m)
