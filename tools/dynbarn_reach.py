"""Could any robot have crossed? Each dynamic-BARN episode's scene replayed with foresight.

For every bag of a ``dynbarn`` world, its scene is rebuilt from the bag's facts (the world's
variant and the episode's seed give the same field and the same obstacle motion as the engine:
``engine.crowd.movers``, stepped at the control period) and searched for a way from the start
to within the goal tolerance inside the time budget, by a robot that knows every obstacle's
future: a disc of ``--radius`` (default half the footprint's width) that moves in any direction
at up to ``--speed`` and may wait. The search is the reachable set on a grid of 5 cm (finer
for a slow disc), grown each control period by the cells within one period's travel and cut
by the static field (inflated by the radius) and by where the moving cylinders are at the
period's end (inflated by both radii). It is optimistic: no heading, no acceleration limit, the moving obstacles checked
at the periods' ends only, the footprint's narrow side everywhere. A scene it cannot cross is
one no robot of that width and speed crosses; one it can is not shown to be easy.

    .venv/bin/python tools/dynbarn_reach.py bags/dynbarn --speed 2.0
"""

from __future__ import annotations

import argparse
import math
import sys
from collections import Counter
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from functools import cache
from pathlib import Path
from types import SimpleNamespace

import numpy as np

from pic4rl_metrics.bags.inputs import discover
from pic4rl_metrics.bags.reader import read_episode
from pic4rl_metrics.errors import MetricsError
from pic4rl_sim.engine.crowd.movers import Movers
from pic4rl_sim.engine.paths import clearance_grid
from pic4rl_sim.engine.worlds.generators import make_world
from pic4rl_sim.engine.worlds.spec import WorldSpec

CONTROL_DT_S = 0.1  # the engine's control period in env_barn.yaml: the movers' step here too
CELL_M = 0.05


def disc_offsets(radius_cells: float) -> list[tuple[int, int]]:
    """The grid offsets (row, column) within ``radius_cells`` of the origin."""
    k = math.floor(radius_cells)
    return [(i, j) for i in range(-k, k + 1) for j in range(-k, k + 1)
            if i * i + j * j <= radius_cells * radius_cells + 1e-9]


def dilate(mask: np.ndarray, offsets: Sequence[tuple[int, int]]) -> np.ndarray:
    """``mask`` grown by every offset (cells off the grid are dropped)."""
    out = np.zeros_like(mask)
    ny, nx = mask.shape
    for i, j in offsets:
        out[max(i, 0):ny + min(i, 0), max(j, 0):nx + min(j, 0)] |= \
            mask[max(-i, 0):ny - max(i, 0), max(-j, 0):nx - max(j, 0)]
    return out


def mover_positions(world: WorldSpec, seed: int, dt_s: float = CONTROL_DT_S) -> Iterator[np.ndarray]:
    """The moving obstacles' centres (n x 2, m) at the end of each period of ``dt_s`` of the
    episode with seed ``seed``: the engine's own ``Movers``, placed and stepped as it does."""
    moving = world.moving
    if moving is None:
        while True:
            yield np.zeros((0, 2))
    movers = Movers(moving, tuple(range(len(moving.starts))))
    movers.place(SimpleNamespace(mocap_pos=np.zeros((len(moving.starts), 3))), world.seed, seed)
    while True:
        movers.advance(dt_s)
        yield movers.pos.copy()


def earliest_arrival(world: WorldSpec, seed: int, start: tuple[float, float],
                     goal: tuple[float, float], *, goal_tolerance_m: float, budget_s: float,
                     radius_m: float, speed_mps: float, cell_m: float = CELL_M,
                     dt_s: float = CONTROL_DT_S) -> float | None:
    """The first time (s, a whole number of periods) a disc of ``radius_m`` at up to
    ``speed_mps`` that knows the moving obstacles' future reaches within ``goal_tolerance_m``
    of ``goal`` from ``start`` in ``world`` with the episode seed ``seed``; None when it cannot
    within ``budget_s``. The cell is at most half a period's travel, so that a period's moves
    reach the diagonal neighbours."""
    cell_m = min(cell_m, speed_mps * dt_s / 2)
    xmin, ymin = world.bounds[:2]
    static_free = clearance_grid(world, cell_m) >= radius_m
    ny, nx = static_free.shape
    xs = xmin + (np.arange(nx) + 0.5) * cell_m
    ys = ymin + (np.arange(ny) + 0.5) * cell_m
    near_goal = np.hypot(*np.meshgrid(xs - goal[0], ys - goal[1])) <= goal_tolerance_m
    reach = np.zeros_like(static_free)
    row, col = int((start[1] - ymin) / cell_m), int((start[0] - xmin) / cell_m)
    reach[row, col] = True
    keep_off = radius_m + (world.moving.radius_m if world.moving is not None else 0.0)
    step = disc_offsets(speed_mps * dt_s / cell_m)
    tracks = mover_positions(world, seed, dt_s)
    for k in range(1, round(budget_s / dt_s) + 1):
        free = static_free.copy()
        for x, y in next(tracks):
            c0, c1 = np.searchsorted(xs, [x - keep_off, x + keep_off])
            r0, r1 = np.searchsorted(ys, [y - keep_off, y + keep_off])
            box = np.hypot(*np.meshgrid(xs[c0:c1] - x, ys[r0:r1] - y)) < keep_off
            free[r0:r1, c0:c1] &= ~box
        reach = dilate(reach, step) & free
        if (reach & near_goal).any():
            return k * dt_s
        if not reach.any():
            return None
    return None


