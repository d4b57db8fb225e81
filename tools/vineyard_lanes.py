"""Write the test episodes of a vineyard variant: every lane once, start to end, as a
PIC4rl-gym ``goals_and_poses`` JSON that ``pic4rl-test`` walks in order.

    .venv/bin/python tools/vineyard_lanes.py config/train_vineyard_sac.yaml 101 -o lanes.json
    .venv/bin/python tools/vineyard_lanes.py config/train_vineyard_sac.yaml 101 --straight ...
    pic4rl-test --agent checkpoints/vineyard_sac --episodes 7 --sim-kwargs world_variant:101 \
        --env-kwargs episodes.file:lanes.json

The world is the recipe's vineyard with ``world_variant`` set to the variant (and, with
``--straight``, ``bend_m`` 0): the same geometry ``--sim-kwargs`` gives the test's sim. The
file records that world (``vineyard:<variant>``) and the robot's radius, which the env checks.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from pic4rl_agents.runs.config import load_run_config
from pic4rl_bridge.episodes import GoalsAndPoses, save_goals_and_poses
from pic4rl_sim.config import build_world_choice, parameter_table, resolve
from pic4rl_sim.engine.robot_specs import load_robot


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("recipe", type=Path, help="a training recipe with a vineyard sim")
    parser.add_argument("variant", type=int, help="world_variant of the test rows")
    parser.add_argument("--straight", action="store_true", help="bend_m 0: straight rows")
    parser.add_argument("-o", "--out", type=Path, required=True)
    args = parser.parse_args(argv)
    sim = dict(load_run_config([args.recipe]).env.sim_params)
    sim["world_variant"] = args.variant
    if args.straight:
        sim["world.vineyard.bend_m"] = 0.0
    robot = load_robot(sim.get("robot", "jackal"))
    choice = build_world_choice(resolve(parameter_table(robot), sim))
    world = choice.build()
    poses = tuple(world.spawn_poses)
    lanes = GoalsAndPoses(poses[0], tuple(world.goal_points), poses,
                          world=f"{choice.kind}:{choice.variant}",
                          robot_radius_m=robot.footprint.bounding_radius_m)
    save_goals_and_poses(lanes, args.out, overwrite=True, comment=(
        f"every lane of vineyard variant {args.variant} of {args.recipe}"
        f"{' (straight rows)' if args.straight else ''}, start to end"))
    print(f"wrote {len(lanes.goals)} lanes to {args.out}")


if __name__ == "__main__":
    main()
