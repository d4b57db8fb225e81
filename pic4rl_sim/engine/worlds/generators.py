"""World generators: a seed and a few typed parameters make a ``WorldSpec``.

Generators are pure functions ``build(seed, params)``, so an evaluation names its worlds by
(kind, seed, params) and gets the same geometry back. Each generator's parameters are a frozen
dataclass of ``param(...)`` fields (``pic4rl_base.schema``): the only place of their defaults,
units, ranges and descriptions, which the sim node declares as ``world.<kind>.<name>`` and the
docs list; a value out of range is a ``ConfigError`` naming that key. ``make_world`` is the one
entry point for configuration (a generator name, or a user's ``.xml`` file, read with MuJoCo
only then, so that reading parameters needs no MuJoCo).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any, ClassVar, NamedTuple

import numpy as np

from pic4rl_base.errors import ConfigError, require, unknown_key
from pic4rl_base.schema import (POSITIVE, PROBABILITY, Range, check, param, param_names, redefault,
                                to_params)

from ..person_walk import corner_occluders, leg_speeds
from .arena import rng_for, walls
from .barn import BarnParams, barn
from .barn_like import BarnLikeParams, barn_like
from .clutter3d import Clutter3dParams, clutter3d
from .dynbarn import DynBarnParams, dynbarn
from .rooms import RoomsParams, door_centre, furniture, least_room_m, rooms, wall_line
from .spec import Box, Cylinder, PersonSpec, WorldSpec, clearance
from .vineyard import VineyardParams, vineyard

OBSTACLE_HEIGHT_M = 1.0
PERSON_RADIUS_M = 0.25
PERSON_MARGIN_M = 0.2  # a walking person's clearance from obstacles beyond its radius
_COUNT = Range(0, 10)


@dataclass(frozen=True)
class IndoorParams:
    """The ``indoor`` world: rooms in a grid above a corridor."""

    KIND: ClassVar[str] = "indoor"
    size_x_m: float = param(12.0, doc="arena length along x inside the walls", unit="m",
                            range=POSITIVE)
    size_y_m: float = param(10.0, doc="arena width along y inside the walls", unit="m",
                            range=POSITIVE)
    rooms_x: int = param(3, doc="number of rooms along x", range=Range(1, 10))
    rooms_y: int = param(2, doc="number of rows of rooms along y, above the corridor",
                         range=Range(1, 10))
    corridor_width_m: float = param(2.0, doc="width of the corridor along the south wall",
                                    unit="m", range=Range(1.0, 10.0))
    door_width_m: float = param(1.0, doc="width of every door opening", unit="m",
                                range=Range(0.6, 3.0))
    narrow_width_m: float = param(0.7, doc="width of the one narrow passage, narrower than a "
                                  "door", unit="m", range=Range(0.5, 3.0, hi_open=True))
    furniture_per_room: int = param(2, doc="furniture boxes (0.4-1.2 m sides) tried per room",
                                    range=_COUNT)

    def __post_init__(self) -> None:
        check(self, "world.indoor.")
        require(self.narrow_width_m < self.door_width_m, "world.indoor.narrow_width_m",
                self.narrow_width_m, f"a width in [0.5, door_width_m={self.door_width_m}) m")
        room_min = least_room_m(self.door_width_m)
        require(self.size_x_m / self.rooms_x >= room_min, "world.indoor.size_x_m",
                self.size_x_m, f"at least rooms_x * {room_min:.2f} m so that doors fit")
        require((self.size_y_m - self.corridor_width_m) / self.rooms_y >= room_min,
                "world.indoor.size_y_m", self.size_y_m,
                f"at least corridor_width_m + rooms_y * {room_min:.2f} m so that doors fit")


@dataclass(frozen=True)
class ObstaclesParams:
    """The ``obstacles`` world: a walled square with a random field of cylinders and boxes."""

    KIND: ClassVar[str] = "obstacles"
    size_m: float = param(10.0, doc="side of the square arena inside the walls", unit="m",
                          range=Range(2.0, 100.0))
    count: int = param(20, doc="number of static obstacles", range=Range(0, 300))
    min_size_m: float = param(0.2, doc="smallest obstacle diameter or box side", unit="m",
                              range=Range(0.05, 25.0))
    max_size_m: float = param(1.0, doc="largest obstacle diameter or box side", unit="m",
                              range=Range(0.05, 25.0))
    min_gap_m: float = param(0.6, doc="least free gap between two obstacles, and to the walls",
                             unit="m", range=Range(0.0, 50.0))
    cylinder_fraction: float = param(0.5, doc="fraction of obstacles that are cylinders, the "
                                     "rest boxes", range=PROBABILITY)

    def __post_init__(self) -> None:
        key, quarter = f"world.{self.KIND}", self.size_m / 4
        check(self, f"{key}.")
        require(self.min_size_m <= quarter, f"{key}.min_size_m", self.min_size_m,
                f"a value in [0.05, {quarter}]")
        require(self.min_size_m <= self.max_size_m <= quarter, f"{key}.max_size_m",
                self.max_size_m, f"a value in [{self.min_size_m}, {quarter}]")
        require(self.min_gap_m <= self.size_m / 2, f"{key}.min_gap_m", self.min_gap_m,
                f"a value in [0.0, {self.size_m / 2}]")


@dataclass(frozen=True)
class PersonParams(ObstaclesParams):
    """The ``person`` world: a person walking a loop in a smaller ``obstacles`` arena."""

    KIND: ClassVar[str] = "person"
    size_m: float = redefault(ObstaclesParams, "size_m", 8.0)
    count: int = redefault(ObstaclesParams, "count", 6)
    min_size_m: float = redefault(ObstaclesParams, "min_size_m", 0.3)
    min_gap_m: float = redefault(ObstaclesParams, "min_gap_m", 0.8)
    waypoints: int = param(4, doc="number of waypoints on the person's closed loop",
                           range=Range(2, 20))
    speed_m_s: float = param(0.6, doc="walking speed of the person", unit="m/s",
                             range=Range(0.0, 3.0))
    speed_spread_fraction: float = param(0.3, doc="each leg walked at speed_m_s x [1 - f, "
                                         "1 + f], drawn per leg", range=Range(0.0, 0.9))
    occluders: int = param(2, doc="obstacles inside the loop's corners that hide the person "
                           "from a follower", range=Range(0, 20))

    def __post_init__(self) -> None:
        super().__post_init__()
        require(self.occluders <= self.waypoints, "world.person.occluders", self.occluders,
                f"an integer in [0, {self.waypoints}] (a corner of the loop each)")


def indoor(seed: int, p: IndoorParams) -> WorldSpec:
    """Rooms in a grid above a corridor along the south wall (the paper's Figure 3).

    Every wall between two neighbouring spaces has one opening at a random place, so every
    room is reachable; one opening, chosen at random, is the narrow passage. Its centre is
    kept in ``params`` (``narrow_x_m``, ``narrow_y_m``, ``narrow_along_x``) for checks.
    """
    params: dict[str, float] = _plain(p)
    size_x_m, size_y_m, rooms_x, rooms_y = p.size_x_m, p.size_y_m, p.rooms_x, p.rooms_y
    corridor_width_m, door_width_m, narrow_width_m = (p.corridor_width_m, p.door_width_m,
                                                      p.narrow_width_m)
    room_y = (size_y_m - corridor_width_m) / rooms_y
    rng = rng_for(seed)
    x0, y0 = -size_x_m / 2, -size_y_m / 2
    room_x, y_rooms = size_x_m / rooms_x, y0 + corridor_width_m
    n_doors = rooms_x * rooms_y + (rooms_x - 1) * rooms_y
    narrow = int(rng.integers(n_doors))

    def opening(lo: float, index: int) -> tuple[float, float]:
        width = narrow_width_m if index == narrow else door_width_m
        length = room_x if index < rooms_x * rooms_y else room_y
        return door_centre(rng, lo, length, width), width

    boxes = walls((x0, y0, -x0, -y0))
    doors: list[tuple[float, float]] = []
    index = 0
    for j in range(rooms_y):  # the corridor's wall, then the walls between rows of rooms
        y = y_rooms + j * room_y
        line = [opening(x0 + i * room_x, index + i) for i in range(rooms_x)]
        index += rooms_x
        boxes += wall_line(y, x0, -x0, line, along_x=True)
        doors += [(c, y) for c, _ in line]
    for i in range(1, rooms_x):  # the walls between columns of rooms
        x = x0 + i * room_x
        line = [opening(y_rooms + j * room_y, index + j) for j in range(rooms_y)]
        index += rooms_y
        boxes += wall_line(x, y_rooms, -y0, line, along_x=False)
        doors += [(x, c) for c, _ in line]
    params.update(narrow_x_m=doors[narrow][0], narrow_y_m=doors[narrow][1],
                  narrow_along_x=float(narrow < rooms_x * rooms_y))
    door_xy = np.array(doors)
    for j in range(rooms_y):
        for i in range(rooms_x):
            room = (x0 + i * room_x, y_rooms + j * room_y, room_x, room_y)
            boxes += furniture(rng, room, p.furniture_per_room, door_xy, door_width_m)
    return WorldSpec("indoor", (x0, y0, -x0, -y0), tuple(boxes), seed=seed, params=params)


def _field(rng: np.random.Generator, p: ObstaclesParams, keep_off_xy: np.ndarray | None = None,
           keep_off_m: float = 0.0) -> tuple[list[Box], list[Cylinder]]:
    """``p.count`` cylinders and boxes in a square of side ``p.size_m`` around the origin, every
    one at least ``p.min_gap_m`` from the others and from the walls, and ``keep_off_m`` from
    the points ``keep_off_xy``."""
    size_m, count, min_gap_m = p.size_m, p.count, p.min_gap_m
    min_size_m, max_size_m, cylinder_fraction = p.min_size_m, p.max_size_m, p.cylinder_fraction
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
    require(placed == count, f"world.{p.KIND}.count", count,
            f"a count that fits the arena with min_gap_m={min_gap_m} (placed {placed})")
    return boxes, cylinders


def obstacles(seed: int, p: ObstaclesParams) -> WorldSpec:
    """A walled square arena with a random field of cylinders and boxes, ``min_gap_m`` apart."""
    boxes, cylinders = _field(rng_for(seed), p)
    bounds = (-p.size_m / 2, -p.size_m / 2, p.size_m / 2, p.size_m / 2)
    return WorldSpec("obstacles", bounds, tuple(walls(bounds) + boxes), tuple(cylinders),
                     seed=seed, params=_plain(p))


def person(seed: int, p: PersonParams) -> WorldSpec:
    """A person walking a closed loop around the arena's centre, among a few obstacles.

    The loop is drawn first and the obstacles kept off it, so it never needs repair: waypoint
    i lies in the direction of angle 2 pi i / n (the loop never crosses itself) at a random
    distance from the centre. Then each leg gets its speed and up to ``occluders`` corners a
    cylinder on their inside (``person_walk``; how many stand is ``occluders_placed`` in
    ``params``)."""
    rng, size_m, waypoints = rng_for(seed), p.size_m, p.waypoints
    need = PERSON_RADIUS_M + PERSON_MARGIN_M
    angles = rng.uniform(0, 2 * math.pi) + 2 * math.pi * np.arange(waypoints) / waypoints
    reach = rng.uniform(0.4, 1.0, waypoints) * (size_m / 2 - need)
    loop = np.column_stack([reach * np.cos(angles), reach * np.sin(angles)])
    path = np.concatenate([a + np.linspace(0, 1, int(np.hypot(*(b - a)) / 0.05) + 2)[:, None]
                           * (b - a) for a, b in zip(loop, np.roll(loop, -1, axis=0))])
    boxes, cylinders = _field(rng, p, path, need + 0.025)  # path: 5 cm samples
    hiding = corner_occluders(rng, loop, path, p.occluders, keep_off_m=need + 0.025,
                              sizes_m=(p.min_size_m, p.max_size_m),
                              half_size_m=size_m / 2, obstacles=(tuple(boxes), tuple(cylinders)))
    walk = PersonSpec(tuple((float(x), float(y)) for x, y in loop), p.speed_m_s, PERSON_RADIUS_M,
                      leg_speeds_m_s=leg_speeds(rng, waypoints, p.speed_m_s,
                                                p.speed_spread_fraction))
    bounds = (-size_m / 2, -size_m / 2, size_m / 2, size_m / 2)
    return WorldSpec("person", bounds, tuple(walls(bounds) + boxes), (*cylinders, *hiding),
                     person=walk, seed=seed, params=_plain(p, occluders_placed=len(hiding)))


def _plain(p: Any, **drawn: float) -> dict[str, float]:
    """A world's ``params``: its generator's parameters, then what it drew."""
    return {**to_params(p), **drawn}


class Generator(NamedTuple):
    """A world generator: its parameters (a schema dataclass with a ``KIND``) and the pure
    function that builds its world from a seed and them."""

    params: type[Any]
    build: Callable[[int, Any], WorldSpec]


#: Every generator, by the ``KIND`` of its parameters.
WORLD_TABLE: dict[str, Generator] = {g.params.KIND: g for g in (
    Generator(IndoorParams, indoor), Generator(ObstaclesParams, obstacles),
    Generator(VineyardParams, vineyard), Generator(PersonParams, person),
    Generator(BarnParams, barn), Generator(BarnLikeParams, barn_like),
    Generator(Clutter3dParams, clutter3d), Generator(DynBarnParams, dynbarn),
    Generator(RoomsParams, rooms))}


def world_params(kind: str, params: Mapping[str, Any] | None = None) -> Any:
    """Generator ``kind``'s parameters: ``params`` over the defaults, typed and checked; an
    unknown kind or name is a ``ConfigError`` with a "did you mean"."""
    if kind not in WORLD_TABLE:
        raise unknown_key(kind, WORLD_TABLE, where="world")
    cls = WORLD_TABLE[kind].params
    names = param_names(cls)
    for name in params or {}:
        if name not in names:
            raise unknown_key(name, names, where=f"world.{kind}")
    return cls(**(params or {}))


def make_world(kind: str, *, seed: int = 0, **params: Any) -> WorldSpec:
    """The world named ``kind`` (a generator, or a path ending in ``.xml``) for ``seed``."""
    if kind.endswith(".xml"):
        if params:
            raise ConfigError(f"world: {kind!r} is an MJCF file and takes no parameters; "
                              f"got {sorted(params)}")
        from .mjcf import world_from_mjcf  # MuJoCo, loaded only for a user's file

        return world_from_mjcf(kind)
    typed = world_params(kind, params)
    return WORLD_TABLE[kind].build(seed, typed)
