"""``pic4rl-train``: the training node. It owns the env (the paper's training(env(Node))) and
trains an SB3 agent on it, with checkpoints, resume, evaluation, logs and a reward curve.

    pic4rl-train --ros-args --params-file config/train_goto_lidar_td3.yaml
    pic4rl-train --hyperparams learning_rate:0.001 epsilon.initial:0.2 -n 50000 \\
        --env-kwargs transport:ros --ros-args --params-file config/train_goto_lidar_td3.yaml
    pic4rl-train --resume runs/td3_lidar            # the run's newest checkpoint that loads

A run lives in ``<runs_dir>/<run>/`` (``pic4rl_agents.runs.rundir`` has its layout). A new run with a
taken name gets ``<run>-2``; a resume continues the run's model, replay buffer, curriculum and
curve, as a new session. The command line is read by ``pic4rl_agents.training.args``.
"""

from __future__ import annotations

import contextlib
import logging
import sys
import threading
import time
import warnings
from collections.abc import Iterator, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

import yaml

from pic4rl_agents.runs import rundir
from pic4rl_agents.runs.config import RunConfig
from pic4rl_agents.runs.console import console_logging
from pic4rl_agents.launch.rosargs import RosArgs, no_sim_hint, split_ros_args
from pic4rl_base import atomic
from pic4rl_base.entry import entry_point
from pic4rl_bridge.config import EnvConfig
from pic4rl_bridge.errors import BridgeError, TransportError

from .args import build_parser, resolve

if TYPE_CHECKING:
    from pic4rl_bridge.scenario import Scenario

log = logging.getLogger(__name__)


@contextlib.contextmanager
def _trainer_node(env: EnvConfig, ros: RosArgs) -> Iterator[Any]:
    """The ``trainer`` node, in its own context, for an env that talks ROS 2."""
    import rclpy
    from rclpy.context import Context
    from rclpy.node import Node

    context = Context()
    domain = env.ros.domain_id if env.ros.domain_id >= 0 else None
    rclpy.init(args=["pic4rl-train", "--ros-args", *ros.rest], context=context,
               domain_id=domain)
    try:
        node = Node("trainer", namespace=env.ros.namespace or None, context=context)
        try:
            yield node
        finally:
            node.destroy_node()
    finally:
        context.try_shutdown()


