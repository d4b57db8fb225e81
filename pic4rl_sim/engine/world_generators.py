"""World generators: a seed and a few typed parameters make a ``WorldSpec``.

Generators are pure functions ``name(seed, **params)``, so an evaluation names its worlds by
(kind, seed, params) and gets the same geometry back. ``make_world`` is the one entry point for
configuration (a generator name, or a user's ``.xml`` file); ``generator_params`` and
``PARAM_DOCS`` describe the parameters so that a ROS node can declare one parameter each.
"""

from __future__ import annotations

import inspect
import math
from collections.abc import Callable
from typing import Any

import numpy as np

from ..errors import ConfigError, require, unknown_key
from ..schema import coerce, param_type
from .arena import WALL_HEIGHT_M, WALL_THICKNESS_M, check_count, check_within, rng_for, walls
from .mjcf_world import world_from_mjcf
from .person_walk import corner_occluders, leg_speeds
from .vineyard_world import VINEYARD_PARAM_DOCS, vineyard
from .world_spec import Box, Cylinder, PersonSpec, WorldSpec, clearance

OBSTACLE_HEIGHT_M = 1.0
JUNCTION_MARGIN_M = 0.4  # a door's edge to the nearest crossing wall
FURNITURE_GAP_M = 0.7  # furniture to walls, doors' wall lines and other furniture: a robot fits
PERSON_RADIUS_M = 0.25
PERSON_MARGIN_M = 0.2  # a walking person's clearance from obstacles beyond its radius

PARAM_DOCS: dict[str, str] = {
    "size_x_m": "arena length along x inside the walls (m)",
    "size_y_m": "arena width along y inside the walls (m)",
    "rooms_x": "number of rooms along x",
    "rooms_y": "number of rows of rooms along y, above the corridor",
    "corridor_width_m": "width of the corridor along the south wall (m)",
    "door_width_m": "width of every door opening (m)",
    "narrow_width_m": "width of the one narrow passage, narrower than a door (m)",
    "furniture_per_room": "furniture boxes (0.4-1.2 m sides) tried per room",
    "size_m": "side of the square arena inside the walls (m)",
    "count": "number of static obstacles",
    "min_size_m": "smallest obstacle diameter or box side (m)",
    "max_size_m": "largest obstacle diameter or box side (m)",
    "min_gap_m": "least free gap between two obstacles, and to the walls (m)",
    "cylinder_fraction": "fraction of obstacles that are cylinders, the rest boxes",
    "waypoints": "number of waypoints on the person's closed loop",
    "speed_m_s": "walking speed of the person (m/s)",
    "speed_spread_fraction": "each leg walked at speed_m_s x [1 - f, 1 + f], drawn per leg",
    "occluders": "obstacles inside the loop's corners that hide the person from a follower",
    **VINEYARD_PARAM_DOCS,
}


def _wall_line(fixed: float, lo: float, hi: float, openings: list[tuple[float, float]],
               along_x: bool) -> list[Box]:
    """A straight interior wall from ``lo`` to ``hi`` broken by ``(centre, width)`` openings."""
    edges = [lo]
    for centre, width in sorted(openings):
        edges += [centre - width / 2, centre + width / 2]
    edges.append(hi)
    boxes = []
    for a, b in zip(edges[::2], edges[1::2]):
        if b - a > 1e-6:
            mid, size = 0.5 * (a + b), b - a
            boxes.append(Box(mid, fixed, size, WALL_THICKNESS_M, WALL_HEIGHT_M) if along_x
                         else Box(fixed, mid, WALL_THICKNESS_M, size, WALL_HEIGHT_M))
    return boxes


