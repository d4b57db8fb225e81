"""``pic4rl-test``: trained agents and classical baselines on the same test episodes, each
episode recorded to a bag, then one metrics table from the bags (the paper's testing package).

    pic4rl-test --agent checkpoints/td3_lidar --baseline proportional --baseline dwa
    pic4rl-test --agent runs/sac_lidar --random 100 --seed 0
    pic4rl-test --agent td3=runs/td3_lidar/checkpoints/model_50000_steps.zip \
        --ros-args --params-file my_test_pairs.yaml

An agent is a run or checkpoint directory (``model.zip`` and ``config.yaml``) or a model zip
(its run's ``config.yaml`` is found above it; else give ``--algorithm`` and a params file).
Its env is its training config, then the given params files key by key, then
``--env-kwargs`` and ``-p``; a baseline uses the first agent's env, but with the robot's full
speed range (``min_linear_m_s`` 0 unless given), or the params files alone. Every agent drives the same episodes: the start–goal pairs named at test time
(``episodes.file`` in a params file or the overrides), else the paper's 5 indoor pairs when
the world is the indoor one (variant 0), else ``--episodes`` pairs drawn from ``--seed``;
``--random N`` always draws N, of the kind ``--pairs`` names (``paper``: 4-8 m apart with a
collision-free path at most 1.3 times the straight line, the default; ``any``: whatever the
simulator samples). It prints which set it used. The training pairs are never reused for
testing.
Bags go to ``<bags>/<run>/<agent>/episode_NNNN/``; the table is ``pic4rl_metrics``'s own
(``pic4rl-metrics compare`` on those bags prints the same).
"""

from __future__ import annotations

import argparse
import signal
import sys
import time
from collections.abc import Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np

from pic4rl_bridge.baselines import BASELINES, check_fits
from pic4rl_bridge.errors import BridgeError, ConfigError, TransportError
from pic4rl_sim import params_file
from pic4rl_sim.engine.sampling import PAIR_KINDS

from .config import (
    ENV_NODE,
    RunConfig,
    load_run_config,
    parse_overrides,
)
from .rosargs import RosArgs, no_sim_hint, split_ros_args
from .runs import free_path, run_config_file

#: The paper's testing set for the indoor world: 5 start–goal pairs, walked in order.
DEFAULT_PAIRS = Path(__file__).resolve().parent / "data" / "goals_indoor_test.json"


@dataclass(frozen=True)
class AgentSpec:
    """One row of the table: a trained model (``model`` set) or a baseline (``baseline``)."""

    name: str
    run: RunConfig
    model: Path | None = None
    baseline: str = ""


def _agent_files(path: Path) -> tuple[Path, Path | None]:
    """The model zip and its run's config, from a directory or a zip (the config is looked
    for beside the zip and up to two folders above: checkpoints/, best/<session>/)."""
    if path.is_dir():
        model = path / "model.zip"
        if not model.is_file():
            raise ConfigError(f"--agent {path}: no model.zip in it")
        return model, run_config_file(path)
    if path.is_file() and path.suffix == ".zip":
        for folder in (path.parent, path.parent.parent, path.parent.parent.parent):
            if (config := run_config_file(folder)) is not None:
                return path, config
        return path, None
    raise ConfigError(f"--agent {path}: no such model (expected a run directory with "
                      "model.zip and config.yaml, or a model .zip)")


def _test_pairs(ros: RosArgs, env_overrides: dict[str, Any]) -> str | None:
    """The ``episodes.file`` named at test time (params files, then overrides), if any."""
    pairs = None
    for path in ros.params_files:
        section = params_file.node_section(params_file.read(path), ENV_NODE, source=path) or {}
        if section.get("episodes.file"):
            pairs = params_file.beside(section["episodes.file"], Path(path))
    return env_overrides.get("episodes.file", pairs)


