"""A classical baseline's settings tried on BARN's training worlds, never on its 50 test worlds:
how fast against how wide (docs/results.md, "BARN"). In process, no bags (the score is the
metric's formula on the env's own poses), one episode per world and setting.

    .venv/bin/python tools/barn_tune.py planner planner.max_linear_m_s=1.5,2.0 \
        planner.plan_margin_m=0,0.1
    .venv/bin/python tools/barn_tune.py dwa dwa.horizon_s=1.5,2.5 --worlds 3:300:6
    .venv/bin/python tools/barn_tune.py explorer explorer.squeeze_radius_m=0.27,0.3 \
        explorer.max_linear_m_s=1.0,1.5,2.0

Each ``KEY=V1,V2`` is one axis of the grid (a ``baselines.*`` key without its prefix); every
combination runs on ``--worlds`` (a Python range START:STOP:STEP; default every world whose
index is 3 mod 6, 50 of the 250 training worlds). A test world in the range is refused. One
line per combination: success, collision and timeout counts, mean BARN time of the successes
and mean BARN score.
"""

from __future__ import annotations

import argparse
import itertools
import math
import sys
from collections.abc import Sequence

import numpy as np

from pic4rl_bridge.settings.baselines import baselines_config_from_params
from pic4rl_bridge.baselines.registry import make_baseline
from pic4rl_bridge.env import NavEnv
from pic4rl_metrics.core.metrics import BARN_CLIP, BARN_MOVED_M, BARN_SPEED_MPS
from pic4rl_sim.engine.worlds.barn import challenge_test_worlds

ENV = "config/env_barn.yaml"


def episode(env: NavEnv, baseline: str, settings: object, seed: int) -> tuple[str, float, float]:
    """(outcome, BARN time s, BARN score) of one episode of ``baseline`` in ``env``'s world."""
    controller = make_baseline(baseline, env.config, env.scenario.robot, env.scenario.world,
                               settings)  # type: ignore[arg-type]
    env.reset(seed=seed)
    controller.reset()
    frame = env.frame
    start, t0, outcome, steps = (frame.pose.x, frame.pose.y), None, "timeout", 0
    while True:
        _, _, terminated, truncated, info = env.step(controller.action(env.frame))
        steps += 1
        pose = env.frame.pose
        if t0 is None and math.dist(start, (pose.x, pose.y)) >= BARN_MOVED_M:
            t0 = steps - 1
        if terminated or truncated:
            outcome = str(info.get("outcome", "timeout"))
            break
    dt = env.scenario.robot.control_dt_s
    at = (steps - (t0 or 0)) * dt
    reference = env.scenario.world.params["reference_path_length_m"]
    ot = reference / BARN_SPEED_MPS
    score = ot / float(np.clip(at, BARN_CLIP[0] * ot, BARN_CLIP[1] * ot)) if outcome == "goal" else 0.0
    return outcome, at, score


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("baseline", choices=("dwa", "planner", "explorer"))
    parser.add_argument("axes", nargs="*", metavar="KEY=V1,V2")
    parser.add_argument("--worlds", default="3:300:6", help="START:STOP:STEP (a range)")
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args(argv)
    worlds = range(*(int(v) for v in args.worlds.split(":")))
    banned = sorted(set(worlds) & set(challenge_test_worlds()))
    if banned:
        print(f"barn_tune: --worlds {args.worlds} holds test worlds {banned[:5]}...; tune on "
              "training worlds only", file=sys.stderr)
        return 2
    keys = [a.split("=")[0] for a in args.axes]
    grids = [[float(v) for v in a.split("=")[1].split(",")] for a in args.axes]
    envs = [NavEnv(ENV, sim={"world_variant": w}) for w in worlds]
    try:
        for combo in itertools.product(*grids):
            settings = baselines_config_from_params(dict(zip(keys, combo)))
            runs = [episode(env, args.baseline, settings, args.seed + i)
                    for i, env in enumerate(envs)]
            outcomes = [r[0] for r in runs]
            times = [r[1] for r in runs if r[0] == "goal"]
            label = " ".join(f"{k}={v:g}" for k, v in zip(keys, combo)) or "defaults"
            print(f"{label}: goal {outcomes.count('goal')}/{len(runs)} collision "
                  f"{outcomes.count('collision')} timeout {outcomes.count('timeout')} "
                  f"time {np.mean(times) if times else math.nan:.2f} s score "
                  f"{np.mean([r[2] for r in runs]):.4f}", flush=True)
    finally:
        for env in envs:
            env.close()
    return 0


if __name__ == "__main__":
    sys.exit(main())
