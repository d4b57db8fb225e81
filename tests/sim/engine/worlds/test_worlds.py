"""World generators: determinism, geometry measured on the shapes made, reachability, MJCF."""

from __future__ import annotations

import math
from collections import deque

import numpy as np
import pytest

from pic4rl_base.errors import ConfigError
from pic4rl_base.schema import param_names, specs, to_params
from pic4rl_sim.engine.worlds.generators import (WORLD_TABLE, ObstaclesParams, make_world, obstacles,
                                                 world_params)
from pic4rl_sim.engine.worlds.mjcf import world_from_mjcf
from pic4rl_sim.engine.worlds.spec import Box, Cylinder, WorldSpec, clearance
from pic4rl_sim.errors import WorldError

ROBOT_RADIUS_M = 0.25
KINDS = sorted(WORLD_TABLE)


def outline(shape: Box | Cylinder, step_m: float = 0.02) -> np.ndarray:
    """Points on the footprint's edge (n, 2)."""
    if isinstance(shape, Cylinder):
        a = np.linspace(0, 2 * math.pi, 64, endpoint=False)
        return np.column_stack([shape.x + shape.radius_m * np.cos(a),
                                shape.y + shape.radius_m * np.sin(a)])
    hx, hy = shape.size_x_m / 2, shape.size_y_m / 2
    corners = np.array([(-hx, -hy), (hx, -hy), (hx, hy), (-hx, hy), (-hx, -hy)])
    local = np.concatenate([a + np.linspace(0, 1, max(2, int(np.hypot(*(b - a)) / step_m)))[:, None]
                            * (b - a) for a, b in zip(corners[:-1], corners[1:])])
    c, s = math.cos(shape.yaw_rad), math.sin(shape.yaw_rad)
    return np.column_stack([shape.x + c * local[:, 0] - s * local[:, 1],
                            shape.y + s * local[:, 0] + c * local[:, 1]])


def grid(world: WorldSpec, step_m: float = 0.1) -> tuple[np.ndarray, np.ndarray]:
    """Cell centres (nx, ny, 2) over the bounds and their clearance (nx, ny)."""
    xmin, ymin, xmax, ymax = world.bounds
    gx, gy = np.meshgrid(np.arange(xmin + step_m / 2, xmax, step_m),
                         np.arange(ymin + step_m / 2, ymax, step_m), indexing="ij")
    xy = np.stack([gx, gy], axis=-1)
    return xy, world.clearance(xy.reshape(-1, 2)).reshape(gx.shape)


def flood(free: np.ndarray, start: tuple[int, int]) -> np.ndarray:
    """Cells reachable from ``start`` through free cells (8-neighbours)."""
    reached = np.zeros_like(free)
    reached[start] = True
    todo = deque([start])
    while todo:
        i, j = todo.popleft()
        for di in (-1, 0, 1):
            for dj in (-1, 0, 1):
                n = (i + di, j + dj)
                if (0 <= n[0] < free.shape[0] and 0 <= n[1] < free.shape[1] and free[n]
                        and not reached[n]):
                    reached[n] = True
                    todo.append(n)
    return reached


@pytest.mark.parametrize("kind", KINDS)
def test_same_seed_gives_the_same_world_and_other_seeds_other_worlds(kind: str) -> None:
    a, b = make_world(kind, seed=3), make_world(kind, seed=3)
    assert a == b and a.params == b.params and a.seed == 3
    others = {make_world(kind, seed=s) for s in range(4, 9)}
    assert a not in others and len(others) == 5
    assert {k: a.params[k] for k in param_names(WORLD_TABLE[kind].params)} == to_params(
        WORLD_TABLE[kind].params())


@pytest.mark.parametrize("kind", KINDS)
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_four_walls_enclose_every_obstacle(kind: str, seed: int) -> None:
    curved = {"row_radius_m": 7.0} if kind == "vineyard" and seed == 2 else {}
    world = make_world(kind, seed=seed, **curved)
    xmin, ymin, xmax, ymax = world.bounds
    shapes = world.boxes + world.cylinders
    outside = []
    for shape in shapes:
        pts = outline(shape)
        inside = ((pts[:, 0] >= xmin - 1e-9) & (pts[:, 0] <= xmax + 1e-9)
                  & (pts[:, 1] >= ymin - 1e-9) & (pts[:, 1] <= ymax + 1e-9))
        if not inside.all():
            outside.append(shape)
    assert len(outside) == 4 and all(s.kind == "wall" for s in outside)
    # A ring just outside the bounds lies entirely inside the walls: nothing can leave.
    t = np.linspace(0, 1, 400)[:, None]
    d = 0.05
    corners = np.array([(xmin - d, ymin - d), (xmax + d, ymin - d), (xmax + d, ymax + d),
                        (xmin - d, ymax + d), (xmin - d, ymin - d)])
    ring = np.concatenate([a + t * (b - a) for a, b in zip(corners[:-1], corners[1:])])
    assert (clearance(ring, tuple(outside), ()) < 0).all()
    assert len(shapes) <= 300


