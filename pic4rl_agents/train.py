"""``pic4rl-train``: the training node. It owns the env (the paper's training(env(Node))) and
trains an SB3 agent on it, with checkpoints, resume, evaluation, logs and a reward curve.

    pic4rl-train --ros-args --params-file config/train_goto_lidar_td3.yaml
    pic4rl-train --hyperparams learning_rate:0.001 epsilon.initial:0.2 -n 50000 \\
        --env-kwargs transport:ros --ros-args --params-file config/train_goto_lidar_td3.yaml
    pic4rl-train --resume runs/td3_lidar            # the run's latest checkpoint

A run lives in ``<runs_dir>/<run>/``: ``config.yaml`` (all three sections, loads back as a
params file), ``checkpoints/`` (model and replay buffer every ``checkpoint.interval_steps``),
``model.zip`` and ``replay_buffer.pkl`` at the end (or on Ctrl-C), ``monitor/`` (one CSV row
per episode), and per session (0, then one more per resume) ``logs/<session>/`` (SB3's
progress.csv and TensorBoard events), ``eval/<session>/`` and ``best/<session>/`` (the best
evaluated model); ``reward_curve.png`` and ``summary.yaml``. A new run with a taken name gets
``<run>-2``; a resume continues the run's model, replay buffer, curriculum and curve.
"""

from __future__ import annotations

import argparse
import contextlib
import re
import signal
import sys
import time
import warnings
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from pic4rl_bridge.config import EnvConfig, EpisodesConfig
from pic4rl_sim.schema import help_text, param_names, specs, to_params
from pic4rl_bridge.errors import BridgeError, ConfigError, TransportError, unknown_key

from .config import (
    EvalConfig,
    RunConfig,
    TrainConfig,
    load_run_config,
    parse_overrides,
)
from .rosargs import RosArgs, no_sim_hint, split_ros_args
from .runs import free_path, run_config_file

_CHECKPOINT = re.compile(r"^model_(\d+)_steps\.zip$")


@dataclass(frozen=True)
class Resume:
    """A checkpoint to continue from: the model, its replay buffer (if saved), its run dir."""

    model: Path
    replay_buffer: Path | None
    run_dir: Path


def find_resume(path: str | Path) -> Resume:
    """The checkpoint named by ``path``: a model zip, or a run directory (its latest
    checkpoint, or its final ``model.zip`` when that is newer)."""
    path = Path(path)
    if path.is_dir():
        candidates = [(int(m.group(1)), p) for p in (path / "checkpoints").glob("model_*.zip")
                      if (m := _CHECKPOINT.match(p.name))]
        final = path / "model.zip"
        if final.is_file():
            candidates.append((_steps_in(final), final))
        if not candidates:
            raise ConfigError(f"--resume {path}: no checkpoint in it (expected model.zip or "
                              "checkpoints/model_<steps>_steps.zip)")
        path = max(candidates, key=lambda c: (c[0], c[1].stat().st_mtime))[1]
    if not path.is_file() or path.suffix != ".zip":
        raise ConfigError(f"--resume {path}: no such checkpoint (expected a model .zip or a "
                          "run directory)")
    if match := _CHECKPOINT.match(path.name):
        buffer = path.with_name(f"model_replay_buffer_{match.group(1)}_steps.pkl")
        default = path.parent.parent
    else:
        buffer = path.with_name("replay_buffer.pkl")
        default = path.parent
    # The run is the nearest folder with a run config: checkpoints/.., best/<session>/../..
    run_dir = next((d for d in (path.parent, path.parent.parent, path.parent.parent.parent)
                    if run_config_file(d) is not None), default)
    return Resume(path, buffer if buffer.is_file() else None, run_dir)


def _steps_in(model_zip: Path) -> int:
    """The env steps a saved model had trained for (its ``num_timesteps``)."""
    from stable_baselines3.common.save_util import load_from_zip_file

    data, _, _ = load_from_zip_file(model_zip, load_data=True, device="cpu")
    return int((data or {}).get("num_timesteps", 0))


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


