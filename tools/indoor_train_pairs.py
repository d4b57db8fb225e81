"""Write config/goals_indoor_train.json: the training start–goal pairs of the indoor world.

    .venv/bin/python tools/indoor_train_pairs.py

Pairs come from the simulator's own sampler (world_variant 0, the Jackal's footprint plus the
sim's 0.2 m clearance) and are kept when 1–6 m apart, like the test pairs (4–6 m): long
enough to need avoidance, short enough that goals are reached while exploring. The seed is
fixed, so the file is the same on every machine.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np

from pic4rl_sim.engine.robot_specs import load_robot
from pic4rl_sim.engine.sampling import sample_start_goal
from pic4rl_sim.engine.world_generators import make_world

OUT = Path(__file__).resolve().parents[1] / "config" / "goals_indoor_train.json"
COMMENT = ("Training start-goal pairs of the indoor world (world_variant 0) for the Jackal: "
           "1000 pairs from the simulator's sampler, 1-6 m apart. initial_pose: the starting "
           "episodes' start (the paper's curriculum: random goals around it first). "
           "Regenerate with tools/indoor_train_pairs.py.")


def main(n_pairs: int = 1000, max_distance_m: float = 6.0, seed: int = 2026) -> None:
    world = make_world("indoor", seed=0)
    clearance = load_robot("jackal").footprint.bounding_radius_m + 0.2
    rng = np.random.default_rng(seed)
    poses: list[list[float]] = []
    goals: list[list[float]] = []
    while len(poses) < n_pairs:
        start, goal = sample_start_goal(world, rng, clearance_m=clearance, min_distance_m=1.0)
        if math.dist((start.x, start.y), goal) <= max_distance_m:
            poses.append([round(start.x, 2), round(start.y, 2), round(start.yaw, 3)])
            goals.append([round(goal[0], 2), round(goal[1], 2)])
    doc = {"comment": COMMENT, "initial_pose": [0.0, -0.3, 0.0], "goals": goals,
           "poses": poses}
    OUT.write_text(json.dumps(doc, separators=(",", ":")))
    print(f"wrote {len(goals)} pairs to {OUT}")


if __name__ == "__main__":
    main()
