"""``pic4rl-tune``: hyperparameter search with Optuna, as RL Zoo does it. A sampler per algorithm
draws trainer parameters, each trial trains in process from a base params file and is evaluated
on the eval env's seeded test-kind pairs (``eval.*``), a median pruner stops trials whose eval
success falls below the median of earlier trials at the same evaluation, and the best trial is
written out as a params file that ``pic4rl-train`` takes as it is.

    pic4rl-tune --base config/train_goto_lidar_td3.yaml --n-trials 50 --max-steps 50000
    pic4rl-tune --base config/train_goto_lidar_td3.yaml --trial-seconds 600 --n-jobs 2 \\
        --storage postgresql://user@host/optuna --study-name td3_lidar   # several machines
    pic4rl-tune --base config/train_goto_lidar_td3.yaml --address auto --n-jobs 16 \
        --storage postgresql://user@host/optuna       # the trials as tasks of a Ray cluster

The study lives in ``<study-dir>`` (default ``<runs_dir>/tune/<study-name>``): ``study.db``
(the default storage), ``trials/trial_<n>/`` (each trial's run directory), and the summary,
rewritten after every trial: ``trials.csv``, ``best_trial.yaml``, ``best_params.yaml``, and at
the end ``importances.yaml`` and ``eval_curves.png``.
"""

from __future__ import annotations

import argparse
import contextlib
import math
import multiprocessing
import sys
import time
from collections.abc import Iterator, Sequence
from pathlib import Path
from typing import Any

import optuna
from sqlalchemy.engine import URL
from stable_baselines3.common.callbacks import BaseCallback

from pic4rl_agents.runs.config import ENV_NODE, TRAINER_NODE, RunConfig, load_run_config
from pic4rl_agents.runs.console import console_logging
from pic4rl_agents.models.algorithm_table import ALGORITHM_TABLE
from pic4rl_agents.runs.overrides import check_overrides, parse_overrides
from pic4rl_agents.training.callbacks import SeededEvalCallback
from pic4rl_base.entry import Interrupted, entry_point
from pic4rl_bridge.errors import BridgeError, ConfigError

from .settings import TrialSeeded, TuneSettings
from .space import Fixing
from .summary import log_trial, write_summary

OBJECTIVES = ("success_rate", "mean_reward")


class TrialReport(BaseCallback):
    """``callback_after_eval`` of a trial: reports each evaluation to Optuna (step 1, 2, ...),
    stops a trial that the pruner prunes, and one that has used its ``trial_seconds``."""

    def __init__(self, trial: optuna.Trial, settings: TuneSettings) -> None:
        super().__init__()
        self.trial, self.settings = trial, settings
        self.evaluations = 0
        self.pruned = False

    def _on_step(self) -> bool:
        evaluation = self.parent
        assert isinstance(evaluation, SeededEvalCallback)
        value = (evaluation.last_success_rate if self.settings.objective == "success_rate"
                 else evaluation.last_mean_reward)
        self.evaluations += 1
        self.trial.report(value, self.evaluations)
        if self.trial.should_prune():
            self.pruned = True
            return False
        budget = self.settings.trial_seconds
        return not (budget > 0 and evaluation.last_row["train_wall_s"] >= budget)


def suggest(trial: Any, base: RunConfig, fixed: dict[str, Any]) -> dict[str, Any]:
    """The trial's trainer parameters: the algorithm's sampler (drawing none that ``fixed``
    holds), then ``fixed`` (which wins); kept in the trial's user attribute ``hyperparams``
    for the best params file and ``trials.csv``."""
    algorithm = base.train.algorithm
    sampled = ALGORITHM_TABLE[algorithm].sampler(Fixing(trial, fixed), base.train.n_envs)
    params = {**sampled, "algorithm": algorithm, **fixed}
    trial.set_user_attr("hyperparams", params)
    return params