@contextlib.contextmanager
def _sigterm_as_interrupt() -> Iterator[None]:
    """SIGTERM (``pic4rl-run`` stopping us, a cluster's scheduler) ends training the way Ctrl-C
    does: the model and replay buffer are saved first."""
    def handler(signum: int, frame: object) -> None:
        raise KeyboardInterrupt

    previous = signal.signal(signal.SIGTERM, handler)
    # A process started in the background by a shell inherits SIGINT ignored; Ctrl-C and
    # pic4rl-run's SIGINT must still reach us.
    previous_int = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, previous)
        signal.signal(signal.SIGINT, previous_int)


def _trainer_node(env: EnvConfig, ros: RosArgs) -> tuple[Any, Any]:
    """The ``trainer`` node, in its own context, for an env that talks ROS 2."""
    import rclpy
    from rclpy.context import Context
    from rclpy.node import Node

    context = Context()
    domain = env.ros.domain_id if env.ros.domain_id >= 0 else None
    rclpy.init(args=["pic4rl-train", "--ros-args", *ros.rest], context=context,
               domain_id=domain)
    node = Node("trainer", namespace=env.ros.namespace or None, context=context)
    return node, context


def eval_env_config(env: EnvConfig, evaluation: EvalConfig) -> EnvConfig:
    """The evaluation env of a run whose env is ``env``: in process, not recording, and every
    ``episodes.*`` key back at its default (no training pairs, no curriculum) but
    ``episodes.pair_kind``, the evaluation's: pairs sampled from the seed, like a test's."""
    defaults = {f"episodes.{k}": v for k, v in to_params(EpisodesConfig()).items()}
    return env.replace(**{**defaults, "episodes.pair_kind": evaluation.pair_kind,
                          "transport": "inprocess", "record.enabled": False})


