"""Example episode bags for ``make demo``, before any simulator or agent exists.

Two made-up agents drive a Jackal through a walled room with three cylinders: ``smooth``
drives straight, or in one gentle arc around a cylinder in its way; ``wobbly`` weaves along
the straight line and, on its third episode, drives into a cylinder. The bags follow the bag
contract, so the metrics read them as they would read recorded ones.

    python -m pic4rl_metrics.examples bags/example
"""

from __future__ import annotations

import argparse
import math
import sys
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import yaml

from .facts import Footprint
from .synthetic import DEFAULT_T0_NS, Obstacles, Track, cast_scan, write_episode_bag

FOOTPRINT = {"length_m": 0.508, "width_m": 0.430}  # Clearpath Jackal
COLLISION_TOLERANCE_M = 0.05
ROOM_M = (8.0, 6.0)
ROOM = Obstacles(
    circles=((4.0, 3.0, 0.4), (2.0, 4.3, 0.3), (6.0, 1.9, 0.3)),
    segments=((0, 0, 8, 0), (8, 0, 8, 6), (8, 6, 0, 6), (0, 6, 0, 0)),
)
#: Per episode: start (x, y), goal (x, y), and how far (m) the smooth agent arcs off the
#: straight line to pass the cylinder in its way.
EPISODES = (
    ((1.0, 1.0), (7.0, 1.0), 0.0),
    ((1.0, 5.0), (7.0, 5.0), 0.0),
    ((1.0, 3.0), (7.0, 3.0), 1.0),
)
DT_S = 0.1


@dataclass(frozen=True)
class ExampleRun:
    """What ``write_examples`` did: episode bags written and kept, and the run's config."""

    written: tuple[Path, ...]
    kept: tuple[Path, ...]
    config: Path


def _weave(
    start: Sequence[float],
    goal: Sequence[float],
    speed_mps: float,
    amplitude_m: float,
    half_waves: int,
) -> Track:
    """Along the line start→goal at ``speed_mps``, swinging sideways ``A sin(w t)``; the swing
    ends at zero, so the track ends on the goal. Heading and yaw rate are exact derivatives."""
    p0, p1 = np.asarray(start[:2], float), np.asarray(goal[:2], float)
    length = float(np.hypot(*(p1 - p0)))
    along, side = (p1 - p0) / length, np.array([-(p1 - p0)[1], (p1 - p0)[0]]) / length
    duration = length / speed_mps
    t = np.arange(0.0, duration, DT_S)
    t = np.append(t[t < duration - 1e-6], duration)
    w = half_waves * math.pi / duration
    q = amplitude_m * w * np.cos(w * t) / speed_mps  # side speed over forward speed
    dq = -amplitude_m * w**2 * np.sin(w * t) / speed_mps
    xy = p0 + np.outer(speed_mps * t, along) + np.outer(amplitude_m * np.sin(w * t), side)
    yaw = math.atan2(along[1], along[0]) + np.arctan(q)
    zeros = np.zeros_like(t)
    return Track(t, xy[:, 0], xy[:, 1], yaw, speed_mps * np.hypot(1, q), zeros, dq / (1 + q**2))


def _clearance_m(track: Track, footprint: Footprint) -> np.ndarray:
    """Per pose, the smallest gap (m) between the footprint and the scanned obstacles."""
    angles = np.linspace(-math.pi, math.pi - 2 * math.pi / 360, 360)
    gaps = []
    for x, y, yaw in zip(track.x, track.y, track.yaw):
        ranges = cast_scan(x, y, yaw, ROOM)
        hit = np.isfinite(ranges)
        points = np.column_stack([ranges[hit] * np.cos(angles[hit]), ranges[hit] * np.sin(angles[hit])])
        gaps.append(footprint.signed_distance(points).min() if hit.any() else math.inf)
    return np.array(gaps)


def _episode(agent: str, k: int) -> tuple[Track, str]:
    """The track of ``agent``'s episode ``k`` and its outcome."""
    start, goal, detour_m = EPISODES[k]
    if agent == "smooth":
        return _weave(start, goal, 0.45, detour_m, 1), "goal"
    track = _weave(start, goal, 0.35, 0.2 + 0.05 * k, 2 * k + 3)
    gap = _clearance_m(track, Footprint.parse(FOOTPRINT))
    touching = np.flatnonzero(gap < COLLISION_TOLERANCE_M)
    if len(touching):
        return track.truncated(int(touching[0]) + 1), "collision"
    return track, "goal"


def write_examples(run_dir: Path) -> ExampleRun:
    """Write the example episodes into ``run_dir``; keep any that exist already."""
    run_dir = Path(run_dir)
    run_dir.mkdir(parents=True, exist_ok=True)
    written, kept = [], []
    for a, agent in enumerate(("smooth", "wobbly")):
        for k, (_, goal, _) in enumerate(EPISODES):
            bag = run_dir / f"{agent}_ep{k}"
            if bag.exists():
                kept.append(bag)
                continue
            track, outcome = _episode(agent, k)
            start = [round(float(v[0]), 4) for v in (track.x, track.y, track.yaw)]
            facts = {
                "agent": agent, "task": "goToPose", "world": "example_room", "robot": "jackal",
                "run": run_dir.name, "episode": str(k), "seed": 100 * a + k,
                "footprint": FOOTPRINT, "start": start, "goal": list(goal), "goal_tolerance_m": 0.3,
                "collision_tolerance_m": COLLISION_TOLERANCE_M,
            }  # fmt: skip
            t0_ns = DEFAULT_T0_NS + (3 * a + k) * 60_000_000_000
            written.append(write_episode_bag(
                bag, track, obstacles=ROOM, goal=goal, facts=facts, outcome=outcome, t0_ns=t0_ns,
            ))  # fmt: skip
    config = run_dir / "run.yaml"
    if not config.exists():
        config.write_text(
            yaml.safe_dump(_config(run_dir.name), sort_keys=False, default_flow_style=None)
        )
    return ExampleRun(tuple(written), tuple(kept), config)


def _config(run: str) -> dict[str, object]:
    """The run's config: what generated these episodes."""
    return {
        "run": run,
        "generator": "pic4rl_metrics.examples",
        "task": "goToPose",
        "world": {"name": "example_room", "size_m": list(ROOM_M),
                  "cylinders": [list(c) for c in ROOM.circles]},
        "robot": {"name": "jackal", "footprint": FOOTPRINT},
        "agents": {
            "smooth": "straight, or one arc around a cylinder in the way, at 0.45 m/s forward",
            "wobbly": "weaves along the straight line at 0.35 m/s forward; stops on contact",
        },
        "episodes": [{"start": list(s), "goal": list(g)} for s, g, _ in EPISODES],
        "control_dt_s": DT_S,
        "scan": {"n_beams": 360, "range_min_m": 0.05, "range_max_m": 10.0},
    }  # fmt: skip


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m pic4rl_metrics.examples",
        description="Write the example episode bags of `make demo`.",
    )
    parser.add_argument("run_dir", type=Path, help="run directory, e.g. bags/example")
    args = parser.parse_args(argv)
    try:
        run = write_examples(args.run_dir)
    except OSError as err:
        print(f"error: {args.run_dir}: {err}", file=sys.stderr)
        return 1
    for bag in sorted(run.written + run.kept):
        print(f"wrote {bag}" if bag in run.written else f"kept {bag} (exists already)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
