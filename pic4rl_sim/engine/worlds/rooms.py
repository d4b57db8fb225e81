"""The ``rooms`` world: a larger house of rooms joined by doors, for exploration, and the walls
with doors and the furniture that it and ``indoor`` share.

Exploration wants layouts it has never seen, each needing many rooms visited: ``indoor``'s six
rooms on one corridor are seen in a minute. Here a grid of ``rooms_x`` x ``rooms_y`` rooms
(20 x 15 m by default, 2.5 times ``indoor``'s floor) has its inner wall lines shifted by up to
``wall_jitter_m`` each, so rooms differ in size, and its doors drawn from the seed: a random
spanning tree of the rooms' grid (every room reachable, by one way in a tree) and, on each
other wall between neighbours, a door with chance ``extra_door_fraction`` (loops). Each door
opening lies at a random place along its wall, and furniture keeps a robot's width from walls,
doors and other furniture, so every free region is reachable. The doors kept are in
``params`` (``doors``: how many).

Layouts are ``world_variant``s (seeds): 1000-1019 are the held-out test layouts
(``TEST_LAYOUTS``, in ``held_out.HELD_OUT``: no training or evaluation env may draw them),
0-999 are for training.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from pic4rl_base.errors import require
from pic4rl_base.schema import POSITIVE, PROBABILITY, Range, check, param, to_params

from .arena import WALL_HEIGHT_M, WALL_THICKNESS_M, rng_for, walls
from .spec import Box, WorldSpec, clearance

JUNCTION_MARGIN_M = 0.4  # a door's edge to the nearest crossing wall
FURNITURE_GAP_M = 0.7  # furniture to walls, doors' wall lines and other furniture: a robot fits
#: The held-out test layouts (``world_variant``s); train on 0-999.
TEST_LAYOUTS = tuple(range(1000, 1020))


@dataclass(frozen=True)
class RoomsParams:
    """The ``rooms`` world: a grid of rooms of jittered sizes joined by seeded doors."""

    KIND: ClassVar[str] = "rooms"
    size_x_m: float = param(20.0, doc="house length along x inside the walls", unit="m",
                            range=POSITIVE)
    size_y_m: float = param(15.0, doc="house width along y inside the walls", unit="m",
                            range=POSITIVE)
    rooms_x: int = param(4, doc="number of rooms along x", range=Range(1, 10))
    rooms_y: int = param(3, doc="number of rooms along y", range=Range(1, 10))
    wall_jitter_m: float = param(1.0, doc="each inner wall line is shifted by up to this from "
                                 "its even place", unit="m", range=Range(0.0, 5.0))
    door_width_m: float = param(1.0, doc="width of every door opening", unit="m",
                                range=Range(0.6, 3.0))
    extra_door_fraction: float = param(0.3, doc="chance of a door in a wall between neighbours "
                                       "beyond the spanning tree's (loops)", range=PROBABILITY)
    furniture_per_room: int = param(2, doc="furniture boxes (0.4-1.2 m sides) tried per room",
                                    range=Range(0, 10))

    def __post_init__(self) -> None:
        check(self, "world.rooms.")
        room_min = least_room_m(self.door_width_m)
        for key, size, count in (("size_x_m", self.size_x_m, self.rooms_x),
                                 ("size_y_m", self.size_y_m, self.rooms_y)):
            least = count * (room_min + 2 * self.wall_jitter_m)
            require(size >= least, f"world.rooms.{key}", size,
                    f"at least {least:.2f} m: rooms of {room_min:.2f} m (door_width_m and "
                    "margins) plus twice wall_jitter_m each")


def least_room_m(door_width_m: float) -> float:
    """The shortest wall a door of ``door_width_m`` fits in, margins to crossing walls kept."""
    return door_width_m + 2 * JUNCTION_MARGIN_M + 0.2


def door_centre(rng: np.random.Generator, lo: float, length: float, width: float) -> float:
    """A door's centre drawn on the wall of ``length`` from ``lo``, off its crossing walls."""
    return lo + JUNCTION_MARGIN_M + width / 2 + float(
        rng.uniform(0, length - width - 2 * JUNCTION_MARGIN_M))


