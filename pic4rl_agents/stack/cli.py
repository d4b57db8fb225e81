"""``pic4rl-run stack``: a ROS 2 stack as the agent, from the command line.

    pic4rl-run stack --command "python examples/ros_gap_follower_node.py" --name gap_node \\
        --params-file config/env_goto_lidar.yaml --pairs pic4rl_agents/data/goals_indoor_test.json

Starts the sim node with the params file's ``sim:`` section and the command in a ROS domain
of their own (``simproc.domain_lease``), drives the episodes (the pairs in order, or the env's
own), records them to ``<bags>/<name>/episode_NNNN/`` and stops both. Prints each outcome.
"""

from __future__ import annotations

import argparse
from collections.abc import Sequence
from pathlib import Path

from .spec import CLOCKS, RESTARTS, stack_spec


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="pic4rl-run stack", description=__doc__.split("\n\n")[0])
    p.add_argument("--command", required=True, help="the stack's command line")
    p.add_argument("--name", default="stack", help="the agent's name in bags and tables")
    p.add_argument("--params-file", required=True, help="env config (sim: and nav_env:)")
    p.add_argument("--pairs", default="", help="start-goal pairs file, walked in order")
    p.add_argument("--episodes", type=int, default=0, help="0: the pairs file's count, else 1")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--bags", default="bags", help="bags go to BAGS/NAME/episode_NNNN/")
    p.add_argument("--clock", choices=CLOCKS, default="lockstep")
    p.add_argument("--real-time-factor", type=float, default=10.0)
    p.add_argument("--restart", choices=RESTARTS, default="episode")
    p.add_argument("--reset-service", default="")
    p.add_argument("--start-timeout-s", type=float, default=30.0)
    p.add_argument("--silence-s", type=float, default=5.0)
    return p


def main(argv: Sequence[str]) -> int:
    """Drive the episodes; 0, or 2 for bad arguments (one line)."""
    import tempfile

    from pic4rl_bridge.episodes import load_goals_and_poses

    from pic4rl_agents.launch.simproc import domain_lease
    from .driver import drive_stack

    args = build_parser().parse_args(list(argv))
    stack = stack_spec({"command": args.command, "name": args.name, "clock": args.clock,
                        "restart": args.restart, "reset_service": args.reset_service,
                        "real_time_factor": args.real_time_factor,
                        "start_timeout_s": args.start_timeout_s,
                        "silence_s": args.silence_s}, "pic4rl-run stack")
    overrides = {"record.enabled": True, "record.bags_dir": args.bags, "record.run": stack.name}
    episodes = args.episodes or 1
    if args.pairs:
        overrides.update({"episodes.file": args.pairs, "episodes.ordered": True})
        episodes = args.episodes or len(load_goals_and_poses(args.pairs).goals)
    with domain_lease() as domain, tempfile.TemporaryDirectory(prefix="pic4rl-stack-") as tmp:
        outcomes = drive_stack(stack, args.params_file, overrides=overrides, episodes=episodes,
                               seed=args.seed, domain=domain, cwd=Path.cwd(),
                               sim_file=Path(tmp) / "sim.yaml")
    for k, outcome in enumerate(outcomes):
        print(f"{stack.name} episode {k}: {outcome}")
    return 0
