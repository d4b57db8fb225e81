"""``pic4rl-test``: trained agents and classical baselines on the same test episodes, each
episode recorded to a bag, then one metrics table from the bags (the paper's testing package).

    pic4rl-test --agent checkpoints/td3_lidar --baseline proportional --baseline dwa
    pic4rl-test --agent runs/sac_lidar --random 100 --seed 0
    pic4rl-test --agent td3=runs/td3_lidar/checkpoints/model_50000_steps.zip \
        --ros-args --params-file my_test_pairs.yaml

An agent is a run or checkpoint directory (``model.zip`` and ``config.yaml``) or a model zip
(its run's ``config.yaml`` is found above it; else give ``--algorithm`` and a params file),
a TorchScript ``.pt`` with its sidecar, or a policy plugin (``FILE.py:NAME``,
``package.module:NAME``, an entry point: ``pic4rl_agents.testing.policies``), which runs in a
baseline's env and whose failure ends that episode ``aborted``. Its env is its training config, then the given params files key by key, then
``--env-kwargs`` and ``-p``; a baseline uses the first agent's env, but with the robot's full
speed range (``min_linear_m_s`` 0 unless given), or the params files alone. Every agent drives
the same episodes: the start–goal pairs named at test time
(``episodes.file`` in a params file or the overrides), else the paper's 5 indoor pairs when
the world is the indoor one (variant 0), else ``--episodes`` pairs drawn from ``--seed``;
``--random N`` always draws N, of the kind ``--pairs`` names (``paper``: 4-8 m apart with a
collision-free path at most 1.3 times the straight line, the default; ``any``: whatever the
simulator samples). It prints which set it used. The training pairs are never reused for
testing.
Bags go to ``<bags>/<run>/<agent>/episode_NNNN/`` (with ``--video``, each episode's video
beside it, ``episode_NNNN.mp4``, drawn from the bag by ``pic4rl_metrics``); the table is
``pic4rl_metrics``'s own (``pic4rl-metrics compare`` on those bags prints the same). The
command line builds a ``TestPlan``; ``drive_and_judge(plan)`` does the test and returns a
``TestResult``.
"""

from __future__ import annotations

import argparse
import logging
import shutil
import signal
import sys
import time
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

from pic4rl_agents.runs.config import ENV_NODE, SIM_NODE
from pic4rl_agents.runs.console import console_logging
from pic4rl_agents.runs.overrides import check_overrides, parse_overrides
from pic4rl_agents.launch.rosargs import RosArgs, no_sim_hint, split_ros_args
from pic4rl_base import atomic
from pic4rl_base.entry import entry_point
from pic4rl_bridge.baselines import BASELINES
from pic4rl_bridge.errors import BridgeError, ConfigError, TransportError
from pic4rl_bridge.settings.baselines import PREFIX as BASELINES_PREFIX
from pic4rl_bridge.settings.baselines import baselines_config_from_params
from pic4rl_bridge.settings.tasks import TASK_TABLE
from pic4rl_sim.engine.sampling import PAIR_KINDS

from .plan import AgentSpec, TestPlan, recorded, resolve_agents
from .policies import Driver, PolicyFailure

if TYPE_CHECKING:
    import pandas as pd

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class TestResult:
    """What a test did: its bags, each agent's outcomes, the metrics table by agent."""

    run_dir: Path  # <bags>/<run>: <agent>/episode_NNNN/ bags, episodes.csv, table.md
    episode_set: str  # the episodes driven, in words
    outcomes: dict[str, list[str]]  # by agent, in episode order
    table: pd.DataFrame  # pic4rl_metrics.tables.aggregate by agent
    failed: tuple[str, ...] = ()  # the errors of bags that could not be judged
    videos: tuple[str, ...] = ()  # with --video: one per episode, beside its bag


