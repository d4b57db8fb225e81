"""The ``rooms`` world family (exploration's larger house): every free region reachable, by the
robot too; the free-area fact the explore task writes equals the house's floor less its walls
and furniture, 2 to 4 times ``indoor``'s; rooms of jittered sizes; doors that make a tree or
more; the held-out layouts no training env may draw; bad parameters named."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import yaml

from pic4rl_base.errors import ConfigError
from pic4rl_bridge.perception.frontiers import component
from pic4rl_bridge.tasks.explore import FREE_RESOLUTION_M, free_area_m2
from pic4rl_sim.engine.paths import clearance_grid
from pic4rl_sim.engine.worlds.generators import make_world
from pic4rl_sim.engine.worlds.held_out import HELD_OUT
from pic4rl_sim.engine.worlds.rooms import TEST_LAYOUTS
from pic4rl_sim.engine.worlds.spec import WorldSpec

REPO = Path(__file__).resolve().parents[4]
SEEDS = [0, 1, 2, 1000, 1007]
JACKAL_RADIUS_M = 0.33  # circumscribed, as the explore baselines plan with it


def _inside(world: WorldSpec) -> list:
    xmin, ymin, xmax, ymax = world.bounds
    return [b for b in world.boxes if xmin < b.x < xmax and ymin < b.y < ymax]


@pytest.mark.parametrize("seed", SEEDS)
def test_every_free_region_is_reachable_by_the_robot_too(seed: int) -> None:
    world = make_world("rooms", seed=seed)
    clear = clearance_grid(world, FREE_RESOLUTION_M)
    for threshold, what in ((0.0, "floor"), (JACKAL_RADIUS_M, "robot's centre")):
        free = clear > threshold
        rows, cols = np.nonzero(free)
        corner = (int(rows[0]), int(cols[0]))
        assert np.count_nonzero(component(free, corner)) == np.count_nonzero(free), what
    # from opposite corners the explore task counts the same floor: all of it
    xmin, ymin, xmax, ymax = world.bounds
    total = np.count_nonzero(clear > 0) * FREE_RESOLUTION_M**2
    assert free_area_m2(world, (xmin + 0.3, ymin + 0.3)) == pytest.approx(total, abs=1e-9)
    assert free_area_m2(world, (xmax - 0.3, ymax - 0.3)) == pytest.approx(total, abs=1e-9)


@pytest.mark.parametrize("seed", SEEDS)
def test_the_free_area_fact_is_the_floor_less_walls_and_furniture(seed: int) -> None:
    world = make_world("rooms", seed=seed)
    xmin, ymin, xmax, ymax = world.bounds
    solid = sum(b.size_x_m * b.size_y_m for b in _inside(world))
    analytic = (xmax - xmin) * (ymax - ymin) - solid  # wall crossings counted twice: 0.01 m²
    fact = free_area_m2(world, (0.5 * (xmin + xmax), 0.5 * (ymin + ymax)))
    assert fact == pytest.approx(analytic, rel=0.005)
    indoor = free_area_m2(make_world("indoor", seed=seed), (0.0, -4.0))
    assert 2.0 * indoor < fact < 4.0 * indoor


def test_rooms_differ_in_size_and_doors_make_a_tree_or_more() -> None:
    world = make_world("rooms", seed=3)
    p = world.params
    rooms = int(p["rooms_x"] * p["rooms_y"])
    neighbour_walls = int((p["rooms_x"] - 1) * p["rooms_y"] + p["rooms_x"] * (p["rooms_y"] - 1))
    counts = [make_world("rooms", seed=s).params["doors"] for s in range(10)]
    # a spanning tree has rooms - 1 doors; the extra ones (loops) vary with the seed
    assert all(rooms - 1 <= c <= neighbour_walls for c in counts) and len(set(counts)) > 1
    xs = sorted({round(b.x, 6) for b in _inside(world) if b.kind == "wall"
                 and b.size_x_m < b.size_y_m})
    widths = np.diff([world.bounds[0], *xs, world.bounds[2]])
    assert len(widths) == p["rooms_x"] and widths.max() - widths.min() > 0.1
    closed = make_world("rooms", seed=3, extra_door_fraction=0.0).params["doors"]
    assert closed == rooms - 1


def test_held_out_layouts_are_never_trained_on() -> None:
    assert HELD_OUT["rooms"].variants() == TEST_LAYOUTS == tuple(range(1000, 1020))
    env = yaml.safe_load((REPO / "config" / "env_explore_rooms.yaml").read_text())
    text = env["nav_env"]["ros__parameters"]["episodes"]["world_variants"]
    low, high = (int(v) for v in text.split(":"))
    assert env["sim"]["ros__parameters"]["world"] == "rooms"
    assert not set(range(low, high)) & set(TEST_LAYOUTS) and high - low >= 100


def test_bad_params_are_named() -> None:
    with pytest.raises(ConfigError, match=r"world\.rooms\.size_x_m"):
        make_world("rooms", rooms_x=8)
    with pytest.raises(ConfigError, match=r"world\.rooms\.extra_door_fraction"):
        make_world("rooms", extra_door_fraction=1.5)
