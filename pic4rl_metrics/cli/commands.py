"""``pic4rl-metrics``: compute, compare, plot, watch (``video``) and report (one HTML page)
navigation metrics from bags.

Results go to stdout (or ``--out``); progress, warnings and errors go to stderr. The exit
code is 1 when any bag failed (after all bags were judged and reported), 2 on bad usage.
"""

from __future__ import annotations

import argparse
import os
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from pic4rl_base import atomic
from pic4rl_base.entry import entry_point
from pic4rl_base.errors import ConfigError

from ..bags.inputs import discover
from ..bags.topics import TopicMap, load_topic_map, parse_frames
from ..contract import EpisodeFacts, parse_facts
from ..core.registry import METRIC_TABLE, METRICS
from ..core.roles import ROLE_TABLE, Role
from ..tables.batch import MetricsResult, compute
from ..tables.groups import BY_CHOICES, parse_by, render_groups
from ..tables.layouts import FORMATS
from ..tables.paired import render_paired
from ..tables.protocol import LAYOUTS, protocol_table
from ..tables.results import METRIC_COLUMNS, table_columns
from ..tables.text import EPISODE_VIEW, render_episodes
from .plot import run_plot, writing
from .video import add_video_options, run_video_command


def _add_input_options(parser: argparse.ArgumentParser, *, metrics: bool = True) -> None:
    parser.add_argument(
        "bags", nargs="+",
        help="rosbag2 directories, metadata.yaml, .db3/.mcap files (or their .zstd), ROS 1 .bag "
             "files, directories to search, globs",
    )
    topics = parser.add_argument_group("topics (defaults: the bag contract's names)")
    topics.add_argument("--topic-map", type=Path, help="YAML topic map (and episode facts)")
    topics.add_argument("--pose-topic", action="append", metavar="TOPIC",
                        help="Odometry/PoseStamped/PoseWithCovarianceStamped topic; repeat for "
                             "fallbacks (with --pose-frames: the TFMessage topic, default /tf)")
    topics.add_argument("--pose-frames", type=_frames, metavar="PARENT:CHILD",
                        help="poses from /tf and /tf_static: CHILD's pose in PARENT, e.g. "
                             "odom:base_link or map:base_link")
    for role in _FLAGGED:
        topics.add_argument(role.flag, metavar="TOPIC", help=role.help)
    facts = parser.add_argument_group("episode facts (override what the bags record)")
    facts.add_argument("--agent", help="agent name, e.g. for a real-robot log")
    facts.add_argument("--goal", nargs=2, type=float, metavar=("X", "Y"), help="goal position (m)")
    facts.add_argument("--start", nargs=3, type=float, metavar=("X", "Y", "YAW"), help="start pose")
    facts.add_argument("--footprint", help="robot footprint: radius R, 'circle:R' or 'rect:LxW' (m)")
    facts.add_argument("--goal-tolerance", type=float, metavar="M", help="goal tolerance (m)")
    facts.add_argument("--collision-tolerance", type=float, metavar="M",
                       help="scan distance beyond the footprint that counts as a collision (m)")
    facts.add_argument("--safety-margin", type=float, metavar="M",
                       help="scan distance beyond the footprint that counts as unsafe (m)")
    facts.add_argument("--max-speed", type=float, metavar="MPS", help="robot's max speed")
    run = parser.add_argument_group("running")
    run.add_argument("--jobs", "-j", type=_jobs, default=1, metavar="N",
                     help="bags judged in parallel (0: one per core)")
    if metrics:
        run.add_argument("--metrics", type=_names, metavar="NAME[,NAME...]",
                         help="metric columns to compute (default: all; outcome and success "
                              "always)")
    run.add_argument("--progress", action=argparse.BooleanOptionalAction, default=None,
                     help="progress bar on stderr (default: when stderr is a terminal)")


#: The input roles with a ``--<role>-topic`` option.
_FLAGGED = tuple(role for role in ROLE_TABLE if role.flag)


def _dest(role: Role) -> str:
    """The ``argparse`` attribute of a role's option (``--cmd-topic``: ``cmd_topic``)."""
    return str(role.flag).lstrip("-").replace("-", "_")


def _jobs(text: str) -> int:
    """--jobs: a whole number >= 0 (0: one process per core)."""
    try:
        jobs = int(text)
    except ValueError:
        jobs = -1
    if jobs < 0:
        msg = f"{text!r}: expected a number of processes >= 1, or 0 for one per core"
        raise argparse.ArgumentTypeError(msg)
    return jobs


def _frames(text: str) -> tuple[str, str]:
    """--pose-frames: PARENT:CHILD."""
    try:
        return parse_frames(text, "")
    except ConfigError as err:
        raise argparse.ArgumentTypeError(str(err).strip()) from err


def _by(text: str) -> tuple[str, ...]:
    """compare --by: row-key columns, comma-separated."""
    try:
        return parse_by(text)
    except ConfigError as err:
        raise argparse.ArgumentTypeError(str(err)) from err