def drive_agent(spec: AgentSpec, *, episodes: int, seed: int, progress: bool) -> list[str]:
    """Drive ``episodes`` episodes of ``spec``, recorded; their outcomes in order."""
    from tqdm import tqdm

    from pic4rl_bridge.env import NavEnv
    from pic4rl_bridge.recording import record_from_config

    nav = NavEnv(spec.scenario or spec.run.env)  # what the policy sees; ``env`` records it
    env = record_from_config(nav) if spec.run.env.record.enabled else nav
    outcomes: list[str] = []
    headline, words = TASK_TABLE[spec.run.env.task].headline
    try:
        policy = Driver(spec, nav)
        bar = tqdm(range(episodes), desc=spec.name, unit="episode", disable=not progress)
        for episode in bar:
            obs, _ = env.reset(seed=seed if episode == 0 else None)
            done, info = False, {}
            try:
                policy.begin(nav)
                while not done:
                    obs, _, terminated, truncated, info = env.step(policy.act(obs, nav))
                    done = terminated or truncated
            except PolicyFailure as err:  # that episode ends aborted; the next one runs
                log.error("%s: episode %d aborted: %s", spec.name, episode, err)
                env.abort(str(err))
                info = {"outcome": "aborted"}
            outcomes.append(str(info.get("outcome")))
            bar.set_postfix({words: f"{outcomes.count(headline)}/{len(outcomes)}"})
    finally:
        env.close()
    return outcomes


def render_table(table: pd.DataFrame, task: str, fmt: str, *, with_std: bool) -> str:
    """The test's table: the episodes per outcome, the headline first, then its rate, SPL
    where a row has it, then Table 1's. The headline is the metrics' (``groups.headline``):
    goals and the success rate (named as ``task`` names its goals: ``row ends``), or for a
    table without a goal (person monitoring) full runs, their k/n, and no goal's columns."""
    from pic4rl_metrics.tables.groups import headline, headline_columns
    from pic4rl_metrics.tables.results import table_columns
    from pic4rl_metrics.tables.text import OUTCOME_COUNTS, render_comparison

    if headline(table) != "success":
        counts = {"n_full_runs": "full runs", **{k: v for k, v in OUTCOME_COUNTS.items()
                                                 if k not in ("n_success", "n_timeout")}}
        return render_comparison(table, fmt, columns=headline_columns(
            table, table_columns(table)), with_std=with_std, counts=counts)
    outcome, words = TASK_TABLE[task].headline
    counts = {**OUTCOME_COUNTS, "n_success": words if outcome == "goal" else "goals"}
    columns = list(table_columns(table))
    if "spl_mean" in table.columns and table["spl_mean"].notna().any():
        columns.insert(1, "spl")
    return render_comparison(table, fmt, columns=columns, with_std=with_std, counts=counts)


def judge(run_dir: Path, task: str, *,
          with_std: bool) -> tuple[pd.DataFrame, tuple[str, ...]]:
    """The metrics table of every bag under ``run_dir`` (grouped by agent; its trajectory
    columns average the successful episodes, or every episode where the table has no goal:
    ``groups.headline``; ``task``: the agents' task, naming its goals) and the errors of the
    bags that could not be judged; the per-episode CSV and the table (markdown) are written
    into ``run_dir``."""
    from pic4rl_metrics.tables.aggregate import aggregate
    from pic4rl_metrics.tables.batch import compute
    from pic4rl_metrics.tables.groups import headline
    from pic4rl_metrics.tables.text import render_episodes

    result = compute([run_dir])
    atomic.write_text(run_dir / "episodes.csv", render_episodes(result.frame, "csv"))
    table = aggregate(result.frame, by="agent")
    if headline(table) != "success":  # no goal (person monitoring): over every episode
        table = aggregate(result.frame, by="agent", over="all")
    atomic.write_text(run_dir / "table.md",
                      render_table(table, task, "markdown", with_std=with_std))
    return table, tuple(str(failed.error) for failed in result.failed)


