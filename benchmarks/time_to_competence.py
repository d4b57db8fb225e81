"""Time to competence: the wall-clock a training recipe needs, from scratch, until its policy
reaches ``--target`` (90 %) eval success on ``--eval-episodes`` (100) seeded test-kind pairs.

The recipe (``--config``, default ``config/train_goto_lidar_td3.yaml``) trains in this process
exactly as ``pic4rl-train`` trains it (``pic4rl_agents.training.train.Trainer``; imitation of the
privileged planner included, whose labelling counts in the clock), with three changes
that do not touch learning: no checkpoints, no progress bar, and no step limit (the clock
decides: training stops at the first evaluation that reaches the target, or at the first one
past ``--budget-s``). Every ``--eval-every-s`` seconds of training the deterministic policy
drives the same ``--eval-episodes`` episodes: pairs that the simulator samples from the eval
seed with ``episodes.pair_kind: paper`` (4-8 m apart, detour <= 1.3), never training pairs.

The clock is the trainer's ``train_wall_s``: from the start of the training run (building the
envs and the model included) to the start of the evaluation that reached the target, with the
time spent evaluating excluded, so the figure does not depend on how often one evaluates.
``wall_s`` (evaluations included) is printed per evaluation beside it.

    .venv/bin/python benchmarks/time_to_competence.py                  # the shipped LiDAR recipe
    .venv/bin/python benchmarks/time_to_competence.py --config my.yaml --budget-s 1800 \\
        --runs-dir runs/ttc        # keep the run (model, evaluations.csv) for the curves

The last lines are ``RESULT <name> <value>``: ``time_to_<target>pct_s`` (``nan`` when the target
was not reached within the budget), ``steps_to_<target>pct``, ``best_eval_success_rate``,
``evaluations`` and ``train_wall_s_total``.
"""

from __future__ import annotations

import argparse
import math
import shutil
import sys
import tempfile
from pathlib import Path
from typing import Any

from pic4rl_agents.training.callbacks import StopAfterEval
from pic4rl_agents.runs.config import load_run_config
from pic4rl_agents.runs.overrides import parse_overrides
from pic4rl_agents.training.curves import eval_curves
from pic4rl_agents.training.train import Trainer

ROOT = Path(__file__).resolve().parents[1]
CONFIG = ROOT / "config" / "train_goto_lidar_td3.yaml"
NO_STEP_LIMIT = 10**9
#: --smoke: seconds-long, to check the script runs (tiny nets, episodes too short to succeed).
SMOKE_TRAIN = {"policy.net_arch": [16], "policy.critic_arch": [16], "batch_size": 32,
               "learning_starts": 50, "buffer_size": 5000, "tensorboard": False,
               "imitation.bc_steps": 100, "imitation.dagger_steps": 100,
               "imitation.gradient_steps": 10, "imitation.critic_warmup_steps": 10}
SMOKE_ENV = {"episode_max_steps": 40}  # 4 s at 0.5 m/s: 2 m, short of any 4-8 m pair


class Watch(StopAfterEval):
    """Stops as ``StopAfterEval`` does and prints each evaluation as it comes."""

    def _on_step(self) -> bool:
        keep_going = super()._on_step()
        row, parent = self.parent.last_row, self.parent  # type: ignore[union-attr]
        print(f"eval  steps {row['steps']:>8}  train {row['train_wall_s']:8.1f} s  "
              f"wall {row['wall_s']:8.1f} s  success "
              f"{100 * parent.last_success_rate:5.1f} %  "  # type: ignore[union-attr]
              f"reward {parent.last_mean_reward:8.1f}", flush=True)  # type: ignore[union-attr]
        return keep_going


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--config", default=str(CONFIG), help="the recipe's params file")
    parser.add_argument("--target", type=float, default=0.9, help="eval success to reach")
    parser.add_argument("--budget-s", type=float, default=3600.0,
                        help="give up after this many seconds of training")
    parser.add_argument("--eval-every-s", type=float, default=60.0,
                        help="seconds of training between evaluations")
    parser.add_argument("--eval-episodes", type=int, default=100)
    parser.add_argument("--runs-dir", help="keep the run here (default: a temporary folder)")
    parser.add_argument("--hyperparams", nargs="+", default=[], metavar="KEY:VALUE",
                        help="trainer overrides, as pic4rl-train's")
    parser.add_argument("--env-kwargs", nargs="+", default=[], metavar="KEY:VALUE",
                        help="env overrides, as pic4rl-train's")
    parser.add_argument("--smoke", action="store_true",
                        help="seconds-long: tiny nets, 2-episode evaluations every 1 s, "
                             "a 4 s budget (checks the script, measures nothing)")
    return parser


def measure(args: argparse.Namespace, runs_dir: Path) -> dict[str, float]:
    train: dict[str, Any] = {}
    env: dict[str, Any] = {}
    if args.smoke:
        train.update(SMOKE_TRAIN)
        env.update(SMOKE_ENV)
        args.eval_every_s, args.eval_episodes, args.budget_s = 1.0, 2, 4.0
    train.update(parse_overrides(args.hyperparams, flag="--hyperparams"))
    env.update(parse_overrides(args.env_kwargs, flag="--env-kwargs"))
    train.update({"runs_dir": str(runs_dir), "run": "time_to_competence",
                  "max_steps": NO_STEP_LIMIT, "checkpoint.interval_steps": 0,
                  "eval.interval_s": args.eval_every_s, "eval.interval_steps": 0,
                  "eval.episodes": args.eval_episodes, "eval.pair_kind": "paper"})
    run = load_run_config([args.config], train=train, env=env)
    print(f"{args.config}: {run.train.algorithm} {run.env.sensor}, {run.train.n_envs} env(s); "
          f"target {100 * args.target:.0f} % on {args.eval_episodes} pairs (seed "
          f"{run.train.eval.seed}), an evaluation every {args.eval_every_s:g} s of training, "
          f"budget {args.budget_s:g} s", flush=True)
    trainer = Trainer(run, progress=False,
                      after_eval=Watch(success_rate=args.target, budget_s=args.budget_s))
    trainer.run()
    if args.runs_dir is not None:
        print(f"run kept in {trainer.run_dir}", flush=True)
    (evaluations,) = eval_curves(trainer.run_dir).values()
    reached = evaluations[evaluations["success_rate"] >= args.target]
    first = reached.iloc[0] if len(reached) else None
    pct = f"{100 * args.target:.0f}pct"
    return {f"time_to_{pct}_s": float(first["train_wall_s"]) if first is not None else math.nan,
            f"steps_to_{pct}": float(first["steps"]) if first is not None else math.nan,
            "best_eval_success_rate": float(evaluations["success_rate"].max()),
            "evaluations": float(len(evaluations)),
            "train_wall_s_total": float(evaluations["train_wall_s"].iloc[-1])}


def main(argv: list[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    if not 0 <= args.target <= 1:
        print(f"--target {args.target}: expected a success rate in [0, 1]", file=sys.stderr)
        return 2
    keep = args.runs_dir is not None
    runs_dir = Path(args.runs_dir) if keep else Path(tempfile.mkdtemp(prefix="ttc_"))
    try:
        results = measure(args, runs_dir)
    finally:
        if not keep:
            shutil.rmtree(runs_dir, ignore_errors=True)
    for name, value in results.items():
        text = "nan" if math.isnan(value) else (f"{value:.0f}" if name.startswith(("steps",
                                                "evaluations")) else f"{value:.3f}")
        print(f"RESULT {name} {text}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
