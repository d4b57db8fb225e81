"""The ``pic4rl-train`` command line: its parser, its overrides (each checked and blamed on
the flag that gave it), and the run's config and checkpoint they resolve to."""

from __future__ import annotations

import argparse
import dataclasses
from typing import Any

from pic4rl_agents.runs import rundir
from pic4rl_agents.runs.config import (ENV_NODE, NODES, SIM_NODE, TRAINER_NODE, RunConfig, TrainConfig,
                                  run_config)
from pic4rl_agents.runs.overrides import check_overrides, parse_overrides
from pic4rl_agents.launch.rosargs import RosArgs
from pic4rl_base import params_file
from pic4rl_base.schema import help_text, param_names, specs
from pic4rl_bridge.config import EnvConfig
from pic4rl_bridge.errors import ConfigError, unknown_key

DESCRIPTION = ("pic4rl-train: the training node. It owns the env (the paper's "
               "training(env(Node))) and trains an SB3 agent on it, with checkpoints, resume, "
               "evaluation, logs and a reward curve.")


def route_params(params: dict[str, Any]) -> tuple[dict[str, Any], dict[str, Any]]:
    """``-p key:=value`` items split between the trainer (its keys) and the env (its keys);
    a key neither knows is an error with a "did you mean"."""
    train_keys, env_keys = param_names(TrainConfig), param_names(EnvConfig)
    train, env = {}, {}
    for key, value in params.items():
        if key in train_keys:
            train[key] = value
        elif key in env_keys:
            env[key] = value
        else:
            raise unknown_key(key, (*train_keys, *env_keys), where="-p parameters")
    return train, env


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="pic4rl-train", description=DESCRIPTION,
        formatter_class=argparse.RawDescriptionHelpFormatter,
        epilog="ROS arguments after --ros-args: --params-file FILE (sim:, nav_env:, trainer: "
               "sections), -p key:=value (a trainer or env key).\n\ntrainer parameters:\n"
               f"{help_text(specs(TrainConfig))}\n\nenv (nav_env) parameters:\n"
               f"{help_text(specs(EnvConfig))}")
    parser.add_argument("--hyperparams", nargs="+", default=[], metavar="KEY:VALUE",
                        help="trainer overrides, RL-Zoo style: learning_rate:0.001 "
                             "policy.net_arch:[64,64]")
    parser.add_argument("--env-kwargs", nargs="+", default=[], metavar="KEY:VALUE",
                        help="env (nav_env) overrides: episode_max_steps:300 transport:ros")
    parser.add_argument("--sim-kwargs", nargs="+", default=[], metavar="KEY:VALUE",
                        help="sim overrides: world_variant:1")
    parser.add_argument("-n", "--max-steps", type=int, help="trainer max_steps")
    parser.add_argument("--seed", type=int, help="trainer seed")
    parser.add_argument("--run", help="run name (a folder under runs_dir)")
    parser.add_argument("--n-envs", type=int, help="trainer n_envs")
    parser.add_argument("-i", "--trained-agent", metavar="PATH",
                        help="trainer trained_agent: start from this model's networks")
    parser.add_argument("--resume", metavar="PATH",
                        help="a checkpoint .zip or a run directory (its latest checkpoint)")
    parser.add_argument("--no-progress", action="store_true", help="no progress bar")
    return parser


def _overrides(args: argparse.Namespace, ros: RosArgs) -> dict[str, dict[str, Any]]:
    """The command line's overrides by section, each checked and blamed on its flag."""
    p_train, p_env = route_params(ros.params)
    train = {**check_overrides(TRAINER_NODE, p_train, where="-p parameters"),
             **check_overrides(TRAINER_NODE, parse_overrides(args.hyperparams,
                                                             flag="--hyperparams"),
                               where="--hyperparams")}
    for flag, key in (("-n/--max-steps", "max_steps"), ("--seed", "seed"), ("--run", "run"),
                      ("--n-envs", "n_envs"), ("-i/--trained-agent", "trained_agent")):
        value = getattr(args, key)
        if value is not None:
            train.update(check_overrides(TRAINER_NODE, {key: value}, where=flag))
    env = {**check_overrides(ENV_NODE, p_env, where="-p parameters"),
           **check_overrides(ENV_NODE, parse_overrides(args.env_kwargs, flag="--env-kwargs"),
                             where="--env-kwargs")}
    sim = check_overrides(SIM_NODE, parse_overrides(args.sim_kwargs, flag="--sim-kwargs"),
                          where="--sim-kwargs")
    return {TRAINER_NODE: train, ENV_NODE: env, SIM_NODE: sim}


def resolve(args: argparse.Namespace, ros: RosArgs) -> tuple[RunConfig, rundir.Resume | None]:
    """The run's config from params files, -p items and the flags (in that order), and the
    checkpoint to resume from; each file is read once."""
    overrides = _overrides(args, ros)
    resume = rundir.find_resume(args.resume) if args.resume else None
    latest = rundir.run_config_file(resume.run_dir) if resume is not None else None
    files = list(ros.params_files)
    if not files and resume is not None:
        if latest is None:
            raise ConfigError(f"--resume {args.resume}: no {rundir.CONFIG} in {resume.run_dir}; "
                              "give the params file with --ros-args --params-file FILE")
        files = [str(latest)]
    if not files:
        raise ConfigError("no --params-file given (e.g. pic4rl-train --ros-args --params-file "
                          "config/train_goto_lidar_td3.yaml)")
    read = {f: params_file.load([f], NODES)
            for f in dict.fromkeys([*files, *([str(latest)] if latest else [])])}
    run = run_config(params_file.merge(*(read[f] for f in files)), files,
                     train=overrides[TRAINER_NODE], env=overrides[ENV_NODE],
                     sim=overrides[SIM_NODE])
    if resume is None and run.train.trained_agent:
        rundir.trained_model(run.train.trained_agent, where=(
            "-i/--trained-agent" if args.trained_agent else "trainer.trained_agent"))
    if resume is not None and latest is not None:
        trained = run_config(read[str(latest)], [str(latest)]).origin
        resume = dataclasses.replace(resume, trained=f"trained with {trained}")
    return run, resume
