"""A synthetic benchmark's bags: agents × start–goal pairs × runs in one walled arena, each
agent succeeding at a chosen rate, for the report's tests and its benchmark script.

Every agent drives every pair once per run, from the pair's start to its goal by a detour of
its own (so the maps tell the agents apart); a success reaches the goal, a failure stops part
way with a recorded ``collision`` or ``timeout``. The bags are real rosbag2 bags written by
``synthetic.write_episode_bag``, under ``<root>/<run>/<agent>/episode_NNNN``, as
``pic4rl-test`` lays them out.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from pathlib import Path

import numpy as np

from .synthetic import Obstacles, from_waypoints, write_episode_bag

#: A 12 m × 12 m walled arena with four cylinders.
ARENA = Obstacles(
    circles=((6.0, 6.0, 0.5), (3.0, 9.0, 0.3), (9.0, 3.0, 0.3), (9.0, 9.0, 0.3)),
    segments=((0, 0, 12, 0), (12, 0, 12, 12), (12, 12, 0, 12), (0, 12, 0, 0)),
)
FOOTPRINT = {"radius_m": 0.2}


def pairs_in_arena(n: int, seed: int = 0) -> list[tuple[tuple[float, float], tuple[float, float]]]:
    """``n`` start–goal pairs inside the arena, at least 4 m apart, drawn from ``seed``."""
    rng = np.random.default_rng(seed)
    out: list[tuple[tuple[float, float], tuple[float, float]]] = []
    while len(out) < n:
        start, goal = rng.uniform(1.0, 11.0, 2).round(2), rng.uniform(1.0, 11.0, 2).round(2)
        if math.dist(start, goal) >= 4.0:
            out.append(((float(start[0]), float(start[1])), (float(goal[0]), float(goal[1]))))
    return out


def write_benchmark(root: Path, rates: Mapping[str, float], *, pairs: int = 4, runs: int = 1,
                    seed: int = 0, n_beams: int = 90, speed_mps: float = 0.8,
                    dt_s: float = 0.1, scan_every: int = 1) -> list[Path]:
    """Write the bags of ``rates`` (agent: success probability) on ``pairs`` pairs, ``runs``
    times each, under ``root``; the bag directories. Poses every ``dt_s``, a scan of
    ``n_beams`` every ``scan_every``-th pose; outcomes drawn from ``seed``."""
    rng = np.random.default_rng(seed + 1)
    chosen = pairs_in_arena(pairs, seed)
    bags: list[Path] = []
    for run in range(runs):
        for a, (agent, rate) in enumerate(rates.items()):
            for k, (start, goal) in enumerate(chosen):
                heading = math.atan2(goal[1] - start[1], goal[0] - start[0])
                side = 0.6 * (a - (len(rates) - 1) / 2)
                mid = ((start[0] + goal[0]) / 2 - side * math.sin(heading),
                       (start[1] + goal[1]) / 2 + side * math.cos(heading))
                track = from_waypoints([start, mid, goal], speed_mps, dt_s)
                outcome = "goal"
                if rng.random() >= rate:
                    outcome = "collision" if rng.random() < 0.5 else "timeout"
                    track = track.truncated(max(3, int(len(track) * rng.uniform(0.3, 0.8))))
                facts = {"agent": agent, "task": "goto", "world": "arena", "run": f"run{run}",
                         "episode": f"episode_{k:04d}", "seed": run * 1000 + k,
                         "footprint": FOOTPRINT, "start": [*start, heading], "goal": list(goal),
                         "time_budget_s": float(track.t_s[-1])}
                path = root / f"run{run}" / agent / f"episode_{k:04d}"
                bags.append(write_episode_bag(path, track, obstacles=ARENA, n_beams=n_beams,
                                              scan_every=scan_every, facts=facts,
                                              outcome=outcome))
    return bags