def objective(trial: optuna.Trial, settings: TuneSettings) -> float:
    """Train trial ``trial`` and return its last evaluation's objective; raise
    ``optuna.TrialPruned`` when the pruner stopped it."""
    from pic4rl_agents.training.curves import eval_curves
    from pic4rl_agents.training.train import Trainer

    params = suggest(trial, settings.base, settings.fixed)
    run = settings.trial_run(trial.number, params)
    report = TrialReport(trial, settings)
    trainer = Trainer(run, progress=False, after_eval=report)
    trial.set_user_attr("run_dir", str(trainer.run_dir))
    trainer.run()
    if trainer.interrupted:
        raise KeyboardInterrupt
    try:
        (evaluations,) = eval_curves(trainer.run_dir).values()
    except ConfigError:
        raise ConfigError(f"trial {trial.number}: no evaluation ran (max_steps "
                          f"{settings.max_steps} ended it before the first)") from None
    last = evaluations.iloc[-1]
    for key in ("steps", "train_wall_s", "success_rate", "mean_reward", "mean_length"):
        trial.set_user_attr(key, float(last[key]))
    if report.pruned:
        raise optuna.TrialPruned(f"pruned at evaluation {report.evaluations}")
    return float(last[settings.objective])


def create_study(settings: TuneSettings, *, pruner: str = "median", n_startup_trials: int = 5,
                 seed: int = 0) -> Any:
    """The study in ``settings.storage`` (created, or loaded when it exists: trials on
    several machines share it): TPE seeded per trial (``TrialSeeded``: a resumed study draws
    anew), and RL Zoo's median pruner (no pruning before ``n_startup_trials`` trials
    completed, nor in the first third of a trial's evaluations)."""
    sampler = TrialSeeded(seed, n_startup_trials)
    if pruner == "median":
        chosen: Any = optuna.pruners.MedianPruner(n_startup_trials=n_startup_trials,
                                                  n_warmup_steps=settings.n_evaluations // 3)
    else:
        chosen = optuna.pruners.NopPruner()
    return optuna.create_study(study_name=settings.study_name, storage=settings.storage,
                               sampler=sampler, pruner=chosen, direction="maximize",
                               load_if_exists=True)


def optimize(settings: TuneSettings, *, n_trials: int, timeout_s: float | None = None,
             pruner: str = "median", n_startup_trials: int = 5, seed: int = 0) -> Any:
    """Run ``n_trials`` trials in this process (fewer when ``timeout_s`` passes first); the
    summary is rewritten after each. A trial whose config is refused fails, and the next
    goes on."""
    optuna.logging.set_verbosity(optuna.logging.ERROR)  # each trial's line is log_trial's
    study = create_study(settings, pruner=pruner, n_startup_trials=n_startup_trials, seed=seed)

    def after(study: Any, trial: Any) -> None:
        log_trial(study, trial)
        write_summary(study, settings)

    def run(trial: optuna.Trial) -> float:
        try:
            return objective(trial, settings)
        except (ConfigError, BridgeError) as err:
            trial.set_user_attr("error", str(err))
            raise

    study.optimize(run, n_trials=n_trials, timeout=timeout_s, catch=(ConfigError, BridgeError),
                   callbacks=[after])
    return study


def _shares(settings: TuneSettings, n_jobs: int,
            options: dict[str, Any]) -> list[dict[str, Any]]:
    """Each worker's ``optimize`` options: the trials split among ``n_jobs`` workers (their
    trials' numbers, hence their draws, differ). Creates the study first, once, before the
    workers load it."""
    create_study(settings)
    counts = [options["n_trials"] // n_jobs + (i < options["n_trials"] % n_jobs)
              for i in range(n_jobs)]
    return [{**options, "n_trials": count} for count in counts if count > 0]


def _optimize_on_ray(settings: TuneSettings, n_jobs: int, options: dict[str, Any],
                     address: str) -> Any:
    """The workers as Ray tasks (one CPU each) on the cluster at ``address``, sharing the
    study's storage; Ray is the ``cluster`` extra."""
    try:
        import ray
    except ImportError as err:
        raise ConfigError("--address: Ray is not installed (pip install 'pic4rl[cluster]')") \
            from err
    from pic4rl_agents.launch import raycluster

    shares = _shares(settings, n_jobs, options)
    raycluster.init(address, num_cpus=n_jobs if address == "local" else None,
                    include_dashboard=False, logging_level="ERROR", log_to_driver=True)
    try:
        task = ray.remote(num_cpus=1, max_retries=0)(_worker)
        ray.get([task.remote(settings, share) for share in shares])
    finally:
        ray.shutdown()
    return create_study(settings)


def _worker(settings: TuneSettings, options: dict[str, Any]) -> None:
    with _console(), contextlib.suppress(KeyboardInterrupt):  # the parent reports it
        optimize(settings, **options)


@contextlib.contextmanager
def _console() -> Iterator[None]:
    """The trials on stdout; each trial's training summary and the summary's warnings on
    stderr."""
    with console_logging(__name__, "pic4rl-tune: %(message)s", stream=sys.stdout), \
            console_logging("pic4rl_agents.tune.summary", "pic4rl-tune: %(message)s"), \
            console_logging("pic4rl_agents.tune.settings", "pic4rl-tune: %(message)s"), \
            console_logging("pic4rl_agents.training.train", "pic4rl-train: %(message)s"):
        yield


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="pic4rl-tune", description=__doc__.split("\n\n")[0])
    parser.add_argument("--base", default="config/train_goto_lidar_td3.yaml", metavar="FILE",
                        help="the params file every trial starts from (default %(default)s)")
    parser.add_argument("--algorithm", help="tune this algorithm instead of the base's")
    parser.add_argument("--n-trials", type=int, default=20, help="trials to run (default 20)")
    parser.add_argument("--timeout", type=float, metavar="S",
                        help="stop starting trials after S seconds")
    parser.add_argument("--n-jobs", type=int, default=1,
                        help="worker processes sharing the study (default 1)")
    parser.add_argument("--address", metavar="RAY",
                        help="run the --n-jobs workers as Ray tasks on this cluster ('auto': "
                             "the one this machine joined, 'local': a new local Ray); every "
                             "node must reach --storage (an RDB server URL across machines)")
    parser.add_argument("--storage", metavar="URL",
                        help="Optuna RDB storage (default sqlite:///<study-dir>/study.db)")
    parser.add_argument("--study-name", help="default: the base run's name")
    parser.add_argument("--study-dir", metavar="DIR",
                        help="default <runs_dir>/tune/<study-name>")
    parser.add_argument("--max-steps", type=int, default=50_000,
                        help="env steps per trial (default 50000)")
    parser.add_argument("--trial-seconds", type=float, default=0.0, metavar="S",
                        help="training seconds per trial (evaluations excluded); 0: steps only")
    parser.add_argument("--n-evaluations", type=int, default=5,
                        help="evaluations per trial, reported to the pruner (default 5)")
    parser.add_argument("--eval-episodes", type=int,
                        help="episodes per evaluation (default: the base's eval.episodes)")
    parser.add_argument("--objective", choices=OBJECTIVES, default="success_rate",
                        help="what the trials maximise: eval success rate (default) or mean "
                             "reward, at the trial's last evaluation")
    parser.add_argument("--pruner", choices=("median", "none"), default="median")
    parser.add_argument("--n-startup-trials", type=int, default=5,
                        help="trials before the pruner and TPE start (default 5)")
    parser.add_argument("--seed", type=int, default=0,
                        help="the sampler's seed (trial n draws from seed + n)")
    parser.add_argument("--hyperparams", nargs="+", default=[], metavar="KEY:VALUE",
                        help="trainer parameters fixed in every trial (they win over the "
                             "sampler's)")
    parser.add_argument("--env-kwargs", nargs="+", default=[], metavar="KEY:VALUE",
                        help="env (nav_env) parameters for every trial")
    return parser


