"""The ``barn`` world against its shipped data file, and the ``barn_like`` generator: seeded,
a path in every world of a sample, parameters out of range refused."""

from __future__ import annotations

import gzip
import json
import math

import numpy as np
import pytest

from pic4rl_base.errors import ConfigError
from pic4rl_sim.engine.paths import shortest_path_length
from pic4rl_sim.engine.robot_specs import ROBOT_TABLE
from pic4rl_sim.engine.sampling import sample_start_goal
from pic4rl_sim.engine.worlds.barn import (DATA, LICENSE, WORLDS, challenge_test_worlds,
                                           start_and_goal)
from pic4rl_sim.engine.worlds.generators import make_world

JACKAL_RADIUS_M = ROBOT_TABLE["jackal"].footprint.bounding_radius_m


@pytest.fixture(scope="module")
def data() -> dict:
    """The data file read here on its own, not through the module under test."""
    with gzip.open(DATA, "rt", encoding="utf-8") as f:
        return json.load(f)


def test_the_data_ships_with_its_license() -> None:
    assert "MIT License" in LICENSE.read_text() and "Zifan Xu" in LICENSE.read_text()


@pytest.mark.parametrize("index", [0, 1, 150, 299])
def test_the_cylinders_are_the_data_files(data: dict, index: int) -> None:
    world = make_world("barn", seed=index)
    expected = data["worlds"][index]
    assert expected["index"] == index
    got = np.array([(c.x, c.y) for c in world.cylinders])
    assert len(got) == len(expected["cylinders"]) > 150
    np.testing.assert_array_equal(got, np.array(expected["cylinders"]))
    assert {(c.radius_m, c.height_m) for c in world.cylinders} == {(0.075, 1.0)}
    assert world.params["reference_path_length_m"] == expected["reference_path_length_m"]
    xmin, ymin, xmax, ymax = world.bounds  # the bounds enclose every cylinder and the goal
    assert xmin < got[:, 0].min() and got[:, 0].max() < xmax
    assert ymin < got[:, 1].min() and max(got[:, 1].max(), 13.0) < ymax


def test_the_start_and_goal_are_the_challenges(data: dict) -> None:
    start, goal = start_and_goal()
    assert tuple(start) == (-2.25, 3.0, 1.57) == tuple(data["start_pose"])
    assert goal == (-2.25, 13.0)
    assert challenge_test_worlds() == tuple(range(0, 300, 6))
    world = make_world("barn", seed=6)
    assert world.spawn_poses == (start,) and world.goal_points == (goal,)
    # the simulator's own sampling can only give the challenge's pair
    drawn = sample_start_goal(world, np.random.default_rng(3), clearance_m=JACKAL_RADIUS_M + 0.1)
    assert drawn == (start, goal)


def test_the_start_is_collision_free_in_all_300_worlds() -> None:
    start, goal = start_and_goal()
    for index in range(WORLDS):
        world = make_world("barn", seed=index)
        gaps = world.clearance(np.array([start[:2], goal]))
        assert gaps.min() > JACKAL_RADIUS_M, (index, gaps)


@pytest.mark.parametrize("index", [0, 6, 294])
def test_the_planner_finds_the_shortest_path(index: int) -> None:
    start, goal = start_and_goal()
    length = shortest_path_length(make_world("barn", seed=index), start[:2], goal,
                                  robot_radius_m=JACKAL_RADIUS_M)
    assert 10.0 <= length < 14.0  # at least the straight 10 m


@pytest.mark.bad_input
@pytest.mark.parametrize("index", [300, 1000])
def test_a_bad_index_names_the_range(index: int) -> None:
    with pytest.raises(ConfigError) as err:
        make_world("barn", seed=index)
    assert str(err.value) == (f"world_variant: {index} is invalid; expected a BARN world index "
                              "in [0, 299] (world: barn)")


def test_barn_like_is_seeded() -> None:
    a, b = make_world("barn_like", seed=4), make_world("barn_like", seed=4)
    assert a == b and a.cylinders == b.cylinders
    assert a.cylinders != make_world("barn_like", seed=5).cylinders
    assert make_world("barn_like", seed=4, fill_fraction=0.5).cylinders != a.cylinders


@pytest.mark.parametrize("params", [{}, {"fill_fraction": 0.6, "fill_threshold": 3,
                                         "smoothing_steps": 3, "wander": 1.0}])
def test_every_barn_like_world_of_a_sample_has_a_path(params: dict) -> None:
    start, goal = start_and_goal()
    for seed in range(6):
        world = make_world("barn_like", seed=seed, **params)
        assert world.params["filled_fraction"] > 0.03
        length = shortest_path_length(world, start[:2], goal, robot_radius_m=JACKAL_RADIUS_M)
        assert math.isfinite(length), (seed, params)


def test_barn_like_fills_about_as_much_as_barn(data: dict) -> None:
    filled = [make_world("barn_like", seed=s).params["filled_fraction"] for s in range(20)]
    field = [(len(w["cylinders"]) - 156) / (28 * 30) for w in data["worlds"]]  # less enclosure
    assert min(field) <= np.mean(filled) <= max(field)


@pytest.mark.bad_input
@pytest.mark.parametrize(("key", "value", "expected"), [
    ("fill_fraction", 0.7, "a value in [0, 0.6]"),
    ("corridor_cells", 4, "a value in [5, 28]"),
    ("fill_threshold", 9, "a value in [1, 8]"),
])
def test_barn_like_parameters_out_of_range_are_refused(key: str, value: float,
                                                       expected: str) -> None:
    with pytest.raises(ConfigError) as err:
        make_world("barn_like", **{key: value})
    assert str(err.value) == f"world.barn_like.{key}: {value} is invalid; expected {expected}"