@pytest.mark.parametrize("seed", [0, 1, 2, 3, 4])
def test_indoor_every_room_is_reachable(seed: int) -> None:
    world = make_world("indoor", seed=seed)
    xy, clear = grid(world)
    free = clear > ROBOT_RADIUS_M
    corridor = np.argwhere(free & (xy[..., 1] < world.bounds[1] + 1.0))[0]
    reached = flood(free, tuple(corridor))
    assert reached.sum() == free.sum()  # no pocket of free space is shut off
    p = world.params
    room_x = p["size_x_m"] / p["rooms_x"]
    room_y = (p["size_y_m"] - p["corridor_width_m"]) / p["rooms_y"]
    for i in range(int(p["rooms_x"])):
        for j in range(int(p["rooms_y"])):
            x0 = world.bounds[0] + i * room_x
            y0 = world.bounds[1] + p["corridor_width_m"] + j * room_y
            in_room = ((xy[..., 0] > x0) & (xy[..., 0] < x0 + room_x)
                       & (xy[..., 1] > y0) & (xy[..., 1] < y0 + room_y))
            assert (reached & in_room).sum() * 0.01 > 0.3 * room_x * room_y


def opening_width(world: WorldSpec, x: float, y: float, along_x: bool) -> float:
    """Length of the free run along a wall line through the opening centred at (x, y)."""
    s = np.arange(-2.0, 2.0, 0.001)
    pts = np.column_stack([x + s, np.full_like(s, y)] if along_x else [np.full_like(s, x), y + s])
    free = world.clearance(pts) > 0
    centre = len(s) // 2
    assert free[centre]
    lo = centre - np.argmin(free[centre::-1])
    hi = centre + np.argmin(free[centre:])
    return (hi - lo) * 0.001


@pytest.mark.parametrize(("seed", "width_m"), [(0, 0.7), (1, 0.7), (2, 0.6), (3, 0.8)])
def test_indoor_narrow_passage_has_the_width_asked_and_a_robot_fits(seed: int,
                                                                    width_m: float) -> None:
    world = make_world("indoor", seed=seed, narrow_width_m=width_m)
    p = world.params
    measured = opening_width(world, p["narrow_x_m"], p["narrow_y_m"], p["narrow_along_x"] == 1)
    assert 0.6 - 0.01 <= measured <= 0.8 + 0.01
    assert measured == pytest.approx(width_m, abs=0.005)
    assert measured < p["door_width_m"]
    centre = np.array([[p["narrow_x_m"], p["narrow_y_m"]]])
    assert world.clearance(centre)[0] > 0.43 / 2  # a Jackal passes


def test_indoor_has_corridor_doors_and_furniture_off_the_doors() -> None:
    world = make_world("indoor", seed=0)
    furniture = [b for b in world.boxes if b.kind == "furniture"]
    assert len(furniture) >= 6
    assert all(0.4 <= b.size_x_m <= 1.2 and 0.4 <= b.size_y_m <= 1.2 for b in furniture)
    xmin, ymin, xmax, _ = world.bounds
    strip = np.column_stack([np.linspace(xmin + 1.0, xmax - 1.0, 200),
                             np.full(200, ymin + 1.0)])
    assert (world.clearance(strip) >= 0.9).all()  # the corridor is a clear 2 m wide strip
    walls = tuple(b for b in world.boxes if b.kind == "wall")
    wall_line = np.column_stack([np.linspace(xmin, xmax, 2000), np.full(2000, ymin + 2.0)])
    door_cells = clearance(wall_line, walls, ()) > 0
    assert (np.diff(door_cells.astype(int)) == 1).sum() == world.params["rooms_x"]


def test_indoor_rejects_bad_params() -> None:
    with pytest.raises(ConfigError, match=r"world\.indoor\.narrow_width_m: 1\.2"):
        make_world("indoor", narrow_width_m=1.2)
    with pytest.raises(ConfigError, match=r"world\.indoor\.size_x_m"):
        make_world("indoor", rooms_x=8)
    with pytest.raises(ConfigError, match=r"world\.seed"):
        make_world("indoor", seed=-1)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_obstacles_keep_the_minimum_gap(seed: int) -> None:
    world = make_world("obstacles", seed=seed, count=25, min_gap_m=0.7)
    field = [s for s in world.boxes + world.cylinders if s.kind != "wall"]
    assert len(field) == 25
    assert {type(s) for s in field} == {Box, Cylinder}
    assert all(0.2 - 1e-9 <= (s.radius_m * 2 if isinstance(s, Cylinder) else s.size_x_m) <= 1.0
               for s in field)
    for shape in field:
        boxes = tuple(b for b in world.boxes if b is not shape)
        cylinders = tuple(c for c in world.cylinders if c is not shape)
        assert clearance(outline(shape), boxes, cylinders).min() >= 0.7 - 1e-6