def settings_from(args: argparse.Namespace) -> TuneSettings:
    """The study's settings from the command line; a bad one is a ``ConfigError``."""
    for flag, value in (("--n-trials", args.n_trials), ("--n-jobs", args.n_jobs),
                        ("--max-steps", args.max_steps), ("--n-evaluations", args.n_evaluations)):
        if value < 1:
            raise ConfigError(f"{flag} {value}: expected a positive integer")
    if not math.isfinite(args.trial_seconds) or args.trial_seconds < 0:
        raise ConfigError(f"--trial-seconds {args.trial_seconds}: expected a number >= 0")
    if not Path(args.base).is_file():
        raise ConfigError(f"--base {args.base}: no such params file")
    fixed = check_overrides(TRAINER_NODE, parse_overrides(args.hyperparams, flag="--hyperparams"),
                            where="--hyperparams")
    if args.algorithm:
        fixed.setdefault("algorithm", args.algorithm)
    entry = ALGORITHM_TABLE.get(str(fixed.get("algorithm")))
    if entry and not entry.off_policy:
        fixed.setdefault("epsilon.initial", 0.0)  # a base with ε-greedy: not for on-policy
    if args.eval_episodes is not None and args.eval_episodes < 1:
        raise ConfigError(f"--eval-episodes {args.eval_episodes}: expected a positive integer")
    env = check_overrides(ENV_NODE, parse_overrides(args.env_kwargs, flag="--env-kwargs"),
                          where="--env-kwargs")
    base = load_run_config([args.base], train=fixed, env=env)
    name = args.study_name or base.name
    study_dir = Path(args.study_dir or Path(base.train.runs_dir) / "tune" / name)
    study_dir.mkdir(parents=True, exist_ok=True)
    # Quoted (URL.create): a folder named with '?', '#' or '%xx' stays that folder.
    storage = args.storage or URL.create(
        "sqlite", database=str((study_dir / "study.db").resolve())).render_as_string(False)
    return TuneSettings(base, fixed, name, study_dir, storage, args.max_steps,
                        args.trial_seconds, args.n_evaluations, args.eval_episodes,
                        args.objective)