def resolve_agents(args: argparse.Namespace, ros: RosArgs) -> list[AgentSpec]:
    """The agents and baselines to test, each with its run config (env recording set up)."""
    env_overrides = {**ros.params, **parse_overrides(args.env_kwargs, flag="--env-kwargs")}
    args.test_pairs = _test_pairs(ros, env_overrides)
    sim_overrides = parse_overrides(args.sim_kwargs, flag="--sim-kwargs")
    train_overrides = {"algorithm": args.algorithm} if args.algorithm else {}
    specs: list[AgentSpec] = []
    for item in args.agent:
        name, sep, location = item.partition("=")
        path = Path(location if sep else item)
        model, config = _agent_files(path)
        files = ([str(config)] if config else []) + ros.params_files
        if not files:
            raise ConfigError(f"--agent {path}: no config.yaml beside the model; give the "
                              "env with --ros-args --params-file FILE and --algorithm")
        run = load_run_config(files, train=train_overrides, env=env_overrides,
                              sim=sim_overrides)
        if not sep:
            name = path.stem if path.suffix == ".zip" and path.stem != "model" else (
                path.parent.name if path.suffix == ".zip" else path.name)
        specs.append(AgentSpec(name, run, model=model))
    for baseline in args.baseline:
        if baseline not in BASELINES:
            raise ConfigError(f"--baseline {baseline!r}: expected one of {', '.join(BASELINES)}")
        if specs:
            run = specs[0].run
            if "min_linear_m_s" not in env_overrides:
                # An agent's speed floor is its own training choice; a baseline drives the
                # robot's full range unless the user says otherwise.
                run = replace(run, env=run.env.replace(min_linear_m_s=0.0))
        elif ros.params_files:
            run = load_run_config(ros.params_files, env=env_overrides, sim=sim_overrides)
        else:
            raise ConfigError(f"--baseline {baseline}: no env to run it in; give an --agent "
                              "or --ros-args --params-file FILE")
        check_fits(baseline, run.env)  # before any run directory or bag exists
        specs.append(AgentSpec(baseline, run, baseline=baseline))
    if not specs:
        raise ConfigError("nothing to test: give --agent PATH and/or --baseline "
                          f"{'|'.join(BASELINES)}")
    return [replace(s, run=_test_env(s, args)) for s in specs]


def _test_env(spec: AgentSpec, args: argparse.Namespace) -> RunConfig:
    """The agent's env set up for testing: recorded, the test episodes, no curriculum."""
    env = spec.run.env
    overrides: dict[str, Any] = {"agent": spec.name, "record.enabled": True,
                                 "record.bags_dir": str(Path(args.bags_dir) / args.run_dir_name),
                                 "record.run": spec.name,
                                 "episodes.starting_episodes": 0}
    sim = spec.run.env.sim_params
    pairs = args.test_pairs
    if pairs is None and sim.get("world", "indoor") == "indoor" and not sim.get(
            "world_variant", 0):
        pairs = str(DEFAULT_PAIRS)
    if args.random or not pairs:
        kind = args.pairs or ("paper" if args.random else "any")
        overrides.update({"episodes.file": "", "episodes.ordered": False,
                          "episodes.pair_kind": kind})
        args.episode_set = (f"{args.random or args.episodes} random pairs of kind {kind!r} "
                            f"with seed {args.seed}")
    else:
        if args.pairs:
            raise ConfigError(f"--pairs {args.pairs}: the test pairs come from {pairs}; add "
                              "--random N to draw N pairs of that kind")
        overrides.update({"episodes.file": pairs, "episodes.ordered": True,
                          "episodes.change_goal_and_pose": 1})
        args.episode_set = ("the paper's 5 indoor pairs" if pairs == str(DEFAULT_PAIRS)
                            else "pairs file") + f" {pairs}"
    return replace(spec.run, env=env.replace(**overrides))


class Policy:
    """What drives an episode: ``begin()`` at its start, then ``act(obs, env)`` → a
    normalised action."""

    def __init__(self, spec: AgentSpec, env: Any) -> None:
        self.spec = spec
        self.model = None
        self.controller = None
        if spec.model is not None:
            from .algorithms import load_model

            self.model = load_model(spec.model, spec.run.train.algorithm)
            if self.model.observation_space != env.observation_space:
                raise ConfigError(
                    f"--agent {spec.model}: it observes {self.model.observation_space} but "
                    f"its test env gives {env.observation_space}; test it with the sensor "
                    "and settings it was trained with")
        else:
            from pic4rl_bridge.baselines import make_baseline

            self.controller = make_baseline(spec.baseline, env.config, env.scenario.robot)

    def begin(self) -> None:
        if self.controller is not None:
            self.controller.reset()

    def act(self, obs: Any, env: Any) -> np.ndarray:
        if self.model is not None:
            action, _ = self.model.predict(obs, deterministic=True)
            return np.asarray(action)
        return self.controller.action(env.frame)


