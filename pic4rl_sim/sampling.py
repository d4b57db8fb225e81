"""Starts and goals where a robot fits: sampled for each episode, or checked when given.

Sampling draws candidates in batches and tests each batch with one ``clearance`` call, so an
episode reset costs about a millisecond. Results depend only on the world and the rng state.
"""

from __future__ import annotations

import math

import numpy as np

from .errors import WorldError, require
from .geometry import Pose2D
from .world import WorldSpec

BATCH = 256


def _valid(world: WorldSpec, xy: np.ndarray, clearance_m: float) -> np.ndarray:
    """Which points of ``xy`` lie ``clearance_m`` inside the bounds and from every obstacle."""
    xmin, ymin, xmax, ymax = world.bounds
    inside = ((xy[:, 0] >= xmin + clearance_m) & (xy[:, 0] <= xmax - clearance_m)
              & (xy[:, 1] >= ymin + clearance_m) & (xy[:, 1] <= ymax - clearance_m))
    ok = np.zeros(len(xy), dtype=bool)
    if inside.any():
        ok[inside] = world.clearance(xy[inside]) >= clearance_m
    return ok


def sample_start_goal(world: WorldSpec, rng: np.random.Generator, *, clearance_m: float,
                      min_distance_m: float = 1.0, max_tries: int = 10_000,
                      ) -> tuple[Pose2D, tuple[float, float]]:
    """A start pose and a goal point, both ``clearance_m`` (m) from obstacles and the bounds'
    edges, at least ``min_distance_m`` apart.

    A world's ``spawn_poses`` and ``goal_points`` are the only candidates when present (a
    vineyard's lane ends, a spawn keeping its yaw); with as many goals as spawns the goal of
    the same lane is preferred. Elsewhere points are drawn uniformly and the start's yaw too.
    """
    require(math.isfinite(clearance_m) and clearance_m >= 0, "sampling.clearance_m",
            clearance_m, "a finite distance >= 0 m")
    require(math.isfinite(min_distance_m) and min_distance_m >= 0, "sampling.min_distance_m",
            min_distance_m, "a finite distance >= 0 m")
    require(isinstance(max_tries, int) and max_tries >= 1, "sampling.max_tries", max_tries,
            "an integer >= 1")
    spawn_xy = np.array([(p.x, p.y) for p in world.spawn_poses], dtype=float).reshape(-1, 2)
    goal_xy = np.array(world.goal_points, dtype=float).reshape(-1, 2)
    if len(spawn_xy) and len(spawn_xy) == len(goal_xy):
        lanes = rng.permutation(len(spawn_xy))
        far = np.hypot(*(goal_xy[lanes] - spawn_xy[lanes]).T) >= min_distance_m
        ok = _valid(world, spawn_xy[lanes], clearance_m) & _valid(world, goal_xy[lanes],
                                                                   clearance_m) & far
        if ok.any():
            lane = int(lanes[np.argmax(ok)])
            return world.spawn_poses[lane], (float(goal_xy[lane, 0]), float(goal_xy[lane, 1]))
    # Fixed candidates in a random order; None where points are drawn each round instead.
    starts = _shuffled_valid(world, rng, spawn_xy, clearance_m)
    goals = _shuffled_valid(world, rng, goal_xy, clearance_m)
    xmin, ymin, xmax, ymax = world.bounds
    low, high = (xmin + clearance_m, ymin + clearance_m), (xmax - clearance_m, ymax - clearance_m)
    exhausted = (starts is not None and goals is not None) or any(
        fixed is not None and not len(fixed[0]) for fixed in (starts, goals))
    drawn = 0
    while drawn < max_tries and low[0] <= high[0] and low[1] <= high[1]:
        n = min(BATCH, max_tries - drawn)
        drawn += n * ((starts is None) + (goals is None))
        s_xy, s_index = starts or (_draw(world, rng, low, high, n, clearance_m), None)
        g_xy, _ = goals or (_draw(world, rng, low, high, n, clearance_m), None)
        far = np.hypot(s_xy[:, None, 0] - g_xy[None, :, 0],
                       s_xy[:, None, 1] - g_xy[None, :, 1]) >= min_distance_m
        if far.any():
            i, j = np.unravel_index(int(np.argmax(far)), far.shape)
            goal = (float(g_xy[j, 0]), float(g_xy[j, 1]))
            if s_index is not None:
                return world.spawn_poses[int(s_index[i])], goal
            yaw = float(rng.uniform(-math.pi, math.pi))
            return Pose2D(float(s_xy[i, 0]), float(s_xy[i, 1]), yaw), goal
        if exhausted:
            break  # fixed candidates only, or none of them free: drawing again changes nothing
    raise WorldError(f"world {world.name!r}: no start and goal with clearance {clearance_m} m "
                     f"and {min_distance_m} m apart found in {max_tries} tries; lower the "
                     "clearance or the distance, or free some space")


def _draw(world: WorldSpec, rng: np.random.Generator, low: tuple[float, float],
          high: tuple[float, float], n: int, clearance_m: float) -> np.ndarray:
    """The valid ones of ``n`` points drawn uniformly in the rectangle ``low``-``high``."""
    xy = rng.uniform(low, high, (n, 2))
    return xy[_valid(world, xy, clearance_m)]


def _shuffled_valid(world: WorldSpec, rng: np.random.Generator, xy: np.ndarray,
                    clearance_m: float) -> tuple[np.ndarray, np.ndarray] | None:
    """The valid points of a fixed candidate list and their indices, in random order; None
    for an empty list (points are then drawn)."""
    if not len(xy):
        return None
    order = rng.permutation(len(xy))
    order = order[_valid(world, xy[order], clearance_m)]
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
