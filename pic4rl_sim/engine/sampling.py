"""Starts and goals where a robot fits: sampled for each episode, or checked when given.

Sampling draws candidates in batches and tests each batch with one ``clearance`` call, so an
episode reset costs about a millisecond. Results depend only on the world and the rng state.
Pairs of a kind (``PAIR_KINDS``) also bound the straight-line distance and the detour, the
shortest collision-free path over the straight line (``paths``): a path search per candidate
pair (tens of milliseconds), run only when a path check is asked for. In a world with a
walking person a start also keeps its clearance from where the person walks in the episode's
first ``PERSON_CLEAR_S`` seconds: a person walking into the robot as the episode starts would
be a collision of the world's making, not the agent's.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cache
from typing import TYPE_CHECKING

import numpy as np

from pic4rl_base.errors import require

from ..errors import WorldError
from .engine_config import EngineConfig
from pic4rl_base.geometry import Pose2D
from .worlds.spec import PersonSpec, WorldSpec

if TYPE_CHECKING:
    from .paths import PathPlanner

BATCH = 256
MAX_PATH_CHECKS = 400  # path searches per sampled pair before giving up
_MIN_GOAL_DISTANCE_M = EngineConfig.min_goal_distance_m  # the sim's own least distance
#: A sampled start keeps its clearance (plus the person's radius) from everywhere a world's
#: person walks from the episode's start to this time (s).
PERSON_CLEAR_S = 3.0


@dataclass(frozen=True)
class PairKind:
    """What start-goal pairs of a kind satisfy: straight-line distance in
    [``min_distance_m``, ``max_distance_m``] (``None``: the sampler's own minimum, the
    engine's ``min_goal_distance_m``) and shortest path / straight line <= ``max_detour``."""

    min_distance_m: float | None = None
    max_distance_m: float = math.inf
    max_detour: float = math.inf

    def __post_init__(self) -> None:
        low = 0.0 if self.min_distance_m is None else self.min_distance_m
        check_pair_filter(low, self.max_distance_m, self.max_detour, prefix="pairs.")


def check_pair_filter(min_distance_m: float, max_distance_m: float, max_detour: float, *,
                      prefix: str) -> None:
    """``ConfigError`` naming ``<prefix>min_distance_m`` (``max_distance_m``, ``max_detour``)
    unless the least distance is finite and >= 0 m, the greatest at least that, and the detour
    (shortest path / straight line) >= 1. The one check of every pair filter: a kind, the
    sampler's arguments, the env's ``episodes`` section and ``reset`` options, each curriculum
    stage (``prefix``: the caller's keys, ``"episodes."``)."""
    require(math.isfinite(min_distance_m) and min_distance_m >= 0, f"{prefix}min_distance_m",
            min_distance_m, "a finite distance >= 0 m")
    require(max_distance_m >= min_distance_m, f"{prefix}max_distance_m", max_distance_m,
            f"a distance >= min_distance_m={min_distance_m} m")
    require(max_detour >= 1.0, f"{prefix}max_detour", max_detour,
            "a ratio >= 1 (shortest path / straight line)")


#: Named kinds: ``any`` is every free pair the simulator samples (at least its
#: ``min_goal_distance_m`` apart); ``paper`` is PIC4rl-gym's test episodes: 4-8 m apart with a
#: collision-free path at most 1.3 times the straight line.
PAIR_KINDS: dict[str, PairKind] = {
    "any": PairKind(),
    "paper": PairKind(min_distance_m=4.0, max_distance_m=8.0, max_detour=1.3),
}


def _valid(world: WorldSpec, xy: np.ndarray, clearance_m: float, *,
           start: bool = False) -> np.ndarray:
    """Which points of ``xy`` lie ``clearance_m`` inside the bounds and from every obstacle;
    a ``start`` also as far (plus the person's radius) from the person's first
    ``PERSON_CLEAR_S`` seconds of walk."""
    xmin, ymin, xmax, ymax = world.bounds
    inside = ((xy[:, 0] >= xmin + clearance_m) & (xy[:, 0] <= xmax - clearance_m)
              & (xy[:, 1] >= ymin + clearance_m) & (xy[:, 1] <= ymax - clearance_m))
    ok = np.zeros(len(xy), dtype=bool)
    if inside.any():
        ok[inside] = world.clearance(xy[inside]) >= clearance_m
    if start and world.person is not None and ok.any():
        walk = _early_walk(world.person)
        gap = np.hypot(xy[ok, None, 0] - walk[None, :, 0], xy[ok, None, 1] - walk[None, :, 1])
        ok[ok] = gap.min(axis=1) >= clearance_m + world.person.radius_m
    return ok


@cache
def _early_walk(person: PersonSpec) -> np.ndarray:
    """Where ``person`` walks in an episode's first ``PERSON_CLEAR_S`` seconds (k × 2, m)."""
    return person.positions(PERSON_CLEAR_S)


def sample_start_goal(world: WorldSpec, rng: np.random.Generator, *, clearance_m: float,
                      min_distance_m: float = _MIN_GOAL_DISTANCE_M,
                      max_distance_m: float = math.inf,
                      max_detour: float = math.inf, planner: PathPlanner | None = None,
                      max_tries: int = 10_000) -> tuple[Pose2D, tuple[float, float]]:
    """A start pose and a goal point, both ``clearance_m`` (m) from obstacles and the bounds'
    edges, ``min_distance_m`` to ``max_distance_m`` apart. With a ``planner`` (a path check)
    the pair has a collision-free path for the planner's robot, at most ``max_detour`` times
    the straight line (which needs the planner).

    A world's ``spawn_poses`` and ``goal_points`` are the only candidates when present (a
    vineyard's lane ends, a spawn keeping its yaw); with as many goals as spawns the goal of
    the same lane is preferred. Elsewhere points are drawn uniformly and the start's yaw too.
    """
    require(math.isfinite(clearance_m) and clearance_m >= 0, "sampling.clearance_m",
            clearance_m, "a finite distance >= 0 m")
    check_pair_filter(min_distance_m, max_distance_m, max_detour, prefix="sampling.")
    require(planner is not None or max_detour == math.inf, "sampling.max_detour", max_detour,
            "inf without a planner (a finite detour needs one to measure it)")
    require(isinstance(max_tries, int) and max_tries >= 1, "sampling.max_tries", max_tries,
            "an integer >= 1")
    search = _PairSearch(world, clearance_m, min_distance_m, max_distance_m, max_detour, planner)
    spawn_xy = np.array([(p.x, p.y) for p in world.spawn_poses], dtype=float).reshape(-1, 2)
    goal_xy = np.array(world.goal_points, dtype=float).reshape(-1, 2)
    found = None
    if len(spawn_xy) and len(spawn_xy) == len(goal_xy):
        found = search.same_lane(rng, spawn_xy, goal_xy)
    found = found or search.drawn(rng, spawn_xy, goal_xy, max_tries)
    if found is None:
        raise search.failure(max_tries)
    return found


@dataclass
class _PairSearch:
    """One ``sample_start_goal`` call: its limits, its path check and the searches it ran."""

    world: WorldSpec
    clearance_m: float
    min_distance_m: float
    max_distance_m: float
    max_detour: float
    planner: PathPlanner | None
    checks: int = 0  # path searches run, shared by every round

    def first_fit(self, s_xy: np.ndarray, g_xy: np.ndarray, pairs: np.ndarray) -> int | None:
        """The first candidate (row of ``pairs``: start, goal index) the planner accepts."""
        for k, (i, j) in enumerate(pairs):
            if self.planner is None:
                return k
            if self.checks >= MAX_PATH_CHECKS:
                return None
            self.checks += 1
            limit = self.max_detour * math.dist(s_xy[i], g_xy[j])
            if self.planner.length(s_xy[i], g_xy[j], max_length_m=limit) < math.inf:
                return k
        return None

    def apart(self, s_xy: np.ndarray, g_xy: np.ndarray) -> np.ndarray:
        d = np.hypot(s_xy[:, None, 0] - g_xy[None, :, 0], s_xy[:, None, 1] - g_xy[None, :, 1])
        return (d >= self.min_distance_m) & (d <= self.max_distance_m)

    def same_lane(self, rng: np.random.Generator, spawn_xy: np.ndarray,
                  goal_xy: np.ndarray) -> tuple[Pose2D, tuple[float, float]] | None:
        """A spawn and the goal of its own lane, lanes in a random order."""
        lanes = rng.permutation(len(spawn_xy))
        d = np.hypot(*(goal_xy[lanes] - spawn_xy[lanes]).T)
        ok = (_valid(self.world, spawn_xy[lanes], self.clearance_m, start=True)
              & _valid(self.world, goal_xy[lanes], self.clearance_m)
              & (d >= self.min_distance_m) & (d <= self.max_distance_m))
        found = self.first_fit(spawn_xy, goal_xy, np.repeat(lanes[ok], 2).reshape(-1, 2))
        if found is None:
            return None
        lane = int(lanes[ok][found])
        return self.world.spawn_poses[lane], (float(goal_xy[lane, 0]), float(goal_xy[lane, 1]))

    def drawn(self, rng: np.random.Generator, spawn_xy: np.ndarray, goal_xy: np.ndarray,
              max_tries: int) -> tuple[Pose2D, tuple[float, float]] | None:
        """A pair from the fixed candidates (in a random order) or points drawn in rounds."""
        world, clearance_m = self.world, self.clearance_m
        starts = _shuffled_valid(world, rng, spawn_xy, clearance_m,  # None: drawn each round
                                 start=True)
        goals = _shuffled_valid(world, rng, goal_xy, clearance_m)
        xmin, ymin, xmax, ymax = world.bounds
        low = (xmin + clearance_m, ymin + clearance_m)
        high = (xmax - clearance_m, ymax - clearance_m)
        exhausted = (starts is not None and goals is not None) or any(
            fixed is not None and not len(fixed[0]) for fixed in (starts, goals))
        drawn = 0
        while drawn < max_tries and low[0] <= high[0] and low[1] <= high[1]:
            n = min(BATCH, max_tries - drawn)
            drawn += n * ((starts is None) + (goals is None))
            s_xy, s_index = starts or (_draw(world, rng, low, high, n, clearance_m, start=True),
                                       None)
            g_xy, _ = goals or (_draw(world, rng, low, high, n, clearance_m), None)
            rows, cols = np.nonzero(self.apart(s_xy, g_xy))
            if self.planner is not None and len(rows):  # each start's first two goals first
                rank = np.arange(len(rows)) - np.searchsorted(rows, rows)
                order = np.lexsort((rows, np.minimum(rank, 2)))
                rows, cols = rows[order], cols[order]
            found = self.first_fit(s_xy, g_xy, np.stack([rows, cols], axis=1))
            if found is not None:
                i, j = int(rows[found]), int(cols[found])
                goal = (float(g_xy[j, 0]), float(g_xy[j, 1]))
                if s_index is not None:
                    return world.spawn_poses[int(s_index[i])], goal
                yaw = float(rng.uniform(-math.pi, math.pi))
                return Pose2D(float(s_xy[i, 0]), float(s_xy[i, 1]), yaw), goal
            if exhausted or self.checks >= MAX_PATH_CHECKS:
                return None  # fixed candidates only, or none free: drawing again changes nothing
        return None

    def failure(self, max_tries: int) -> WorldError:
        wanted = f"{self.min_distance_m} m" + (
            f" to {self.max_distance_m} m" if self.max_distance_m < math.inf else "")
        path = ("" if self.planner is None else f", a collision-free path at most "
                f"{self.max_detour} times the straight line ({self.checks} paths searched)")
        return WorldError(f"world {self.world.name!r}: no start and goal with clearance "
                          f"{self.clearance_m} m and {wanted} apart{path} found in {max_tries} "
                          "tries; lower the clearance or the distance, or free some space")


def sample_pairs(world: WorldSpec, count: int, rng: np.random.Generator, *, clearance_m: float,
                 kind: PairKind, planner: PathPlanner | None = None,
                 min_goal_distance_m: float = _MIN_GOAL_DISTANCE_M,
                 ) -> list[tuple[Pose2D, tuple[float, float]]]:
    """``count`` pairs of ``kind`` drawn in turn from ``rng`` (deterministic for one rng
    state); ``min_goal_distance_m`` stands in for a kind without a minimum. With a
    ``planner`` every pair has a collision-free path."""
    require(isinstance(count, int) and count >= 0, "sampling.count", count, "an integer >= 0")
    low = kind.min_distance_m if kind.min_distance_m is not None else min_goal_distance_m
    return [sample_start_goal(world, rng, clearance_m=clearance_m, min_distance_m=low,
                              max_distance_m=kind.max_distance_m, max_detour=kind.max_detour,
                              planner=planner) for _ in range(count)]


def _draw(world: WorldSpec, rng: np.random.Generator, low: tuple[float, float],
          high: tuple[float, float], n: int, clearance_m: float, *,
          start: bool = False) -> np.ndarray:
    """The valid ones (``_valid``) of ``n`` points drawn uniformly in the rectangle
    ``low``-``high``."""
    xy = rng.uniform(low, high, (n, 2))
    return xy[_valid(world, xy, clearance_m, start=start)]


def _shuffled_valid(world: WorldSpec, rng: np.random.Generator, xy: np.ndarray,
                    clearance_m: float, *,
                    start: bool = False) -> tuple[np.ndarray, np.ndarray] | None:
    """The valid points (``_valid``) of a fixed candidate list and their indices, in random
    order; None for an empty list (points are then drawn)."""
    if not len(xy):
        return None
    order = rng.permutation(len(xy))
    order = order[_valid(world, xy[order], clearance_m, start=start)]
    return xy[order], order


def check_free(world: WorldSpec, xy: tuple[float, float] | np.ndarray, *, clearance_m: float,
               what: str) -> None:
    """Raise ``WorldError`` unless a user's ``what`` ("start", "goal") point lies inside the
    bounds and at least ``clearance_m`` (m) from every obstacle."""
    x, y = float(xy[0]), float(xy[1])
    xmin, ymin, xmax, ymax = world.bounds
    if not (xmin <= x <= xmax and ymin <= y <= ymax):
        raise WorldError(f"{what}: ({x:.3f}, {y:.3f}) is outside the bounds {world.bounds} of "
                         f"world {world.name!r}")
    found = float(world.clearance(np.array([[x, y]]))[0])
    if found < clearance_m:
        raise WorldError(f"{what}: ({x:.3f}, {y:.3f}) is {found:.3f} m from the nearest "
                         f"obstacle of world {world.name!r}; expected at least {clearance_m} m")
