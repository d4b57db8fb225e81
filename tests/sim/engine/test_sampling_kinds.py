"""Start-goal pairs of a kind: distance range and detour bound held, no pair without a path
when a path check is asked for, determinism, the plain sampler unchanged, clear errors."""

from __future__ import annotations

import math
import re

import numpy as np
import pytest

from pic4rl_base.errors import ConfigError
from pic4rl_sim.engine.paths import PathPlanner
from pic4rl_sim.engine.robot_specs import JACKAL
from pic4rl_sim.engine.sampling import (PAIR_KINDS, PairKind, check_pair_filter, sample_pairs,
                                        sample_start_goal)
from pic4rl_sim.engine.worlds.generators import make_world
from pic4rl_sim.engine.worlds.spec import Box, WorldSpec
from pic4rl_sim.errors import WorldError

INDOOR = make_world("indoor", seed=0)
RADIUS = JACKAL.footprint.bounding_radius_m
CLEARANCE = RADIUS + 0.2


def test_paper_pairs_are_4_to_8_m_apart_with_a_detour_of_at_most_1_3() -> None:
    planner = PathPlanner(INDOOR, robot_radius_m=RADIUS)
    pairs = sample_pairs(INDOOR, 12, np.random.default_rng(5), clearance_m=CLEARANCE,
                         kind=PAIR_KINDS["paper"], planner=planner)
    assert len(set(pairs)) == 12
    for start, goal in pairs:
        straight = math.dist(start[:2], goal)
        assert 4.0 <= straight <= 8.0
        assert planner.length(start[:2], goal) <= 1.3 * straight
        assert (INDOOR.clearance(np.array([start[:2], goal])) >= CLEARANCE).all()
    again = sample_pairs(INDOOR, 12, np.random.default_rng(5), clearance_m=CLEARANCE,
                         kind=PAIR_KINDS["paper"], planner=planner)
    assert again == pairs


def test_without_filters_the_sampler_draws_as_before() -> None:
    """The kind ``any`` without a path check is the plain sampler: same rng, same pairs."""
    plain = [sample_start_goal(INDOOR, rng, clearance_m=CLEARANCE)
             for rng in [np.random.default_rng(3)] for _ in range(5)]
    kind = sample_pairs(INDOOR, 5, np.random.default_rng(3), clearance_m=CLEARANCE,
                        kind=PAIR_KINDS["any"])
    assert kind == plain


def two_rooms() -> WorldSpec:
    """Two rooms split by a full wall at x = 0: no path between them."""
    return WorldSpec("split", (-4.0, -2.0, 4.0, 2.0), boxes=(Box(0.0, 0.0, 0.2, 4.0, 1.0),))


def test_with_a_path_check_no_pair_crosses_a_closed_wall() -> None:
    world = two_rooms()
    planner = PathPlanner(world, robot_radius_m=0.2)
    rng = np.random.default_rng(0)
    for _ in range(10):
        start, goal = sample_start_goal(world, rng, clearance_m=0.3, min_distance_m=1.0,
                                        planner=planner)
        assert (start.x < 0) == (goal[0] < 0)  # the same room
    unchecked = [sample_start_goal(world, rng, clearance_m=0.3) for _ in range(30)]
    assert any((s.x < 0) != (g[0] < 0) for s, g in unchecked)  # the check is what keeps them


def test_a_kind_that_cannot_fit_names_the_world_and_the_filter() -> None:
    world = two_rooms()  # rooms 4 m wide: never 5 m apart in one room
    with pytest.raises(WorldError, match=r"'split'.*5.0 m to 8.0 m apart, a collision-free"):
        sample_start_goal(world, np.random.default_rng(0), clearance_m=0.3, min_distance_m=5.0,
                          max_distance_m=8.0, max_detour=1.3,
                          planner=PathPlanner(world, robot_radius_m=0.2))


@pytest.mark.parametrize(("kwargs", "key"), [
    ({"max_detour": 1.3}, "sampling.max_detour"),  # no planner to measure it with
    ({"max_detour": 0.9, "planner": "p"}, "sampling.max_detour"),
    ({"min_distance_m": 3.0, "max_distance_m": 2.0}, "sampling.max_distance_m"),
])
def test_bad_filters_are_refused(kwargs: dict, key: str) -> None:
    if kwargs.get("planner") == "p":
        kwargs["planner"] = PathPlanner(INDOOR, robot_radius_m=RADIUS, resolution_m=0.2)
    with pytest.raises(ConfigError, match=key):
        sample_start_goal(INDOOR, np.random.default_rng(0), clearance_m=CLEARANCE, **kwargs)
    with pytest.raises(ConfigError, match="pairs.max_detour"):
        PairKind(max_detour=0.5)
    with pytest.raises(ConfigError, match="pairs.max_distance_m"):
        PairKind(min_distance_m=4.0, max_distance_m=1.0)


@pytest.mark.parametrize(("values", "message"), [
    ((-1.0, 5.0, 1.2), "min_distance_m: -1.0 is invalid; expected a finite distance >= 0 m"),
    ((math.inf, math.inf, 1.2), "min_distance_m: inf is invalid"),
    ((4.0, 2.0, 1.2), "max_distance_m: 2.0 is invalid; expected a distance >= "
                      "min_distance_m=4.0 m"),
    ((1.0, math.nan, 1.2), "max_distance_m: nan is invalid"),
    ((1.0, 5.0, 0.9), "max_detour: 0.9 is invalid; expected a ratio >= 1"),
])
def test_the_one_pair_filter_check_names_the_callers_key(values: tuple, message: str) -> None:
    """Every pair filter (a kind, the sampler, the env's section and reset options, a
    curriculum stage) goes through ``check_pair_filter``, with its own key names."""
    for prefix in ("pairs.", "episodes.", "curriculum.", "reset options: "):
        with pytest.raises(ConfigError, match="^" + re.escape(prefix + message)):
            check_pair_filter(*values, prefix=prefix)
    check_pair_filter(2.0, 2.0, 1.0, prefix="x.")  # the bounds themselves are valid

