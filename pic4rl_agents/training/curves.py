"""Training curves: the reward curve of a run, like the paper's Figure 4 (each episode's reward
and its moving average, from the run's Monitor CSVs, one per env; the expert's, the student's
and RL's episodes apart), and the evaluation curves of several runs in one figure (eval
success against the clock and against env steps, from their ``evaluations.csv``), so that two
recipes compare on one plot::

    python -m pic4rl_agents.training.curves runs/td3_lidar sac=runs/sac_lidar -o curves.png
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import pandas as pd
from stable_baselines3.common.monitor import LoadMonitorResultsError, load_results

from pic4rl_agents.runs import rundir
from pic4rl_base import atomic
from pic4rl_bridge.errors import ConfigError

from .envs import DRIVER_KEY

#: The ``driver`` of an episode a monitor file from before drivers were recorded holds.
UNRECORDED = "unrecorded"
#: How the reward curve draws each driver (``envs.DRIVERS``): colour and legend label.
DRIVER_STYLE = {"rl": ("tab:blue", "RL"), "student": ("tab:orange", "student (DAgger)"),
                "expert": ("tab:gray", "expert (imitation)"),
                "mixed": ("tab:purple", "mixed (phase change)"),
                UNRECORDED: ("tab:blue", "episode reward")}


def episode_table(monitor_dir: Path) -> pd.DataFrame:
    """Every finished episode of every env in time order: ``r`` (reward), ``l`` (steps),
    ``t`` (s since the start), ``is_success``, ``outcome``, ``driver`` (``envs.DRIVERS``;
    ``UNRECORDED`` in monitor files written before drivers were); empty when none finished."""
    try:
        df = load_results(str(monitor_dir))
    except LoadMonitorResultsError:
        df = pd.DataFrame()
    if df.empty:  # no file, or none with a row (then SB3 gives r, l, t only)
        return pd.DataFrame(columns=["r", "l", "t", "is_success", "outcome", DRIVER_KEY])
    if DRIVER_KEY not in df:
        df[DRIVER_KEY] = UNRECORDED
    df[DRIVER_KEY] = df[DRIVER_KEY].fillna(UNRECORDED)
    return df.sort_values("t").reset_index(drop=True)


def reward_series(episodes: pd.DataFrame, window: int) -> dict[str, pd.DataFrame]:
    """The reward curve's lines, one per driver in ``DRIVER_STYLE``'s order: ``episode``
    (1-based, in the run's order), ``r`` and ``mean`` (the moving average over that driver's
    last ``window`` episodes: the expert's rewards never lift the agent's average)."""
    numbered = episodes.assign(episode=range(1, len(episodes) + 1))
    series = {}
    for driver in DRIVER_STYLE:
        own = numbered[numbered[DRIVER_KEY] == driver]
        if len(own):
            series[driver] = pd.DataFrame({
                "episode": own["episode"].to_numpy(), "r": own["r"].to_numpy(),
                "mean": own["r"].rolling(window, min_periods=1).mean().to_numpy()})
    return series


def save_reward_curve(monitor_dir: Path, out: Path, *, window: int = 50,
                      title: str = "") -> Path | None:
    """Write ``out`` (PNG): each driver's episode rewards and moving average in its own
    colour (``reward_series``); ``None`` (nothing written) before the first finished episode."""
    df = episode_table(monitor_dir)
    if df.empty:
        return None
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7, 3.5), layout="constrained")
    for driver, line in reward_series(df, window).items():
        colour, label = DRIVER_STYLE[driver]
        ax.plot(line["episode"], line["r"], ".", color=colour, alpha=0.45, ms=4)
        ax.plot(line["episode"], line["mean"], color=colour, lw=2,
                marker="o" if len(line) == 1 else None,
                label=f"{label}: moving average ({window} episodes)")
    ax.set_xlabel("episode")
    ax.set_ylabel("reward")
    ax.set_title(title)
    ax.grid(alpha=0.3)
    ax.legend(loc="best", fontsize="small")
    with atomic.replacing(out) as tmp:  # whole or not at all
        fig.savefig(tmp, dpi=120, format=out.suffix.lstrip(".") or "png")
    plt.close(fig)
    return out


# -- evaluation curves: success against the clock and against env steps ------------------------

#: x-axes of the evaluation curves: ``evaluations.csv`` columns and their axis labels.
EVAL_AXES = {"train_wall_s": "training wall-clock (min, evaluations excluded)",
             "wall_s": "wall-clock (min, evaluations included)", "steps": "env steps"}
EVAL_METRICS = ("success_rate", "mean_reward", "mean_length")


def eval_table(path: str | Path) -> pd.DataFrame:
    """One ``evaluations.csv`` (``pic4rl_agents.training.callbacks.CSV_COLUMNS``)."""
    path = Path(path)
    try:
        df = pd.read_csv(path)
    except (OSError, pd.errors.ParserError, pd.errors.EmptyDataError) as err:
        raise ConfigError(f"{path}: cannot read the evaluations: {err}") from err
    missing = [c for c in ("steps", "wall_s", "train_wall_s", *EVAL_METRICS) if c not in df]
    if missing:
        raise ConfigError(f"{path}: not an evaluations.csv (no column {missing[0]!r})")
    return df


def eval_curves(source: str | Path, label: str | None = None) -> dict[str, pd.DataFrame]:
    """The evaluations of ``source``: an ``evaluations.csv``, or a run directory (each
    session's ``eval/<session>/evaluations.csv``: one curve per session, since each session's
    clock starts at 0), by label (``label``, else the run's name)."""
    path = Path(source)
    if path.is_file():
        return {label or rundir.run_of_evaluations(path): eval_table(path)}
    files = rundir.evaluation_files(path)
    if not files:
        raise ConfigError(f"{path}: no evaluations (expected a run directory with "
                          "eval/<session>/evaluations.csv, or such a file)")
    name = label or path.resolve().name
    if len(files) == 1:
        return {name: eval_table(files[0])}
    return {f"{name} (session {f.parent.name})": eval_table(f) for f in files}


def plot_eval_curves(ax: Any, curves: Mapping[str, pd.DataFrame], *, x: str = "train_wall_s",
                     metric: str = "success_rate") -> None:
    """Draw ``metric`` against ``x`` (an ``EVAL_AXES`` key; clocks in minutes), one line per
    curve, on ``ax``."""
    for label, df in curves.items():
        xs = df[x] / 60.0 if x != "steps" else df[x]
        ys = df[metric] * 100.0 if metric == "success_rate" else df[metric]
        ax.plot(xs, ys, marker="o", ms=3, lw=1.5, label=label)
    ax.set_xlim(left=0)  # runs compare from their start
    ax.set_xlabel(EVAL_AXES[x])
    ax.set_ylabel("eval success (%)" if metric == "success_rate" else f"eval {metric}")
    if metric == "success_rate":
        ax.set_ylim(-2, 102)
    ax.grid(alpha=0.3)


def save_eval_curves(curves: Mapping[str, pd.DataFrame], out: Path, *,
                     clock: str = "train_wall_s", metric: str = "success_rate",
                     title: str = "") -> Path:
    """One PNG, two panels: ``metric`` against ``clock`` and against env steps."""
    if clock not in ("train_wall_s", "wall_s"):
        raise ConfigError(f"clock: {clock!r} is invalid; expected train_wall_s or wall_s")
    if metric not in EVAL_METRICS:
        raise ConfigError(f"metric: {metric!r} is invalid; expected one of "
                          f"{', '.join(EVAL_METRICS)}")
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (left, right) = plt.subplots(1, 2, figsize=(11, 4), layout="constrained")
    plot_eval_curves(left, curves, x=clock, metric=metric)
    plot_eval_curves(right, curves, x="steps", metric=metric)
    right.set_ylabel("")
    left.legend(loc="best", fontsize="small")
    if title:
        fig.suptitle(title)
    with atomic.replacing(out) as tmp:
        fig.savefig(tmp, dpi=120, format=out.suffix.lstrip(".") or "png")
    plt.close(fig)
    return out


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="python -m pic4rl_agents.training.curves",
        description="Evaluation curves of several runs in one PNG: eval success against the "
                    "training wall-clock and against env steps.")
    parser.add_argument("runs", nargs="+", metavar="[LABEL=]PATH",
                        help="a run directory or an evaluations.csv")
    parser.add_argument("-o", "--out", default="eval_curves.png", help="the PNG to write")
    parser.add_argument("--clock", choices=("train_wall_s", "wall_s"), default="train_wall_s",
                        help="the time axis: training time (evaluations excluded) or all")
    parser.add_argument("--metric", choices=EVAL_METRICS, default="success_rate")
    parser.add_argument("--title", default="")
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Write the PNG; exit 2 with one line for a missing or malformed input."""
    args = build_parser().parse_args(argv)
    curves: dict[str, pd.DataFrame] = {}
    try:
        for item in args.runs:
            label, sep, path = item.rpartition("=")
            curves.update(eval_curves(path, label if sep else None))
        out = save_eval_curves(curves, Path(args.out), clock=args.clock, metric=args.metric,
                               title=args.title)
    except ConfigError as err:
        print(f"curves: {err}", file=sys.stderr)
        return 2
    print(out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
