"""``python -m pic4rl_bridge.demo``: episodes of goToPose driven by the proportional baseline,
recorded to bags, for ``make demo`` until trained agents exist (pic4rl_agents).

    python -m pic4rl_bridge.demo --config config/env_goto_lidar.yaml --episodes 5 \\
        --bags bags --run demo_proportional
    pic4rl-metrics compute bags/demo_proportional

A run directory that exists gets more episodes; nothing in it is overwritten.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence

from tqdm import tqdm

from .baselines import GoToGoalController
from .env import NavEnv
from .errors import BridgeError


#: Open space with a few obstacles: the baseline has no avoidance, so some goals are reached
#: and some are not, and the metrics table shows both.
SPARSE_WORLD = {"world": "obstacles", "world.obstacles.count": 6}


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m pic4rl_bridge.demo",
                                     description=__doc__.split("\n")[0])
    parser.add_argument("--config", default="config/env_goto_lidar.yaml")
    parser.add_argument("--episodes", type=int, default=5)
    parser.add_argument("--bags", default="bags", help="bags directory")
    parser.add_argument("--run", default="demo_proportional", help="run name (a folder)")
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args(argv)
    try:
        env = NavEnv(args.config, task="goToPose", sensor="lidar", sim=SPARSE_WORLD,
                     overrides={"record.enabled": True, "record.bags_dir": args.bags,
                                "record.run": args.run, "agent": "proportional"})
    except BridgeError as err:
        print(f"pic4rl_bridge.demo: {err}", file=sys.stderr)
        return 2
    controller = GoToGoalController(env.scenario.robot)
    try:
        for episode in tqdm(range(args.episodes), desc="episodes", unit="ep"):
            env.reset(seed=args.seed if episode == 0 else None)
            done, info = False, {}
            while not done:
                _, _, terminated, truncated, info = env.step(controller.action(env.frame))
                done = terminated or truncated
            tqdm.write(f"episode {episode}: {info['outcome']} after {info['step']} steps")
    finally:
        env.close()
    print(f"bags: {env.recorder.run_dir}" if env.recorder else "")
    return 0


if __name__ == "__main__":
    sys.exit(main())