def test_obstacles_too_many_for_the_arena_is_a_config_error() -> None:
    with pytest.raises(ConfigError, match=r"world\.obstacles\.count: 300"):
        make_world("obstacles", count=300, min_gap_m=1.0)


@pytest.mark.parametrize("seed", [0, 1, 2, 3, 4])
def test_person_walks_clear_of_every_obstacle(seed: int) -> None:
    world = make_world("person", seed=seed, waypoints=5)
    walk = world.person
    assert walk is not None and len(walk.waypoints) == 5 and walk.speed_m_s == 0.6
    need = walk.radius_m + 0.2
    loop = np.array(walk.waypoints + walk.waypoints[:1])
    for a, b in zip(loop[:-1], loop[1:]):
        pts = a + np.linspace(0, 1, int(np.hypot(*(b - a)) / 0.005) + 2)[:, None] * (b - a)
        assert world.clearance(pts).min() >= need
    angles = np.unwrap(np.arctan2(loop[:, 1], loop[:, 0]))  # around the centre: never crosses
    assert (np.diff(angles) > 0).all() and angles[-1] - angles[0] == pytest.approx(2 * math.pi)
    times = np.linspace(0, 60, 500)
    xy = np.array([walk.pose_at(t)[0][:2] for t in times])
    assert world.clearance(xy).min() >= need
    placed = world.params["occluders_placed"]
    assert placed == 2  # every seed here has two corners with room inside
    assert len([s for s in world.boxes + world.cylinders if s.kind != "wall"]) == 6 + placed


def _corner_sight_blocked(world, back_m: float = 2.0, ahead_m: float = 1.0) -> int:
    """Corners where the line from ``back_m`` before the corner (on the incoming leg) to
    ``ahead_m`` after it (on the outgoing leg) crosses an obstacle: a follower there has lost
    the person."""
    loop, blocked = np.array(world.person.waypoints), 0
    for i, corner in enumerate(loop):
        before, after = loop[i - 1], loop[(i + 1) % len(loop)]
        p = corner + (before - corner) / np.hypot(*(before - corner)) * back_m
        q = corner + (after - corner) / np.hypot(*(after - corner)) * ahead_m
        blocked += bool(world.clearance(p + np.linspace(0, 1, 400)[:, None] * (q - p)).min() < 0)
    return blocked


@pytest.mark.parametrize("seed", range(6))
def test_the_person_is_hidden_at_a_corner_only_with_occluders(seed: int) -> None:
    assert _corner_sight_blocked(make_world("person", seed=seed)) >= 1
    assert _corner_sight_blocked(make_world("person", seed=seed, occluders=0)) == 0


def test_person_paths_and_speeds_vary_with_the_seed() -> None:
    walk = {"speed_m_s": 0.8, "speed_spread_fraction": 0.25}
    worlds = [make_world("person", seed=seed, **walk) for seed in range(5)]
    loops = {tuple(np.round(np.ravel(w.person.waypoints), 6)) for w in worlds}
    speeds = {w.person.leg_speeds_m_s for w in worlds}
    assert len(loops) == 5 and len(speeds) == 5
    every = np.concatenate([w.person.leg_speeds_m_s for w in worlds])
    assert every.min() >= 0.8 * 0.75 and every.max() <= 0.8 * 1.25 and every.std() > 0.05
    assert make_world("person", seed=3, **walk) == worlds[3]  # the seed says it all
    assert make_world("person", seed=0, speed_spread_fraction=0.0).person.leg_speeds_m_s == ()


@pytest.mark.parametrize("key, value, match", [
    ("speed_spread_fraction", 0.95, r"world\.person\.speed_spread_fraction: 0\.95"),
    ("occluders", 5, r"world\.person\.occluders: 5 .*\[0, 4\]"),
])
def test_bad_person_walk_parameters_are_config_errors(key, value, match) -> None:
    with pytest.raises(ConfigError, match=match):
        make_world("person", seed=0, **{key: value})