def run_agent(spec: AgentSpec, *, episodes: int, seed: int, progress: bool) -> list[str]:
    """Drive ``episodes`` episodes of ``spec``, recorded; their outcomes in order."""
    from tqdm import tqdm

    from pic4rl_bridge.env import NavEnv

    env = NavEnv(spec.run.env)
    outcomes: list[str] = []
    try:
        policy = Policy(spec, env)
        bar = tqdm(range(episodes), desc=spec.name, unit="episode", disable=not progress)
        for episode in bar:
            obs, _ = env.reset(seed=seed if episode == 0 else None)
            policy.begin()
            done, info = False, {}
            while not done:
                obs, _, terminated, truncated, info = env.step(policy.act(obs, env))
                done = terminated or truncated
            outcomes.append(str(info.get("outcome")))
            bar.set_postfix(goals=f"{outcomes.count('goal')}/{len(outcomes)}")
    finally:
        env.close()
    return outcomes


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="pic4rl-test", description=__doc__.split("\n\n")[0],
        epilog="ROS arguments after --ros-args: --params-file FILE (applied over each agent's "
               "config), -p key:=value (env keys).")
    parser.add_argument("--agent", action="append", default=[], metavar="[NAME=]PATH",
                        help="a run/checkpoint directory or model .zip (repeatable)")
    parser.add_argument("--baseline", action="append", default=[], choices=BASELINES,
                        help="a classical controller through the same tester (repeatable)")
    parser.add_argument("--algorithm", help="the algorithm of a bare model .zip")
    parser.add_argument("--episodes", type=int, default=5,
                        help="episodes per agent (default 5, the paper's)")
    parser.add_argument("--random", type=int, metavar="N",
                        help="N random start-goal pairs instead of the pairs")
    parser.add_argument("--pairs", choices=tuple(PAIR_KINDS),
                        help="kind of the drawn pairs: paper (4-8 m, detour <= 1.3; default "
                             "with --random) or any (the simulator's)")
    parser.add_argument("--seed", type=int, default=0, help="the episodes' seed (default 0)")
    parser.add_argument("--bags", dest="bags_dir", default="bags", help="bags directory")
    parser.add_argument("--run", default="", help="run name (default: test_<date>-<time>); "
                                                  "a taken name gets -2, -3, ...")
    parser.add_argument("--env-kwargs", nargs="+", default=[], metavar="KEY:VALUE")
    parser.add_argument("--sim-kwargs", nargs="+", default=[], metavar="KEY:VALUE")
    parser.add_argument("--format", default="table",
                        choices=("table", "markdown", "latex", "csv", "json"))
    parser.add_argument("--with-std", action="store_true", help="mean ± std cells")
    parser.add_argument("--no-progress", action="store_true")
    return parser


def report(run_dir: Path, fmt: str, *, with_std: bool) -> tuple[str, int]:
    """The metrics table of every bag under ``run_dir`` (grouped by agent), and how many bags
    failed; the per-episode CSV and the table are also written into ``run_dir``."""
    from pic4rl_metrics.aggregate import aggregate
    from pic4rl_metrics.batch import compute
    from pic4rl_metrics.report import render_comparison, render_episodes

    result = compute([run_dir])
    (run_dir / "episodes.csv").write_text(render_episodes(result.frame, "csv"))
    table = aggregate(result.frame, by="agent")
    (run_dir / "table.md").write_text(render_comparison(table, "markdown", with_std=with_std))
    for failed in result.failed:
        print(f"error: {failed.error}", file=sys.stderr)
    return render_comparison(table, fmt, with_std=with_std), len(result.failed)


def main(argv: Sequence[str] | None = None) -> int:
    """Test, record, report; exit 1 if a bag could not be judged, 2 for bad arguments."""
    argv = list(sys.argv[1:] if argv is None else argv)
    # Started in the background by a shell, SIGINT arrives ignored; pic4rl-run's must count.
    signal.signal(signal.SIGINT, signal.default_int_handler)
    specs: list[AgentSpec] = []
    try:
        plain, ros = split_ros_args(argv)
        args = build_parser().parse_args(plain)
        if args.episodes < 1 or (args.random is not None and args.random < 1):
            raise ConfigError("--episodes/--random: expected a positive number of episodes")
        bags_dir = Path(args.bags_dir)
        args.run_dir_name = free_path(
            bags_dir / (args.run or time.strftime("test_%Y%m%d-%H%M%S"))).name
        specs = resolve_agents(args, ros)
        episodes = args.random or args.episodes
        print(f"episodes: {args.episode_set}", file=sys.stderr)
        for spec in specs:
            outcomes = run_agent(spec, episodes=episodes, seed=args.seed,
                                 progress=not args.no_progress)
            print(f"{spec.name}: {outcomes.count('goal')}/{len(outcomes)} goals",
                  file=sys.stderr)
        run_dir = bags_dir / args.run_dir_name
        text, failed = report(run_dir, args.format, with_std=args.with_std)
    except TransportError as err:
        print(f"pic4rl-test: {err}\n{no_sim_hint('test', specs[0].run.env if specs else None)}",
              file=sys.stderr)
        return 2
    except (ConfigError, BridgeError) as err:
        print(f"pic4rl-test: {err}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("pic4rl-test: interrupted; the finished episodes' bags are kept",
              file=sys.stderr)
        return 130
    sys.stdout.write(text if text.endswith("\n") else text + "\n")
    print(f"bags: {run_dir}", file=sys.stderr)
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
