"""``pic4rl-metrics video``: its options and its run (matplotlib and imageio load on demand).

One row per bag goes to stdout (bag, video, frames, duration, error), what was written and
every error to stderr; exit 1 when a bag failed (after every other bag was rendered), 2 on bad
usage.
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from ..contract import EpisodeFacts
    from ..bags.topics import TopicMap
    from ..viz.video_batch import VideoResult


def _positive(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        value = math.nan
    if not (math.isfinite(value) and value > 0):
        raise argparse.ArgumentTypeError(f"{text!r}: expected a number > 0")
    return value


def add_video_options(parser: argparse.ArgumentParser) -> None:
    """The ``video`` subcommand's own options (the bags and topics are ``compute``'s)."""
    video = parser.add_argument_group("video")
    video.add_argument("--out", "-o", type=Path, required=True,
                       help="directory for the videos (<bag>.mp4; pair_NN.mp4 with --grid)")
    video.add_argument("--gif", action="store_true", help="also a GIF per video (half size)")
    video.add_argument("--speed", type=_positive, default=1.0, metavar="X",
                       help="playback speed: seconds of episode per second of video "
                            "(default 1)")
    video.add_argument("--fps", type=_positive, default=10.0,
                       help="frames per second of video (default 10)")
    video.add_argument("--grid", action="store_true",
                       help="one video per start-goal pair, its episodes (agents) side by side")
    video.add_argument("--force", action="store_true", help="replace existing videos")


def _table(rows: tuple[VideoResult, ...]) -> str:
    import pandas as pd

    from ..tables.text import short_bag

    frame = pd.DataFrame(
        [{"bag": short_bag(r.bag), "video": r.video, "frames": r.frames or "",
          "duration_s": "" if math.isnan(r.duration_s) else f"{r.duration_s:.1f}",
          "error": r.error} for r in rows])
    return frame.to_string(index=False)


def run_video_command(args: argparse.Namespace, topic_map: TopicMap, facts: EpisodeFacts,
                      given: frozenset[str]) -> int:
    """Render the videos the parsed ``args`` ask for; the exit code."""
    from ..viz.video import VideoOptions
    from ..viz.video_batch import render_videos

    progress = sys.stderr.isatty() if args.progress is None else args.progress
    options = VideoOptions(fps=args.fps, speed=args.speed, gif=args.gif)
    rows = render_videos(args.bags, args.out, options=options, topic_map=topic_map,
                         facts=facts, given=given, jobs=args.jobs, progress=progress,
                         grid=args.grid, overwrite=args.force)
    if rows:
        sys.stdout.write(_table(rows) + "\n")
    for row in rows:
        if row.error:
            print(f"error: {row.error}", file=sys.stderr)
        elif row.kept:
            print(f"kept existing {row.video} (--force replaces it)", file=sys.stderr)
    for video in dict.fromkeys(r.video for r in rows if r.video and not r.kept):
        print(f"wrote {video}", file=sys.stderr)
    failed = sum(1 for r in rows if r.error)
    if failed:
        print(f"{failed} of {len(rows)} bag(s) failed", file=sys.stderr)
    return 1 if failed else 0