def wall_line(fixed: float, lo: float, hi: float, openings: list[tuple[float, float]],
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


def furniture(rng: np.random.Generator, room: tuple[float, float, float, float], count: int,
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
                and (not len(door_xy) or clearance(door_xy, (box,), ()).min() >= door_width_m)):
            placed.append(box)
    return placed


def _lines(rng: np.random.Generator, lo: float, size: float, count: int,
           jitter: float) -> np.ndarray:
    """The ``count`` + 1 wall lines (outer ones included) of rooms along one axis: evenly
    spaced, each inner one shifted by up to ``jitter``."""
    lines = lo + size * np.arange(count + 1) / count
    lines[1:-1] += rng.uniform(-jitter, jitter, count - 1)
    return lines


def _tree(rng: np.random.Generator, nx: int, ny: int) -> set[tuple[int, int, int, int]]:
    """A random spanning tree of the ``nx`` x ``ny`` rooms' grid (a random walk that backs up
    when stuck: every room joined, one way between any two): its edges ``(i, j, i2, j2)``,
    the lower room first."""
    start = (int(rng.integers(nx)), int(rng.integers(ny)))
    seen, stack, edges = {start}, [start], set()
    while stack:
        i, j = stack[-1]
        near = [(i + di, j + dj) for di, dj in ((1, 0), (-1, 0), (0, 1), (0, -1))
                if 0 <= i + di < nx and 0 <= j + dj < ny and (i + di, j + dj) not in seen]
        if not near:
            stack.pop()
            continue
        nxt = near[int(rng.integers(len(near)))]
        seen.add(nxt)
        stack.append(nxt)
        a, b = sorted(((i, j), nxt))
        edges.add((*a, *b))
    return edges


def rooms(seed: int, p: RoomsParams) -> WorldSpec:
    """The house (see the module's docstring)."""
    rng = rng_for(seed)
    x0, y0 = -p.size_x_m / 2, -p.size_y_m / 2
    xs = _lines(rng, x0, p.size_x_m, p.rooms_x, p.wall_jitter_m)
    ys = _lines(rng, y0, p.size_y_m, p.rooms_y, p.wall_jitter_m)
    tree = _tree(rng, p.rooms_x, p.rooms_y)
    width = p.door_width_m

    def door(lo: float, hi: float) -> float:
        """A door's centre on the wall between ``lo`` and ``hi``."""
        return door_centre(rng, lo, hi - lo, width)

    boxes = walls((x0, y0, -x0, -y0))
    doors: list[tuple[float, float]] = []
    for i in range(1, p.rooms_x):  # the walls between columns of rooms
        line = [door(ys[j], ys[j + 1]) for j in range(p.rooms_y)
                if (i - 1, j, i, j) in tree or rng.random() < p.extra_door_fraction]
        boxes += wall_line(xs[i], y0, -y0, [(c, width) for c in line], along_x=False)
        doors += [(float(xs[i]), c) for c in line]
    for j in range(1, p.rooms_y):  # the walls between rows of rooms
        line = [door(xs[i], xs[i + 1]) for i in range(p.rooms_x)
                if (i, j - 1, i, j) in tree or rng.random() < p.extra_door_fraction]
        boxes += wall_line(ys[j], x0, -x0, [(c, width) for c in line], along_x=True)
        doors += [(c, float(ys[j])) for c in line]
    door_xy = np.array(doors, dtype=float).reshape(-1, 2)
    for j in range(p.rooms_y):
        for i in range(p.rooms_x):
            room = (float(xs[i]), float(ys[j]), float(xs[i + 1] - xs[i]),
                    float(ys[j + 1] - ys[j]))
            boxes += furniture(rng, room, p.furniture_per_room, door_xy, width)
    return WorldSpec("rooms", (x0, y0, -x0, -y0), tuple(boxes), seed=seed,
                     params={**to_params(p), "doors": float(len(doors))})
