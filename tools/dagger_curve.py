"""Imitation alone, round by round: behaviour cloning then DAgger rounds of a training recipe
(its ``trainer.imitation`` settings), with the student evaluated after each round on the eval
pairs (``eval.seed``, 50 test-kind pairs), never training or test pairs. No RL follows.

    .venv/bin/python tools/dagger_curve.py config/train_goto_lidar_td3.yaml
    .venv/bin/python tools/dagger_curve.py config/train_goto_plan_td3.yaml --rounds 8

Prints one line per round: seconds since the start (evaluations included), labelled states,
the regression loss, and the outcomes of the evaluation.
"""

from __future__ import annotations

import argparse
import sys
import time
from collections.abc import Sequence

import torch
from stable_baselines3.common.callbacks import CallbackList
from stable_baselines3.common.evaluation import evaluate_policy
from stable_baselines3.common.logger import configure

from pic4rl_agents.models.algorithms import new_model
from pic4rl_agents.runs.config import load_run_config
from pic4rl_agents.training.envs import eval_env_config, make_vec_env
from pic4rl_agents.training.imitation import EXPERT, STUDENT, Imitation


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("config", help="a training recipe (params file)")
    parser.add_argument("--rounds", type=int, help="DAgger rounds (default: the recipe's)")
    parser.add_argument("--episodes", type=int, default=50, help="evaluation episodes")
    args = parser.parse_args(argv)
    run = load_run_config([args.config])
    cfg, imitation = run.train, run.train.imitation
    torch.set_num_threads(max(cfg.torch_threads, 1))
    env = make_vec_env(run.env, n_envs=cfg.n_envs, seed=cfg.seed, vec_env="dummy",
                       reward_scale=cfg.reward_scale)
    evaluation = make_vec_env(eval_env_config(run.env, cfg.eval), seed=cfg.eval.seed)
    model = new_model(cfg, env)
    model.set_logger(configure(None, []))
    callback = CallbackList([])
    callback.init_callback(model)
    learner = Imitation(imitation, env, run.env, model, callback, batch_size=cfg.batch_size,
                        seed=cfg.seed)
    rounds = [(EXPERT, imitation.bc_steps)] + [(STUDENT, imitation.dagger_steps)] * (
        imitation.dagger_rounds if args.rounds is None else args.rounds)
    started = time.perf_counter()
    try:
        for number, (driver, steps) in enumerate(rounds):
            learner.collect(steps, driver)
            learner.fit(imitation.gradient_steps)
            outcomes: list[str] = []

            def count(local: dict, _: dict) -> None:
                if local["done"]:
                    outcomes.append(str(local["info"].get("outcome")))

            evaluation.seed(cfg.eval.seed)
            evaluate_policy(model, evaluation, n_eval_episodes=args.episodes,
                            deterministic=True, callback=count)
            print(f"round {number} ({'expert' if driver == EXPERT else 'student'}): "
                  f"{time.perf_counter() - started:6.0f} s, {len(learner.data)} labels, loss "
                  f"{learner.losses[-1]:.4f}, goal {outcomes.count('goal')}/{len(outcomes)}, "
                  f"collision {outcomes.count('collision')}, timeout {outcomes.count('timeout')}",
                  flush=True)
    finally:
        env.close()
        evaluation.close()
    return 0


if __name__ == "__main__":
    sys.exit(main())