def _names(text: str) -> tuple[str, ...]:
    return tuple(n.strip() for n in text.split(",") if n.strip())


def _add_output_options(parser: argparse.ArgumentParser, default_format: str) -> None:
    parser.add_argument("--format", "-f", choices=FORMATS, default=default_format)
    parser.add_argument("--out", "-o", type=Path, help="write here instead of stdout")
    parser.add_argument("--force", action="store_true", help="replace an existing --out file")


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="pic4rl-metrics",
        description="Navigation metrics (the PIC4rl-gym paper's and more) from rosbag2 bags alone.",
    )
    sub = parser.add_subparsers(dest="command", required=True)
    p = sub.add_parser("compute", help="one row of metrics per bag")
    _add_input_options(p)
    _add_output_options(p, "table")
    p = sub.add_parser("compare", help="agents or runs side by side (the paper's Table 1)")
    _add_input_options(p)
    _add_output_options(p, "table")
    p.add_argument("--by", type=_by, default=("agent",), metavar="COL[,COL...]",
                   help=f"what makes a row ({', '.join(BY_CHOICES)}; default agent); rows "
                        "are grouped by task and world set, a header per group, except for "
                        "what --by names")
    p.add_argument("--with-std", action="store_true", help="cells as mean ± std")
    p.add_argument("--over", choices=("success", "all"), default="success",
                   help="episodes the trajectory-quality columns average: the successful "
                        "ones (default, as the paper's table) or all")
    p.add_argument("--count-aborted", action="store_true",
                   help="count aborted episodes (cut short, no outcome recorded) as failures "
                        "in the success rate; by default they are counted apart (n_aborted)")
    p.add_argument("--paired", action="append", metavar="REF",
                   help="instead of the table: every agent against REF on shared start-goal "
                        "pairs (success difference, bootstrap interval, McNemar's p); repeat "
                        "for several references")
    p.add_argument("--table", choices=tuple(LAYOUTS), metavar="LAYOUT",
                   help="instead of the table: a benchmark protocol's table, as pic4rl-bench's "
                        "'table:' prints it (barn: success, collision and timeout with Wilson "
                        "95%% intervals, BARN time and score with bootstrap intervals, of the "
                        "episodes in BARN worlds; paper: success with its interval, the "
                        "paper's columns and SPL)")
    p = sub.add_parser("report", help="one self-contained HTML page: leaderboard, paired "
                                      "comparisons, failures, maps, every episode")
    _add_input_options(p)
    p.add_argument("--out", "-o", type=Path, required=True, help="the HTML file to write")
    p.add_argument("--force", action="store_true", help="replace an existing --out file")
    p.add_argument("--reference", action="append", metavar="AGENT",
                   help="compare every agent with this one (repeat for several; default: "
                        "every pair of agents)")
    p.add_argument("--title", default="pic4rl benchmark report", help="the page's title")
    p = sub.add_parser("plot", help="a figure per episode and a comparison figure")
    _add_input_options(p)
    p.add_argument("--out", "-o", type=Path, required=True, help="directory for the PNG files")
    p.add_argument("--by", default="agent", help="what colours the comparison figure")
    p = sub.add_parser("video", help="an MP4 (and a GIF) per episode, from the bag alone")
    _add_input_options(p, metrics=False)
    add_video_options(p)
    return parser


def _inputs(args: argparse.Namespace) -> tuple[TopicMap, EpisodeFacts, frozenset[str]]:
    """Topic map and facts from --topic-map, then the command-line options over them."""
    topic_map, facts, given = TopicMap(), EpisodeFacts(), frozenset()
    if args.topic_map is not None:
        topic_map, facts, given = load_topic_map(args.topic_map)
    topic_map = topic_map.with_overrides(
        pose=tuple(args.pose_topic) if args.pose_topic else None, pose_frames=args.pose_frames,
        **{role.name: getattr(args, _dest(role)) for role in _FLAGGED},
    )
    cli = {
        "agent": args.agent, "goal": args.goal, "start": args.start, "footprint": args.footprint,
        "goal_tolerance_m": args.goal_tolerance, "collision_tolerance_m": args.collision_tolerance,
        "safety_margin_m": args.safety_margin, "max_speed_mps": args.max_speed,
    }
    cli_facts, cli_given = parse_facts(
        {k: v for k, v in cli.items() if v is not None}, source="command line"
    )
    facts = facts.merged(cli_facts, given=cli_given)
    return topic_map, facts, given | cli_given


def _run(args: argparse.Namespace) -> MetricsResult:
    topic_map, facts, given = _inputs(args)
    progress = sys.stderr.isatty() if args.progress is None else args.progress
    sample = 0
    if args.command == "report":  # its maps draw a few scans: only those are kept
        from ..viz.report_maps import SKETCH_SCANS as sample
    return compute(args.bags, topic_map=topic_map, facts=facts, given=given,
                   jobs=args.jobs, progress=progress, metrics=args.metrics,
                   full_scans=args.command == "plot", scan_sample=sample)