def indoor(seed: int = 0, *, size_x_m: float = 12.0, size_y_m: float = 10.0, rooms_x: int = 3,
           rooms_y: int = 2, corridor_width_m: float = 2.0, door_width_m: float = 1.0,
           narrow_width_m: float = 0.7, furniture_per_room: int = 2) -> WorldSpec:
    """Rooms in a grid above a corridor along the south wall (the paper's Figure 3).

    Every wall between two neighbouring spaces has one opening at a random place, so every
    room is reachable; one opening, chosen at random, is the narrow passage. Its centre is
    kept in ``params`` (``narrow_x_m``, ``narrow_y_m``, ``narrow_along_x``) for checks.
    """
    params: dict[str, float] = {k: v for k, v in locals().items() if k != "seed"}
    check_count("world.indoor.rooms_x", rooms_x, 1, 10)
    check_count("world.indoor.rooms_y", rooms_y, 1, 10)
    check_count("world.indoor.furniture_per_room", furniture_per_room, 0, 10)
    check_within("world.indoor.door_width_m", door_width_m, 0.6, 3.0)
    require(0.5 <= narrow_width_m < door_width_m, "world.indoor.narrow_width_m", narrow_width_m,
            f"a width in [0.5, door_width_m={door_width_m}) m")
    check_within("world.indoor.corridor_width_m", corridor_width_m, 1.0, 10.0)
    room_min = door_width_m + 2 * JUNCTION_MARGIN_M + 0.2
    require(math.isfinite(size_x_m) and size_x_m / rooms_x >= room_min, "world.indoor.size_x_m",
            size_x_m, f"at least rooms_x * {room_min:.2f} m so that doors fit")
    room_y = (size_y_m - corridor_width_m) / rooms_y
    require(math.isfinite(size_y_m) and room_y >= room_min, "world.indoor.size_y_m", size_y_m,
            f"at least corridor_width_m + rooms_y * {room_min:.2f} m so that doors fit")
    rng = rng_for(seed)
    x0, y0 = -size_x_m / 2, -size_y_m / 2
    room_x, y_rooms = size_x_m / rooms_x, y0 + corridor_width_m
    n_doors = rooms_x * rooms_y + (rooms_x - 1) * rooms_y
    narrow = int(rng.integers(n_doors))

    def opening(lo: float, index: int) -> tuple[float, float]:
        width = narrow_width_m if index == narrow else door_width_m
        span = (room_x if index < rooms_x * rooms_y else room_y) - width - 2 * JUNCTION_MARGIN_M
        return lo + JUNCTION_MARGIN_M + width / 2 + float(rng.uniform(0, span)), width

    boxes = walls((x0, y0, -x0, -y0))
    doors: list[tuple[float, float]] = []
    index = 0
    for j in range(rooms_y):  # the corridor's wall, then the walls between rows of rooms
        y = y_rooms + j * room_y
        line = [opening(x0 + i * room_x, index + i) for i in range(rooms_x)]
        index += rooms_x
        boxes += _wall_line(y, x0, -x0, line, along_x=True)
        doors += [(c, y) for c, _ in line]
    for i in range(1, rooms_x):  # the walls between columns of rooms
        x = x0 + i * room_x
        line = [opening(y_rooms + j * room_y, index + j) for j in range(rooms_y)]
        index += rooms_y
        boxes += _wall_line(x, y_rooms, -y0, line, along_x=False)
        doors += [(x, c) for c, _ in line]
    params.update(narrow_x_m=doors[narrow][0], narrow_y_m=doors[narrow][1],
                  narrow_along_x=float(narrow < rooms_x * rooms_y))
    door_xy = np.array(doors)
    for j in range(rooms_y):
        for i in range(rooms_x):
            room = (x0 + i * room_x, y_rooms + j * room_y, room_x, room_y)
            boxes += _furniture(rng, room, furniture_per_room, door_xy, door_width_m)
    return WorldSpec("indoor", (x0, y0, -x0, -y0), tuple(boxes), seed=seed, params=params)


def _furniture(rng: np.random.Generator, room: tuple[float, float, float, float], count: int,
               door_xy: np.ndarray, door_width_m: float) -> list[Box]:
    """Up to ``count`` tables and shelves in ``room`` (x, y, size x, size y), with a robot's
    width free around each and off the doors."""
    x, y, w, h = room
    margin = WALL_THICKNESS_M / 2 + FURNITURE_GAP_M
    placed: list[Box] = []
    for _ in range(30 * count):
        if len(placed) == count:
            break
        sx, sy = rng.uniform(0.4, 1.2, 2)
        free_x, free_y = w - 2 * margin - sx, h - 2 * margin - sy
        cx = x + margin + sx / 2 + rng.uniform(0, max(free_x, 0.0))
        cy = y + margin + sy / 2 + rng.uniform(0, max(free_y, 0.0))
        box = Box(float(cx), float(cy), float(sx), float(sy), float(rng.uniform(0.5, 1.5)),
                  kind="furniture")
        reach = 0.5 * math.hypot(sx, sy) + FURNITURE_GAP_M
        if (free_x >= 0 and free_y >= 0
                and clearance(np.array([[cx, cy]]), tuple(placed), ()).min() >= reach
                and clearance(door_xy, (box,), ()).min() >= door_width_m):
            placed.append(box)
    return placed


