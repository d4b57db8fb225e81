"""How far the pairs of a goals-and-poses file are from the straight line: the detour of each
pair (shortest collision-free path / straight line) and the fraction above a bound.

    .venv/bin/python tools/pair_detours.py [config/goals_indoor_train.json] [--max-detour 1.3]

The world and robot are the sim's defaults (``SimParams``: indoor, world_variant 0, the
Jackal's circumscribed radius), as for config/goals_indoor_train.json, and the bound the
``paper`` pair kind's; other worlds and robots with the options.
"""

from __future__ import annotations

import argparse
import math
import sys
from collections.abc import Sequence

import numpy as np

from pic4rl_bridge.episodes import load_goals_and_poses
from pic4rl_sim.engine.paths import PathPlanner
from pic4rl_sim.engine.robot_specs import load_robot
from pic4rl_sim.engine.sampling import PAIR_KINDS
from pic4rl_sim.engine.worlds.generators import make_world
from pic4rl_sim.config import SimParams

SIM = SimParams()


def detours(path: str, *, world: str = SIM.world, variant: int = SIM.world_variant,
            robot: str = SIM.robot, resolution_m: float = 0.05) -> np.ndarray:
    """The detour of each pair of the file (``inf`` where there is no path)."""
    pairs = load_goals_and_poses(path)
    planner = PathPlanner(make_world(world, seed=variant),
                          robot_radius_m=load_robot(robot).footprint.bounding_radius_m,
                          resolution_m=resolution_m)
    return np.array([planner.length(p[:2], g) / math.dist(p[:2], g)
                     for p, g in zip(pairs.poses, pairs.goals)])


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("file", nargs="?", default="config/goals_indoor_train.json")
    parser.add_argument("--max-detour", type=float, default=PAIR_KINDS["paper"].max_detour)
    parser.add_argument("--world", default=SIM.world)
    parser.add_argument("--variant", type=int, default=SIM.world_variant)
    parser.add_argument("--robot", default=SIM.robot)
    parser.add_argument("--resolution", type=float, default=0.05, help="grid cell (m)")
    args = parser.parse_args(argv)
    ratio = detours(args.file, world=args.world, variant=args.variant, robot=args.robot,
                    resolution_m=args.resolution)
    over = ratio > args.max_detour
    print(f"{args.file}: {len(ratio)} pairs, detour > {args.max_detour}: {int(over.sum())} "
          f"({over.mean():.1%}); no path: {int(np.isinf(ratio).sum())}; median detour "
          f"{np.median(ratio):.3f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