MJCF = """<mujoco>
  <worldbody>
    <geom type="plane" size="20 20 0.1"/>
    <geom type="box" size="0.5 0.25 0.4" pos="2 1 0.4" euler="0 0 30"/>
    <geom type="cylinder" size="0.3 0.6" pos="-1 2 0.6"/>
    <geom type="ellipsoid" size="0.2 0.3 0.3" pos="4 0 0.3"/>
    <body pos="0 -2 0"><geom type="box" size="1 0.2 0.5" pos="0 0 0.5"/></body>
    <body pos="3 3 0"><freejoint/><geom type="box" size="0.2 0.2 0.2"/></body>
  </worldbody>
</mujoco>
"""


def test_world_from_mjcf_reads_static_geoms(tmp_path) -> None:
    path = tmp_path / "warehouse.xml"
    path.write_text(MJCF)
    world = world_from_mjcf(path)
    assert world.name == "warehouse" and world.mjcf_path == path.resolve()
    crate, ellipsoid, shelf = world.boxes  # the free-jointed box moves: not an obstacle
    assert (crate.x, crate.y, crate.size_x_m, crate.size_y_m) == pytest.approx((2, 1, 1.0, 0.5))
    assert (crate.yaw_rad, crate.z_base_m, crate.height_m) == pytest.approx(
        (math.radians(30), 0.0, 0.8))
    (pillar,) = world.cylinders
    assert (pillar.x, pillar.y, pillar.radius_m, pillar.z_base_m, pillar.height_m) == \
        pytest.approx((-1, 2, 0.3, 0.0, 1.2))
    assert (ellipsoid.x, ellipsoid.y, ellipsoid.size_x_m, ellipsoid.size_y_m) == pytest.approx(
        (4, 0, 0.4, 0.6))
    assert (shelf.x, shelf.y, shelf.size_x_m, shelf.height_m) == pytest.approx((0, -2, 2, 1))
    assert world.bounds == pytest.approx((-1.3, -2.2, 4.2, 2.3))
    assert make_world(str(path)) == world


def test_world_from_mjcf_errors_name_the_file(tmp_path) -> None:
    bad = tmp_path / "broken.xml"
    bad.write_text("<mujoco><worldbody><geom type='box'/></worldbod></mujoco>")
    with pytest.raises(WorldError, match="broken.xml"):
        world_from_mjcf(bad)
    with pytest.raises(WorldError, match="missing.xml"):
        world_from_mjcf(tmp_path / "missing.xml")
    empty = tmp_path / "floor.xml"
    empty.write_text("<mujoco><worldbody><geom type='plane' size='5 5 .1'/></worldbody></mujoco>")
    with pytest.raises(WorldError, match="floor.xml.*no static geoms"):
        world_from_mjcf(empty)
    with pytest.raises(ConfigError, match="takes no parameters"):
        make_world(str(empty), size_m=3.0)


def test_make_world_suggests_close_names_and_checks_types() -> None:
    with pytest.raises(ConfigError, match=r"world: unknown key 'indor'; did you mean 'indoor'"):
        make_world("indor")
    with pytest.raises(ConfigError, match=r"world\.indoor: .*did you mean 'door_width_m'"):
        make_world("indoor", door_widht_m=1.0)
    with pytest.raises(ConfigError, match=r"world\.indoor\.rooms_x: 2\.5 .*an integer"):
        make_world("indoor", rooms_x=2.5)
    with pytest.raises(ConfigError, match=r"world\.vineyard\.rows: True"):
        make_world("vineyard", rows=True)
    assert make_world("obstacles", seed=2, size_m=8) == obstacles(2, ObstaclesParams(size_m=8.0))


@pytest.mark.parametrize("kind", KINDS)
def test_generator_params_describe_every_parameter(kind: str) -> None:
    described = specs(WORLD_TABLE[kind].params)
    assert described or kind == "barn"  # BARN's worlds are data: an index, no parameters
    for spec in described:
        assert type(spec.default) in (int, float) and spec.description and spec.bounds
        assert (spec.unit != "") == spec.name.endswith(("_m", "_m_s", "_s"))
        assert spec.check(spec.default) == spec.default
    with pytest.raises(ConfigError, match="did you mean"):
        world_params(kind + "x")


def test_world_params_are_the_only_defaults_and_check_on_construction() -> None:
    assert world_params("obstacles") == ObstaclesParams()
    assert world_params("person").size_m == 8.0 and ObstaclesParams().size_m == 10.0
    with pytest.raises(ConfigError, match=r"^world\.person\.max_size_m: 0\.2 is invalid; "
                       r"expected a value in \[0\.3, 2\.0\]$"):
        world_params("person", {"max_size_m": 0.2})
    with pytest.raises(ConfigError, match=r"^world\.obstacles: unknown key 'sise_m'"):
        world_params("obstacles", {"sise_m": 3.0})