def _field(rng: np.random.Generator, kind: str, size_m: float, count: int, min_size_m: float,
           max_size_m: float, min_gap_m: float, cylinder_fraction: float,
           keep_off_xy: np.ndarray | None = None, keep_off_m: float = 0.0,
           ) -> tuple[list[Box], list[Cylinder]]:
    """``count`` cylinders and boxes in a square of side ``size_m`` around the origin, every
    one at least ``min_gap_m`` from the others and from the walls, and ``keep_off_m`` from
    the points ``keep_off_xy``."""
    key = f"world.{kind}"
    check_within(f"{key}.size_m", size_m, 2.0, 100.0)
    check_count(f"{key}.count", count, 0, 300)
    check_within(f"{key}.min_size_m", min_size_m, 0.05, size_m / 4)
    check_within(f"{key}.max_size_m", max_size_m, min_size_m, size_m / 4)
    check_within(f"{key}.min_gap_m", min_gap_m, 0.0, size_m / 2)
    check_within(f"{key}.cylinder_fraction", cylinder_fraction, 0.0, 1.0)
    boxes: list[Box] = []
    cylinders: list[Cylinder] = []
    misses = 0  # draws rejected since the last obstacle placed: many mean the arena is full
    while len(boxes) + len(cylinders) < count and misses < 2000:
        size = float(rng.uniform(min_size_m, max_size_m))
        is_cylinder = rng.random() < cylinder_fraction
        size_y = size if is_cylinder else float(rng.uniform(min_size_m, max_size_m))
        reach = 0.5 * math.hypot(size, size_y) if not is_cylinder else 0.5 * size
        limit = size_m / 2 - reach - min_gap_m
        x, y = (float(v) for v in rng.uniform(-1, 1, 2) * max(limit, 0.0))
        yaw = float(rng.uniform(-math.pi, math.pi))
        if (limit < 0
                or clearance(np.array([[x, y]]), tuple(boxes), tuple(cylinders))[0]
                < reach + min_gap_m
                or (keep_off_xy is not None
                    and np.hypot(*(keep_off_xy - [x, y]).T).min() < reach + keep_off_m)):
            misses += 1
            continue
        misses = 0
        if is_cylinder:
            cylinders.append(Cylinder(x, y, size / 2, OBSTACLE_HEIGHT_M))
        else:
            boxes.append(Box(x, y, size, size_y, OBSTACLE_HEIGHT_M, yaw, kind="obstacle"))
    placed = len(boxes) + len(cylinders)
    require(placed == count, f"{key}.count", count,
            f"a count that fits the arena with min_gap_m={min_gap_m} (placed {placed})")
    return boxes, cylinders


def obstacles(seed: int = 0, *, size_m: float = 10.0, count: int = 20, min_size_m: float = 0.2,
              max_size_m: float = 1.0, min_gap_m: float = 0.6,
              cylinder_fraction: float = 0.5) -> WorldSpec:
    """A walled square arena with a random field of cylinders and boxes, ``min_gap_m`` apart."""
    params: dict[str, float] = {k: v for k, v in locals().items() if k != "seed"}
    rng = rng_for(seed)
    boxes, cylinders = _field(rng, "obstacles", size_m, count, min_size_m, max_size_m,
                              min_gap_m, cylinder_fraction)
    bounds = (-size_m / 2, -size_m / 2, size_m / 2, size_m / 2)
    return WorldSpec("obstacles", bounds, tuple(walls(bounds) + boxes), tuple(cylinders),
                     seed=seed, params=params)