class Trainer:
    """One training run: envs, model, callbacks; ``run()`` trains and saves, and returns the
    run directory."""

    def __init__(self, run: RunConfig, *, resume: rundir.Resume | None = None,
                 progress: bool = True, ros: RosArgs | None = None, after_eval: Any = None) -> None:
        """``after_eval``: an SB3 callback run after each evaluation (its ``parent`` is the
        ``SeededEvalCallback``); returning False ends the training, which is then saved."""
        self.config = run
        self.resume = resume
        self.progress = progress
        self.ros = ros or RosArgs()
        self.after_eval = after_eval
        self.interrupted = False  # Ctrl-C or SIGTERM ended the last run()
        self._refitted = False  # a budget cut imitation short; the actor was fitted after it
        self._stop = threading.Event()  # set by that signal (``stop_on_signal``)
        self.layout = (rundir.RunDir.resume(resume.run_dir) if resume is not None
                       else rundir.RunDir.new(Path(run.train.runs_dir), run.name))

    @property
    def run_dir(self) -> Path:
        return self.layout.path

    def run(self) -> Path:
        """Train this session (resumed where the run was), save, and close what it opened."""
        import torch

        from pic4rl_bridge.scenario import Scenario

        from .callbacks import StopWhenSet, evaluate_saved

        cfg = self.config.train
        session = self._session_env()
        if session is None:
            return self.run_dir
        env_cfg, seed = session
        scenario = Scenario(env_cfg)  # resolved once: the training envs' and the experts'
        if cfg.torch_threads > 0:
            torch.set_num_threads(cfg.torch_threads)
        with contextlib.ExitStack() as stack:
            node = None
            if env_cfg.transport == "ros" and cfg.n_envs == 1:
                node = stack.enter_context(_trainer_node(env_cfg, self.ros))
            started = time.perf_counter()
            env = self._training_env(stack, scenario, seed, node)
            model = self._model(env)
            self._stop.clear()
            callbacks = [StopWhenSet(self._stop), *self._callbacks(stack, env_cfg, started)]
            # Only now: a session that fails to start (a checkpoint that does not fit the
            # env, no sim) leaves no config behind.
            self.layout.write_config(self.config.to_yaml())
            steps = model.num_timesteps
            stack.callback(self._save_if_trained, model, started, steps)
            if self._imitate(model, env, scenario, callbacks):
                self._learn(model, callbacks)
            if not self.interrupted and model.num_timesteps > steps:  # judge the saved model
                self.interrupted = not evaluate_saved(callbacks, self._stop, self._refitted)
        return self.run_dir

    def _imitate(self, model: Any, env: Any, scenario: Scenario, callbacks: list[Any]) -> bool:
        """Imitation before RL when ``imitation.enabled`` (not on a resume: the resumed model
        has imitated already); False when a callback (the clock) ended training during it."""
        from stable_baselines3.common.callbacks import CallbackList

        from .callbacks import stop_on_signal, stopped_by_signal
        from .imitation import DecayingCloning, Imitation

        cfg = self.config.train
        if not cfg.imitation.enabled or self.resume is not None:
            return True
        callback = CallbackList(callbacks)
        callback.init_callback(model)
        with stop_on_signal(self._stop):
            try:
                imitation = Imitation(cfg.imitation, env, scenario, model, callback,
                                      batch_size=cfg.batch_size, seed=cfg.seed,
                                      max_steps=cfg.max_steps, sources=self.config.sources)
                done = imitation.run()
                self._refitted = imitation.refitted
                if cfg.imitation.rl_gradient_steps > 0:
                    callbacks.insert(0, DecayingCloning(imitation))
            except BaseException as err:
                if not stopped_by_signal(err, self._stop):
                    raise
                done = False
        if self._stop.is_set():
            self.interrupted = True
            log.warning("interrupted during imitation at %d steps; saving", model.num_timesteps)
            return False
        return done

    def _session_env(self) -> tuple[EnvConfig, int] | None:
        """This session's env and seed; None when the resumed model has trained enough.
        A resume goes on where the run was: the curriculum's episodes already driven are not
        repeated, and the session's seed gives new episodes."""
        from .curves import episode_table

        cfg, env_cfg = self.config.train, self.config.env
        if self.resume is None:
            return env_cfg, cfg.seed
        done = rundir.steps_in(self.resume.model)
        self._announce(self.resume, done)
        if done >= cfg.max_steps:
            log.info("%s has trained %d steps already (max_steps=%d); nothing to do",
                     self.resume.model, done, cfg.max_steps)
            return None
        driven = len(episode_table(self.layout.monitor))
        starting = max(0, env_cfg.episodes.starting_episodes - driven)
        return (env_cfg.replace(**{"episodes.starting_episodes": starting}),
                cfg.seed + self.layout.session)

    def _announce(self, resume: rundir.Resume, steps: int) -> None:
        """Which checkpoint this session resumes from, which newer ones do not load and why;
        the temporary files of a killed session are removed."""
        for line in resume.skipped:
            log.warning("skipped %s", line)
        model = (resume.model.relative_to(resume.run_dir)
                 if resume.model.is_relative_to(resume.run_dir) else resume.model)
        buffer = (f"its replay buffer {resume.replay_buffer.name}" if resume.replay_buffer
                  else "no replay buffer")
        log.info("resuming from %s (%d steps) with %s", model, steps, buffer)
        for partial in atomic.remove_partials(resume.run_dir):
            log.info("removed %s, a file a killed session left half-written", partial)

    def _training_env(self, stack: contextlib.ExitStack, scenario: Scenario, seed: int,
                      node: Any) -> Any:
        from .envs import make_vec_env

        cfg = self.config.train
        env = make_vec_env(scenario, n_envs=cfg.n_envs, seed=seed, reward_scale=cfg.reward_scale,
                           curriculum=cfg.curriculum, vec_env=cfg.vec_env,
                           monitor_dir=self.layout.monitor, node=node,
                           prefix=f"{self.layout.session}_")
        stack.callback(env.close)
        return env

    def _model(self, env: Any) -> Any:
        """A new model, or the resumed one with its replay buffer and ε schedule; logging to
        this session's ``logs/``."""
        from stable_baselines3.common.logger import configure

        from pic4rl_agents.models.algorithms import load_model, new_model

        cfg = self.config.train
        if self.resume is None:
            model = new_model(cfg, env)
        else:
            model = load_model(
                self.resume.model, cfg.algorithm, env=env, device=cfg.device,
                trained=self.resume.trained,
                env_from=f"this session's env ({self.config.origin})")
            if self.resume.replay_buffer is not None and hasattr(model, "load_replay_buffer"):
                model.load_replay_buffer(self.resume.replay_buffer)
            if hasattr(model, "set_epsilon"):
                model.set_epsilon(cfg.epsilon.initial, cfg.epsilon.decay, cfg.epsilon.min)
        formats = ["csv", "log"] + (["tensorboard"] if cfg.tensorboard else [])
        model.set_logger(configure(str(self.layout.logs), formats))
        return model

    def _callbacks(self, stack: contextlib.ExitStack, env_cfg: EnvConfig,
                   started: float) -> list[Any]:
        """The reward curve, checkpoints, evaluation, wall-clock limit and progress bar."""
        from .callbacks import Checkpoints, RewardCurveCallback, WallClockLimit
        from .progress import ProgressCallback

        cfg = self.config.train
        every = max(cfg.checkpoint.interval_steps // cfg.n_envs, 1)
        callbacks: list[Any] = [RewardCurveCallback(
            self.layout.monitor, self.layout.reward_curve,
            every=every if cfg.checkpoint.interval_steps else 10_000,
            window=cfg.reward_window, title=self._title())]
        if cfg.checkpoint.interval_steps:
            callbacks.append(Checkpoints(
                every, str(self.layout.checkpoints), name_prefix=rundir.CHECKPOINT_PREFIX,
                save_replay_buffer=cfg.checkpoint.replay_buffer and cfg.off_policy))
        if cfg.eval.enabled:
            callbacks.append(self._evaluation(stack, env_cfg, started))
            if cfg.eval.video_episodes:
                from .envs import eval_env_config
                from .videos import EvalVideoCallback

                callbacks.append(EvalVideoCallback(
                    callbacks[-1], eval_env_config(env_cfg, cfg.eval),
                    episodes=cfg.eval.video_episodes, seed=cfg.eval.seed,
                    out_dir=self.layout.videos))
        if cfg.max_wall_s > 0:
            callbacks.append(WallClockLimit(cfg.max_wall_s, started))
        if self.progress:
            callbacks.append(ProgressCallback(cfg.max_steps, desc=self.config.name,
                                              max_wall_s=cfg.max_wall_s, started=started))
        return callbacks

    def _evaluation(self, stack: contextlib.ExitStack, env_cfg: EnvConfig,
                    started: float) -> Any:
        """The seeded evaluation on its own in-process env."""
        from .callbacks import SeededEvalCallback
        from .envs import eval_env_config, make_vec_env

        cfg = self.config.train
        eval_env = make_vec_env(eval_env_config(env_cfg, cfg.eval), seed=cfg.eval.seed)
        stack.callback(eval_env.close)
        # One in-process env evaluates whatever the training envs are (subprocesses).
        warnings.filterwarnings("ignore", "Training and eval env are not of the same")
        return SeededEvalCallback(
            eval_env, eval_seed=cfg.eval.seed, n_eval_episodes=cfg.eval.episodes,
            interval_steps=cfg.eval.interval_steps, interval_s=cfg.eval.interval_s,
            n_envs=cfg.n_envs, clock_start=started, best_model_save_path=str(self.layout.best),
            log_path=str(self.layout.eval), callback_after_eval=self.after_eval,
            deterministic=True, verbose=0)

    def _learn(self, model: Any, callbacks: list[Any]) -> None:
        """Train up to ``max_steps``; Ctrl-C or SIGTERM ends it (the caller saves)."""
        from .callbacks import stop_on_signal, stopped_by_signal

        cfg = self.config.train
        with stop_on_signal(self._stop):
            try:
                if model.num_timesteps >= cfg.max_steps:
                    return  # imitation used every step
                fresh = self.resume is None and model.num_timesteps == 0
                log.info("RL from %d steps (the agent drives)", model.num_timesteps)
                model.learn(cfg.max_steps - model.num_timesteps, callback=callbacks,
                            reset_num_timesteps=fresh,
                            log_interval=10 if cfg.off_policy else 1)
            except BaseException as err:
                if not stopped_by_signal(err, self._stop):
                    raise
        if self._stop.is_set():
            self.interrupted = True
            log.warning("interrupted at %d steps; saving", model.num_timesteps)

    def _title(self) -> str:
        cfg = self.config.train
        return f"{self.config.name}: {cfg.algorithm.upper()} {self.config.env.sensor}"

    def _save_if_trained(self, model: Any, started: float, start_steps: int) -> None:
        """The final (or interrupted) model, its replay buffer, the curve and a summary, once
        this session has trained at all."""
        from .curves import episode_table, eval_table, save_reward_curve
        from .summary import session_summary

        if model.num_timesteps <= start_steps:
            return
        wall_s = time.perf_counter() - started
        cfg = self.config.train
        if cfg.off_policy and cfg.checkpoint.replay_buffer:  # first, as in Checkpoints
            model.save_replay_buffer(self.layout.replay_buffer)
        model.save(self.layout.model)
        save_reward_curve(self.layout.monitor, self.layout.reward_curve,
                          window=cfg.reward_window, title=self._title())
        evaluations = self.layout.eval / rundir.EVALUATIONS
        best = self.layout.best / "best_model.zip"
        summary = session_summary(
            self.config, self.layout.session, model.num_timesteps,
            model.num_timesteps - start_steps, wall_s, episode_table(self.layout.monitor),
            eval_table(evaluations) if evaluations.is_file() else None,
            best_model=best.relative_to(self.run_dir) if best.is_file() else None,
            model=self.layout.model.relative_to(self.run_dir))
        self.layout.write_summary(yaml.safe_dump(summary, sort_keys=False))
        log.info("%d steps, %d episodes, %.1f min (%s steps/s); saved %s",
                 summary["total_steps"], summary["episodes"], wall_s / 60,
                 summary["steps_per_s"], self.layout.model)



@entry_point("pic4rl-train", BridgeError)
def main(argv: Sequence[str] | None = None) -> int:
    """Train; exit 0 when done (or interrupted and saved), 2 for bad arguments or config."""
    argv = list(sys.argv[1:] if argv is None else argv)
    run: RunConfig | None = None
    try:
        plain, ros = split_ros_args(argv)
        args = build_parser().parse_args(plain)
        run, resume = resolve(args, ros)
        with console_logging("pic4rl_agents", "pic4rl-train: %(message)s"):
            Trainer(run, resume=resume, progress=not args.no_progress, ros=ros).run()
    except TransportError as err:
        hint = no_sim_hint("train", run.env if run else None)
        raise TransportError(f"{err}\n{hint}") from err
    return 0


if __name__ == "__main__":
    sys.exit(main())
