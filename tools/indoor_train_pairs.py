"""Write config/goals_indoor_train.json: the training start–goal pairs of the indoor world.

    .venv/bin/python tools/indoor_train_pairs.py

Pairs come from the env's own pair sampler (``pic4rl_bridge.episodes.PairSampler``) in the sim's
default world and robot (``SimParams``: indoor, world_variant 0, the Jackal's footprint plus the
sim's clearance), each with a collision-free path and 1–6 m apart (the sim's least distance;
the test pairs are 4–6 m): long enough to need avoidance, short enough that goals are reached
while exploring. The seed is fixed, so the file is the same on every machine. The file records
its world (``indoor:0``) and the robot's radius, which the env checks before using it. The shipped file
was drawn before the path check (the sim's own sampler, kept at 1–6 m, cm precision); it stays
as the checkpoints were trained on it.
"""

from __future__ import annotations

from pathlib import Path

from pic4rl_bridge.episodes import PairSampler, save_goals_and_poses
from pic4rl_base.geometry import Pose2D
from pic4rl_sim.engine.robot_specs import load_robot
from pic4rl_sim.engine.sampling import PairKind
from pic4rl_sim.engine.worlds.generators import make_world
from pic4rl_sim.config import SimParams

OUT = Path(__file__).resolve().parents[1] / "config" / "goals_indoor_train.json"
COMMENT = ("Training start-goal pairs of the indoor world (world_variant 0) for the Jackal: "
           "{n} pairs from the env's pair sampler, 1-{max:g} m apart, each with a path. "
           "initial_pose: the starting episodes' start (the paper's curriculum: random goals "
           "around it first). Regenerate with tools/indoor_train_pairs.py.")


def main(n_pairs: int = 1000, max_distance_m: float = 6.0, seed: int = 2026) -> None:
    sim = SimParams()
    radius = load_robot(sim.robot).footprint.bounding_radius_m
    sampler = PairSampler(make_world(sim.world, seed=sim.world_variant), robot_radius_m=radius,
                          clearance_m=radius + sim.clearance_m,
                          min_goal_distance_m=sim.min_goal_distance_m,
                          world_name=f"{sim.world}:{sim.world_variant}")
    pairs = sampler.goals_and_poses(n_pairs, seed=seed,
                                    kind=PairKind(max_distance_m=max_distance_m),
                                    initial_pose=Pose2D(0.0, -0.3, 0.0))
    save_goals_and_poses(pairs, OUT, overwrite=True,
                         comment=COMMENT.format(n=n_pairs, max=max_distance_m))
    print(f"wrote {len(pairs.goals)} pairs to {OUT}")


if __name__ == "__main__":
    main()