def person(seed: int = 0, *, size_m: float = 8.0, count: int = 6, min_size_m: float = 0.3,
           max_size_m: float = 1.0, min_gap_m: float = 0.8, cylinder_fraction: float = 0.5,
           waypoints: int = 4, speed_m_s: float = 0.6, speed_spread_fraction: float = 0.3,
           occluders: int = 2) -> WorldSpec:
    """A person walking a closed loop around the arena's centre, among a few obstacles.

    The loop is drawn first and the obstacles kept off it, so it never needs repair: waypoint
    i lies in the direction of angle 2 pi i / n (the loop never crosses itself) at a random
    distance from the centre. Then each leg gets its speed and up to ``occluders`` corners a
    cylinder on their inside (``person_walk``; how many stand is ``occluders_placed`` in
    ``params``)."""
    params: dict[str, float] = {k: v for k, v in locals().items() if k != "seed"}
    check_count("world.person.waypoints", waypoints, 2, 20)
    check_within("world.person.speed_m_s", speed_m_s, 0.0, 3.0)
    check_within("world.person.size_m", size_m, 2.0, 100.0)
    check_within("world.person.speed_spread_fraction", speed_spread_fraction, 0.0, 0.9)
    check_count("world.person.occluders", occluders, 0, waypoints)
    rng = rng_for(seed)
    need = PERSON_RADIUS_M + PERSON_MARGIN_M
    angles = rng.uniform(0, 2 * math.pi) + 2 * math.pi * np.arange(waypoints) / waypoints
    reach = rng.uniform(0.4, 1.0, waypoints) * (size_m / 2 - need)
    loop = np.column_stack([reach * np.cos(angles), reach * np.sin(angles)])
    path = np.concatenate([a + np.linspace(0, 1, int(np.hypot(*(b - a)) / 0.05) + 2)[:, None]
                           * (b - a) for a, b in zip(loop, np.roll(loop, -1, axis=0))])
    boxes, cylinders = _field(rng, "person", size_m, count, min_size_m, max_size_m, min_gap_m,
                              cylinder_fraction, path, need + 0.025)  # path: 5 cm samples
    hiding = corner_occluders(rng, loop, path, occluders, keep_off_m=need + 0.025,
                              sizes_m=(min_size_m, max_size_m),
                              half_size_m=size_m / 2, obstacles=(tuple(boxes), tuple(cylinders)))
    params["occluders_placed"] = len(hiding)
    walk = PersonSpec(tuple((float(x), float(y)) for x, y in loop), speed_m_s, PERSON_RADIUS_M,
                      leg_speeds_m_s=leg_speeds(rng, waypoints, speed_m_s, speed_spread_fraction))
    bounds = (-size_m / 2, -size_m / 2, size_m / 2, size_m / 2)
    return WorldSpec("person", bounds, tuple(walls(bounds) + boxes), (*cylinders, *hiding),
                     person=walk, seed=seed, params=params)


GENERATORS: dict[str, Callable[..., WorldSpec]] = {
    "indoor": indoor, "obstacles": obstacles, "vineyard": vineyard, "person": person,
}


def generator_params(kind: str) -> dict[str, tuple[type, Any, str]]:
    """Each keyword parameter of generator ``kind``: (type, default, description)."""
    if kind not in GENERATORS:
        raise unknown_key(kind, GENERATORS, where="world")
    signature = inspect.signature(GENERATORS[kind])
    return {p.name: (type(p.default), p.default, PARAM_DOCS[p.name])
            for p in signature.parameters.values() if p.kind is p.KEYWORD_ONLY}


def make_world(kind: str, *, seed: int = 0, **params: Any) -> WorldSpec:
    """The world named ``kind`` (a generator, or a path ending in ``.xml``) for ``seed``."""
    if kind.endswith(".xml"):
        if params:
            raise ConfigError(f"world: {kind!r} is an MJCF file and takes no parameters; "
                              f"got {sorted(params)}")
        return world_from_mjcf(kind)
    known = generator_params(kind)
    typed: dict[str, Any] = {}
    for name, value in params.items():
        if name not in known:
            raise unknown_key(name, known, where=f"world.{kind}")
        value = coerce(f"world.{kind}.{name}", param_type(known[name][0])[0], value)
        typed[name] = value
    return GENERATORS[kind](seed, **typed)