@cache
def _world(kind: str, variant: int) -> WorldSpec:
    return make_world(kind, seed=variant)


#: The rows of a suite drive the same scenes (variant, seed): each is searched once.
_arrival = cache(earliest_arrival)


def what_was_hit(world: WorldSpec, seed: int, t_s: float, xy: tuple[float, float],
                 dt_s: float = CONTROL_DT_S) -> str:
    """``moving`` or ``static``: whichever obstacle's surface is nearer the robot's centre at
    ``xy`` at time ``t_s`` of the episode (its last pose, when it ended in a collision)."""
    static = float(world.clearance(np.array([xy]))[0])
    if world.moving is None:
        return "static"
    tracks = mover_positions(world, seed, dt_s)
    for _ in range(max(1, round(t_s / dt_s)) - 1):
        next(tracks)
    moving = float(np.hypot(*(next(tracks) - xy).T).min()) - world.moving.radius_m
    return "moving" if moving < static else "static"


@dataclass(frozen=True)
class Episode:
    bag: str
    agent: str
    world: str
    outcome: str
    arrival_s: float | None  # the foresighted disc's, None: it cannot cross
    hit: str | None  # a collision's obstacle: moving or static


def replay(bag: Path, radius_m: float | None, speed_mps: float) -> Episode:
    """The bag's scene searched as the module says; ``radius_m`` None: half the footprint's
    width. A bag it cannot replay is a ``MetricsError`` (the caller names the bag)."""
    episode = read_episode(bag)
    f = episode.facts
    missing = [k for k in ("world", "seed", "start", "goal", "goal_tolerance_m",
                           "time_budget_s") if getattr(f, k) is None]
    if missing:
        raise MetricsError(f"no {', '.join(missing)} in its facts")
    kind, _, variant = f.world.partition(":")
    if kind != "dynbarn" or not variant.isdigit():
        raise MetricsError(f"world {f.world!r}; expected dynbarn:<variant>")
    if radius_m is None:
        if f.footprint is None or f.footprint.width_m is None:
            raise MetricsError("no rectangular footprint in its facts; give --radius")
        radius_m = f.footprint.width_m / 2
    world = _world(kind, int(variant))
    arrival = _arrival(world, f.seed, tuple(f.start[:2]), (f.goal.x, f.goal.y),
                       goal_tolerance_m=f.goal_tolerance_m, budget_s=f.time_budget_s,
                       radius_m=radius_m, speed_mps=speed_mps)
    outcome = f.outcome.value if f.outcome is not None else "unknown"
    hit = None
    if outcome == "collision" and len(episode.pose.t_ns):
        pose = episode.pose
        # the first pose is the first period's end (the sim's clock starts at the reset)
        t_s = float(pose.t_ns[-1] - pose.t_ns[0]) * 1e-9 + CONTROL_DT_S
        hit = what_was_hit(world, f.seed, t_s, (float(pose.x[-1]), float(pose.y[-1])))
    return Episode(str(bag), f.agent or "?", f.world, outcome, arrival, hit)


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("folders", nargs="+", help="bags or folders of them (the metrics CLI's)")
    parser.add_argument("--speed", type=float, default=2.0,
                        help="the disc's top speed, m/s (default 2.0: the Jackal's in BARN)")
    parser.add_argument("--radius", type=float, default=None,
                        help="the disc's radius, m (default: half the footprint's width)")
    args = parser.parse_args(argv)
    found = discover(args.folders)
    for item, why in found.unmatched:
        print(f"{item}: {why}", file=sys.stderr)
    episodes = []
    for bag in found.bags:
        try:
            ep = replay(bag, args.radius, args.speed)
        except MetricsError as err:  # one bad bag: said, and the batch goes on
            print(f"{bag}: {err}", file=sys.stderr)
            continue
        episodes.append(ep)
        arrival = "cannot cross" if ep.arrival_s is None else f"crosses in {ep.arrival_s:.1f} s"
        hit = f" ({ep.hit} obstacle)" if ep.hit else ""
        print(f"{ep.bag}: {ep.world}, {ep.outcome}{hit}; with foresight {arrival}")
    for agent in sorted({ep.agent for ep in episodes}):
        mine = [ep for ep in episodes if ep.agent == agent]
        crossable = sum(ep.arrival_s is not None for ep in mine)
        print(f"{agent}: {len(mine)} episodes, {crossable} crossable with foresight at "
              f"{args.speed:g} m/s")
        for outcome in sorted({ep.outcome for ep in mine}):
            ended = [ep for ep in mine if ep.outcome == outcome]
            can = sum(ep.arrival_s is not None for ep in ended)
            hits = Counter(ep.hit for ep in ended if ep.hit)
            split = (f" ({hits['moving']} with a moving obstacle, {hits['static']} with the "
                     "static field)") if hits else ""
            print(f"  {outcome}: {len(ended)}{split}; {can} of them crossable")
    return 0 if episodes else 2


if __name__ == "__main__":
    sys.exit(main())