def _check_video() -> None:
    """``--video``'s encoder is there, before any episode is driven."""
    from pic4rl_base.errors import Pic4rlError
    from pic4rl_metrics.viz.video_batch import ffmpeg_writer

    try:
        ffmpeg_writer()
    except Pic4rlError as err:
        raise ConfigError(f"--video: {err}") from err


def drive_and_judge(plan: TestPlan, agents: Sequence[AgentSpec] | None = None) -> TestResult:
    """Drive every agent and baseline of ``plan`` (``agents``: as ``resolve_agents(plan)``
    gave them, when resolved already) on the same episodes, each recorded to a bag in a new
    ``<bags>/<run>`` (claimed atomically; removed again when an agent is refused before its
    first episode), then judge the bags."""
    if plan.video:
        _check_video()
    specs = list(agents or resolve_agents(plan))
    run_dir = atomic.claim_dir(plan.bags_dir / (plan.run or time.strftime("test_%Y%m%d-%H%M%S")))
    specs = [recorded(s, run_dir) for s in specs]
    episode_set = specs[-1].episode_set
    log.info("episodes: %s", episode_set)
    for spec in specs:
        if spec.baseline or spec.plugin:
            log.info("%s", spec.env_line)
    outcomes: dict[str, list[str]] = {}
    try:
        for spec in specs:
            outcomes[spec.name] = drive_agent(spec, episodes=plan.n_episodes, seed=plan.seed,
                                            progress=plan.progress)
            headline, words = TASK_TABLE[spec.run.env.task].headline
            log.info("%s: %d/%d %s", spec.name, outcomes[spec.name].count(headline),
                     len(outcomes[spec.name]), words)
    except BaseException:
        if not any(run_dir.glob("*/episode_*")):  # refused before any episode: no trace
            shutil.rmtree(run_dir, ignore_errors=True)
        raise
    table, failed = judge(run_dir, specs[0].run.env.task, with_std=plan.with_std)
    videos: tuple[str, ...] = ()
    if plan.video:
        from pic4rl_metrics.viz.video_batch import render_videos

        rows = render_videos([run_dir], progress=plan.progress)
        videos = tuple(r.video for r in rows if r.video)
        failed += tuple(r.error for r in rows if r.error and r.error not in failed)
    return TestResult(run_dir, episode_set, outcomes, table, failed, videos)


_DEFAULT = TestPlan()  # the command line's defaults are the plan's


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="pic4rl-test", description=__doc__.split("\n\n")[0],
        epilog="ROS arguments after --ros-args: --params-file FILE (applied over each agent's "
               "config), -p key:=value (env keys; baselines.* keys: the baselines: section's).")
    parser.add_argument("--agent", action="append", default=[], metavar="[NAME=]PATH",
                        help="a run/checkpoint directory, a model .zip (any SB3/sb3-contrib "
                             "algorithm), a TorchScript .pt with its sidecar, or a policy "
                             "plugin FILE.py:NAME, package.module:NAME or entry point "
                             "(repeatable; docs/your-agent.md)")
    parser.add_argument("--baseline", action="append", default=[], choices=BASELINES,
                        help="a classical controller through the same tester (repeatable)")
    parser.add_argument("--algorithm", help="the algorithm of a bare model .zip (any SB3 or "
                        "sb3-contrib class: ppo, tqc, RecurrentPPO, ...)")
    parser.add_argument("--episodes", type=int, default=_DEFAULT.episodes,
                        help="episodes per agent (default %(default)s, the paper's)")
    parser.add_argument("--random", type=int, metavar="N",
                        help="N random start-goal pairs instead of the pairs")
    parser.add_argument("--pairs", choices=tuple(PAIR_KINDS),
                        help="kind of the drawn pairs: paper (4-8 m, detour <= 1.3; default "
                             "with --random) or any (the simulator's)")
    parser.add_argument("--seed", type=int, default=_DEFAULT.seed,
                        help="the episodes' seed (default %(default)s)")
    parser.add_argument("--bags", dest="bags_dir", default=str(_DEFAULT.bags_dir),
                        help="bags directory")
    parser.add_argument("--run", default=_DEFAULT.run, help="run name (default: "
                        "test_<date>-<time>); a taken name gets -2, -3, ...")
    parser.add_argument("--env-kwargs", nargs="+", default=[], metavar="KEY:VALUE")
    parser.add_argument("--sim-kwargs", nargs="+", default=[], metavar="KEY:VALUE")
    parser.add_argument("--format", default="table",
                        choices=("table", "markdown", "latex", "csv", "json"))
    parser.add_argument("--with-std", action="store_true", help="mean ± std cells")
    parser.add_argument("--video", action="store_true",
                        help="an MP4 of each episode beside its bag (episode_NNNN.mp4)")
    parser.add_argument("--no-progress", action="store_true")
    return parser