class Trainer:
    """One training run: envs, model, callbacks; ``run()`` trains and saves, and returns the
    run directory."""

    def __init__(self, run: RunConfig, *, resume: Resume | None = None, progress: bool = True,
                 ros: RosArgs | None = None, after_eval: Any = None) -> None:
        """``after_eval``: an SB3 callback run after each evaluation (its ``parent`` is the
        ``SeededEvalCallback``); returning False ends the training, which is then saved."""
        self.config = run
        self.resume = resume
        self.progress = progress
        self.ros = ros or RosArgs()
        self.after_eval = after_eval
        self.interrupted = False  # Ctrl-C or SIGTERM ended the last run()
        cfg = run.train
        if resume is not None:
            self.run_dir = resume.run_dir
        else:
            self.run_dir = free_path(Path(cfg.runs_dir) / run.name)
        self.run_dir.mkdir(parents=True, exist_ok=True)
        logs = self.run_dir / "logs"
        self.session = len(list(logs.iterdir())) if logs.is_dir() else 0
        self.log_dir = logs / str(self.session)
        self.monitor_dir = self.run_dir / "monitor"

    def _write_config(self) -> Path:
        return self._write_new(self.run_dir / "config.yaml", self.config.to_yaml())

    @staticmethod
    def _write_new(path: Path, text: str) -> Path:
        path = free_path(path, keep_suffix=True)
        path.write_text(text)
        return path

    def run(self) -> Path:
        import torch
        from stable_baselines3.common.callbacks import CheckpointCallback
        from stable_baselines3.common.logger import configure

        from .algorithms import build_model, load_model
        from .callbacks import (
            ProgressCallback,
            RewardCurveCallback,
            SeededEvalCallback,
            WallClockLimit,
        )
        from .curves import episode_table
        from .envs import make_vec_env

        cfg, env_cfg = self.config.train, self.config.env
        seed = cfg.seed
        if self.resume is not None:
            done = _steps_in(self.resume.model)
            if done >= cfg.max_steps:
                print(f"pic4rl-train: {self.resume.model} has trained {done} steps already "
                      f"(max_steps={cfg.max_steps}); nothing to do", file=sys.stderr)
                return self.run_dir
            # Go on where the run was: the curriculum's episodes already driven are not
            # repeated, and the session's seed gives new episodes.
            driven = len(episode_table(self.monitor_dir))
            starting = max(0, env_cfg.episodes.starting_episodes - driven)
            env_cfg = env_cfg.replace(**{"episodes.starting_episodes": starting})
            seed = cfg.seed + self.session
        if cfg.torch_threads > 0:
            torch.set_num_threads(cfg.torch_threads)
        self._write_config()
        node = context = None
        if env_cfg.transport == "ros" and cfg.n_envs == 1:
            node, context = _trainer_node(env_cfg, self.ros)
        env = eval_env = None
        started = time.perf_counter()
        start_steps = 0
        model = None
        try:
            env = make_vec_env(env_cfg, n_envs=cfg.n_envs, seed=seed,
                               reward_scale=cfg.reward_scale, curriculum=cfg.curriculum,
                               vec_env=cfg.vec_env,
                               monitor_dir=self.monitor_dir, node=node,
                               prefix=f"{self.session}_")
            if self.resume is not None:
                model = load_model(self.resume.model, cfg.algorithm, env=env,
                                   device=cfg.device)
                if self.resume.replay_buffer is not None and hasattr(model,
                                                                     "load_replay_buffer"):
                    model.load_replay_buffer(self.resume.replay_buffer)
                if hasattr(model, "set_epsilon"):
                    model.set_epsilon(cfg.epsilon.initial, cfg.epsilon.decay, cfg.epsilon.min)
            else:
                model = build_model(cfg, env)
            start_steps = model.num_timesteps
            formats = ["csv", "log"] + (["tensorboard"] if cfg.tensorboard else [])
            model.set_logger(configure(str(self.log_dir), formats))
            every = max(cfg.checkpoint.interval_steps // cfg.n_envs, 1)
            callbacks: list[Any] = [RewardCurveCallback(
                self.monitor_dir, self.run_dir / "reward_curve.png",
                every=every if cfg.checkpoint.interval_steps else 10_000,
                window=cfg.reward_window, title=f"{self.config.name}: {cfg.algorithm.upper()}"
                f" {env_cfg.sensor}")]
            if cfg.checkpoint.interval_steps:
                callbacks.append(CheckpointCallback(
                    every, str(self.run_dir / "checkpoints"), name_prefix="model",
                    save_replay_buffer=cfg.checkpoint.replay_buffer and cfg.off_policy))
            if cfg.eval.enabled:
                eval_env = make_vec_env(eval_env_config(env_cfg, cfg.eval), seed=cfg.eval.seed)
                # One in-process env evaluates whatever the training envs are (subprocesses).
                warnings.filterwarnings("ignore", "Training and eval env are not of the same")
                callbacks.append(SeededEvalCallback(
                    eval_env, eval_seed=cfg.eval.seed, n_eval_episodes=cfg.eval.episodes,
                    interval_steps=cfg.eval.interval_steps, interval_s=cfg.eval.interval_s,
                    n_envs=cfg.n_envs, clock_start=started,
                    best_model_save_path=str(self.run_dir / "best" / str(self.session)),
                    log_path=str(self.run_dir / "eval" / str(self.session)),
                    callback_after_eval=self.after_eval, deterministic=True, verbose=0))
            if cfg.max_wall_s > 0:
                callbacks.append(WallClockLimit(cfg.max_wall_s, started))
            if self.progress:
                callbacks.append(ProgressCallback(cfg.max_steps, desc=self.config.name))
            remaining = cfg.max_steps - model.num_timesteps
            with _sigterm_as_interrupt():
                try:
                    model.learn(remaining, callback=callbacks,
                                reset_num_timesteps=self.resume is None,
                                log_interval=10 if cfg.off_policy else 1)
                except KeyboardInterrupt:
                    self.interrupted = True
                    print(f"\npic4rl-train: interrupted at {model.num_timesteps} steps; "
                          "saving", file=sys.stderr)
        finally:
            if model is not None and model.num_timesteps > start_steps:
                self._save(model, time.perf_counter() - started, start_steps)
            if env is not None:
                env.close()
            if eval_env is not None:
                eval_env.close()
            if node is not None:
                node.destroy_node()
                context.try_shutdown()
        return self.run_dir

    def _save(self, model: Any, wall_s: float, start_steps: int) -> None:
        """The final (or interrupted) model, its replay buffer, the curve and a summary."""
        from .curves import episode_table, save_reward_curve

        cfg = self.config.train
        model.save(self.run_dir / "model.zip")
        if cfg.off_policy and cfg.checkpoint.replay_buffer:
            model.save_replay_buffer(self.run_dir / "replay_buffer.pkl")
        save_reward_curve(self.monitor_dir, self.run_dir / "reward_curve.png",
                          window=cfg.reward_window,
                          title=f"{self.config.name}: {cfg.algorithm.upper()} "
                          f"{self.config.env.sensor}")
        episodes = episode_table(self.monitor_dir)
        last = episodes.tail(100)
        steps = model.num_timesteps - start_steps
        summary = {"run": self.config.name, "algorithm": cfg.algorithm,
                   "sensor": self.config.env.sensor, "transport": self.config.env.transport,
                   "n_envs": cfg.n_envs, "session": self.session,
                   "total_steps": int(model.num_timesteps), "session_steps": int(steps),
                   "session_wall_s": round(wall_s, 1),
                   "steps_per_s": round(steps / wall_s, 1) if wall_s > 0 else None,
                   "episodes": len(episodes),
                   "last_100_success_rate": (round(float(np.mean(last["is_success"])), 3)
                                             if len(last) else None),
                   "last_100_mean_reward": (round(float(last["r"].mean()), 1)
                                            if len(last) else None)}
        self._write_new(self.run_dir / "summary.yaml", yaml.safe_dump(summary, sort_keys=False))
        print(f"pic4rl-train: {summary['total_steps']} steps, {summary['episodes']} episodes, "
              f"{wall_s / 60:.1f} min ({summary['steps_per_s']} steps/s); saved "
              f"{self.run_dir / 'model.zip'}", file=sys.stderr)


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="pic4rl-train", description=__doc__.split("\n\n")[0],
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
    parser.add_argument("--resume", metavar="PATH",
                        help="a checkpoint .zip or a run directory (its latest checkpoint)")
    parser.add_argument("--no-progress", action="store_true", help="no progress bar")
    return parser


def resolve(args: argparse.Namespace, ros: RosArgs) -> tuple[RunConfig, Resume | None]:
    """The run's config from params files, -p items and the flags (in that order)."""
    resume = find_resume(args.resume) if args.resume else None
    files = list(ros.params_files)
    if not files and resume is not None:
        latest = run_config_file(resume.run_dir)
        if latest is None:
            raise ConfigError(f"--resume {args.resume}: no config.yaml in {resume.run_dir}; "
                              "give the params file with --ros-args --params-file FILE")
        files = [str(latest)]
    if not files:
        raise ConfigError("no --params-file given (e.g. pic4rl-train --ros-args --params-file "
                          "config/train_goto_lidar_td3.yaml)")
    p_train, p_env = route_params(ros.params)
    train = {**p_train, **parse_overrides(args.hyperparams, flag="--hyperparams")}
    for key, value in (("max_steps", args.max_steps), ("seed", args.seed), ("run", args.run),
                       ("n_envs", args.n_envs)):
        if value is not None:
            train[key] = value
    env = {**p_env, **parse_overrides(args.env_kwargs, flag="--env-kwargs")}
    sim = parse_overrides(args.sim_kwargs, flag="--sim-kwargs")
    return load_run_config(files, train=train, env=env, sim=sim), resume


def main(argv: Sequence[str] | None = None) -> int:
    """Train; exit 0 when done (or interrupted and saved), 2 for bad arguments or config."""
    argv = list(sys.argv[1:] if argv is None else argv)
    run: RunConfig | None = None
    try:
        plain, ros = split_ros_args(argv)
        args = build_parser().parse_args(plain)
        run, resume = resolve(args, ros)
        trainer = Trainer(run, resume=resume, progress=not args.no_progress, ros=ros)
        trainer.run()
    except TransportError as err:
        print(f"pic4rl-train: {err}\n{no_sim_hint('train', run.env if run else None)}",
              file=sys.stderr)
        return 2
    except (ConfigError, BridgeError) as err:
        print(f"pic4rl-train: {err}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())