def _shown(result: MetricsResult, default: Sequence[str], *, numeric: bool) -> list[str]:
    """Metric columns a table shows: the ones asked for (``--metrics``, topic map), else the
    default view plus the columns of plugins; ``numeric`` leaves text columns out."""
    computed = [c for c in result.columns if c in METRICS]
    if set(METRIC_COLUMNS) <= set(computed):
        computed = [*default, *(c for c in computed if c not in METRIC_COLUMNS)]
    return [c for c in computed if c == "success" or not (numeric and METRICS[c].text)]


def _emit(text: str, out: Path | None, force: bool) -> None:
    if out is None:
        sys.stdout.write(text if text.endswith("\n") else text + "\n")
        return
    if out.exists() and not force:
        msg = f"--out {str(out)!r} exists; pass --force to replace it"
        raise ConfigError(msg)
    data = (text if text.endswith("\n") else text + "\n").encode()
    with writing(out), atomic.replacing(out) as tmp, tmp.open("wb") as handle:
        _write_all(handle, data)  # whole or not at all: a failed write leaves no file
    print(f"wrote {out}", file=sys.stderr)


def _write_all(handle: Any, data: bytes) -> None:
    handle.write(data)
    handle.flush()
    os.fsync(handle.fileno())


def _check_report_inputs(args: argparse.Namespace) -> None:
    """``report``: refuse an existing ``--out`` (without ``--force``) and inputs that hold no
    bag at all before any bag is read."""
    if args.out.exists() and not args.force:
        raise ConfigError(f"--out {str(args.out)!r} exists; pass --force to replace it")
    if not discover(args.bags).bags:
        raise ConfigError(f"report: no bag in {' '.join(map(str, args.bags))}; expected "
                          "rosbag2 directories, .db3/.mcap or .bag files, or folders of them")


def _report_failures(result: MetricsResult) -> int:
    for failed in result.failed:
        print(f"error: {failed.error}", file=sys.stderr)
    for problem in (*METRIC_TABLE.plugin_errors, *result.skipped):
        print(f"warning: {problem}", file=sys.stderr)
    for ok in result.results:
        for warning in ok.warnings:
            print(f"warning: {ok.bag}: {warning}", file=sys.stderr)
    n_bad, n_all = len(result.failed), len(result.results)
    if n_bad:
        print(f"{n_bad} of {n_all} bag(s) failed", file=sys.stderr)
    if not n_all and result.skipped:  # only FIFOs and the like named: nothing judged
        print("error: no bag judged: every input was skipped (neither a regular file nor a "
              "directory)", file=sys.stderr)
        return 1
    return 1 if n_bad else 0


def _check_table_options(args: argparse.Namespace) -> None:
    """``compare --table``: refuse the options of the other tables before any bag is read."""
    if args.command != "compare" or not args.table:
        return
    clash = [o for o, on in (("--paired", args.paired), ("--with-std", args.with_std),
                             ("--over all", args.over == "all")) if on]
    if clash:
        raise ConfigError(f"compare --table {args.table}: {clash[0]} is not an option of a "
                          "protocol's table (its columns are fixed, as pic4rl-bench's)")
    if args.metrics is not None:  # the layout's columns are always computed
        args.metrics = tuple(dict.fromkeys((*args.metrics, *LAYOUTS[args.table].means)))


@entry_point("pic4rl-metrics")
def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of ``pic4rl-metrics``; returns the exit code."""
    args = build_parser().parse_args(argv)
    if args.command == "video":
        return run_video_command(args, *_inputs(args))
    if args.command == "report":
        _check_report_inputs(args)
    _check_table_options(args)
    result = _run(args)
    if args.command == "compute":
        shown = _shown(result, list(EPISODE_VIEW), numeric=False)
        _emit(render_episodes(result.frame, args.format, columns=shown), args.out, args.force)
    elif args.command == "compare" and args.paired:
        _emit(render_paired(result, args.paired, args.format), args.out, args.force)
    elif args.command == "compare" and args.table:
        text, note = protocol_table(result, args.table, args.format, by=args.by,
                                    count_aborted=args.count_aborted)
        if note:
            print(f"note: {note}", file=sys.stderr)
        _emit(text, args.out, args.force)
    elif args.command == "report":
        from ..viz.html_report import write_report  # matplotlib and Pillow on demand

        write_report(result, args.out, overwrite=args.force, references=args.reference,
                     inputs=[str(b) for b in args.bags], title=args.title)
        print(f"wrote {args.out}", file=sys.stderr)
    elif args.command == "compare":
        text = render_groups(
            result.frame, args.format, by=args.by, over=args.over,
            count_aborted=args.count_aborted, with_std=args.with_std,
            columns=lambda rows: _shown(result, table_columns(rows), numeric=True))
        _emit(text, args.out, args.force)
    else:
        run_plot(args, result)
    return _report_failures(result)


if __name__ == "__main__":
    sys.exit(main())