def build_plan(args: argparse.Namespace, ros: RosArgs) -> TestPlan:
    """The plan of a ``pic4rl-test`` command line: its parsed arguments and ROS arguments."""
    env_params = {k: v for k, v in ros.params.items() if not k.startswith(BASELINES_PREFIX)}
    baseline_params = {k[len(BASELINES_PREFIX):]: v for k, v in ros.params.items()
                       if k.startswith(BASELINES_PREFIX)}
    try:
        baselines_config_from_params(baseline_params)
    except ConfigError as err:
        raise ConfigError(f"-p parameters: {err}") from err
    return TestPlan(
        agents=tuple(args.agent), baselines=tuple(args.baseline), algorithm=args.algorithm or "",
        episodes=args.episodes, random=args.random, pairs=args.pairs, seed=args.seed,
        bags_dir=Path(args.bags_dir), run=args.run, params_files=tuple(ros.params_files),
        env_overrides={
            **check_overrides(ENV_NODE, env_params, where="-p parameters"),
            **check_overrides(ENV_NODE, parse_overrides(args.env_kwargs, flag="--env-kwargs"),
                              where="--env-kwargs")},
        sim_overrides=check_overrides(SIM_NODE, parse_overrides(args.sim_kwargs,
                                                                flag="--sim-kwargs"),
                                      where="--sim-kwargs"),
        baseline_overrides=baseline_params, with_std=args.with_std, video=args.video,
        progress=not args.no_progress)


@entry_point("pic4rl-test", BridgeError,
             interrupted="interrupted; the finished episodes' bags are kept")
def main(argv: Sequence[str] | None = None) -> int:
    """Test, record, report; exit 1 if a bag could not be judged, 2 for bad arguments."""
    argv = list(sys.argv[1:] if argv is None else argv)
    # Started in the background by a shell, SIGINT arrives ignored; pic4rl-run's must count.
    signal.signal(signal.SIGINT, signal.default_int_handler)
    agents: list[AgentSpec] = []
    try:
        plain, ros = split_ros_args(argv)
        args = build_parser().parse_args(plain)
        plan = build_plan(args, ros)
        agents = resolve_agents(plan)
        with console_logging(__name__):
            result = drive_and_judge(plan, agents)
    except TransportError as err:
        env = agents[0].run.env if agents else None
        raise TransportError(f"{err}\n{no_sim_hint('test', env)}") from err
    for error in result.failed:
        print(f"error: {error}", file=sys.stderr)
    text = render_table(result.table, agents[0].run.env.task, args.format,
                        with_std=plan.with_std)
    sys.stdout.write(text if text.endswith("\n") else text + "\n")
    print(f"bags: {result.run_dir}", file=sys.stderr)
    if result.videos:
        print(f"videos: {len(result.videos)} in {result.run_dir}/<agent>/, e.g. "
              f"{result.videos[0]}", file=sys.stderr)
    return 1 if result.failed else 0


if __name__ == "__main__":
    sys.exit(main())