@entry_point("pic4rl-tune", BridgeError)
def main(argv: Sequence[str] | None = None) -> int:
    """Tune; exit 0 when done, 2 for bad arguments, 130 after Ctrl-C (the summary written)."""
    args = build_parser().parse_args(argv)
    with _console():
        return _tune(args)


def _tune(args: argparse.Namespace) -> int:
    optuna.logging.set_verbosity(optuna.logging.ERROR)
    settings: TuneSettings | None = None
    try:
        settings = settings_from(args)
        options = {"n_trials": args.n_trials, "timeout_s": args.timeout, "pruner": args.pruner,
                   "n_startup_trials": args.n_startup_trials, "seed": args.seed}
        print(f"pic4rl-tune: study {settings.study_name!r} in {settings.study_dir} "
              f"({settings.storage}), {args.n_trials} trials of {settings.base.train.algorithm}"
              f", {args.n_jobs} job(s)", flush=True)
        started = time.perf_counter()
        if args.address:
            study = _optimize_on_ray(settings, args.n_jobs, options, args.address)
        elif args.n_jobs == 1:
            study = optimize(settings, **options)
        else:
            study = _optimize_in_processes(settings, args.n_jobs, args.seed, options)
    except KeyboardInterrupt:
        if settings is not None:
            with contextlib.suppress(KeyboardInterrupt):  # a second Ctrl-C: the summary as is
                write_summary(create_study(settings), settings, final=True)
        where = f"; the summary is in {settings.study_dir}" if settings is not None else ""
        raise Interrupted(f"interrupted{where}") from None
    write_summary(study, settings, final=True)
    minutes = (time.perf_counter() - started) / 60
    try:
        best = (f"best trial {study.best_trial.number}: {settings.objective} "
                f"{study.best_value:.3g}; {settings.study_dir / 'best_params.yaml'}")
    except ValueError:
        best = "no trial completed"
    print(f"pic4rl-tune: {len(study.trials)} trials in the study, {minutes:.1f} min; {best}",
          flush=True)
    return 0


def _optimize_in_processes(settings: TuneSettings, n_jobs: int, options: dict[str, Any]) -> Any:
    """``n_jobs`` processes, each running ``optimize`` on the shared storage (threads would
    share one interpreter lock: the env and SB3's loop are Python); trials are split among
    them."""
    context = multiprocessing.get_context("spawn")
    workers = [context.Process(target=_worker, args=(settings, share))
               for share in _shares(settings, n_jobs, options)]
    for worker in workers:
        worker.start()
    try:
        for worker in workers:
            worker.join()
    except KeyboardInterrupt:
        for worker in workers:
            worker.join(timeout=60)
        raise
    return create_study(settings)


if __name__ == "__main__":
    sys.exit(main())
