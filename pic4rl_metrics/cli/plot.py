"""``pic4rl-metrics plot``: its figures written, and the commands' one way of naming a path
they cannot write (``writing``).

Apart from ``commands`` so that the command set stays readable there: a figure per episode, a
comparison per world (trajectories and speeds), and, where some episode of a world explores,
its coverage curves (``viz.coverage_plot.coverage_figure``: the report's curves as a PNG).
"""

from __future__ import annotations

import argparse
import contextlib
import re
import sys
from collections.abc import Iterator
from pathlib import Path

from pic4rl_base.errors import OutputError

from ..tables.batch import MetricsResult


@contextlib.contextmanager
def writing(path: Path) -> Iterator[None]:
    """An OS error while writing ``path`` (a full disk, a parent that is a file, no
    permission) as one ``OutputError`` line naming the path."""
    try:
        yield
    except OSError as err:
        raise OutputError(f"--out {str(path)!r}: cannot write it: "
                          f"{err.strerror or err}") from err


def run_plot(args: argparse.Namespace, result: MetricsResult) -> None:
    """Write ``plot``'s PNG files into ``args.out``, keeping any that exist."""
    from ..viz.coverage_plot import coverage_figure  # matplotlib on demand
    from ..viz.plots import by_world, episode_figure, figure_names, save_figure, trajectories_figure

    out: Path = args.out
    drawn = [r for r in result.results if r.episode is not None]
    figures = [(out / f"{name}.png", lambda r=r: episode_figure(r.episode, r.metrics))
               for name, r in zip(figure_names([r.bag for r in drawn]), drawn)]
    worlds = by_world(result.episodes)
    for world, episodes in worlds.items():  # one comparison per world, never overlaid
        suffix = "" if len(worlds) == 1 else "_" + (re.sub(r"[^\w.-]", "-", world) or "no-world")
        if len(episodes) > 1:
            figures.append((out / f"comparison{suffix}.png", lambda e=episodes: trajectories_figure(
                e, group_by=args.by)))
        coverage = coverage_figure(episodes, group_by=args.by)
        if coverage is not None:
            figures.append((out / f"coverage{suffix}.png", lambda f=coverage: f))
    for target, draw in figures:
        if target.exists():
            print(f"kept existing {target}", file=sys.stderr)
            continue
        with writing(target):
            save_figure(draw(), target)
        print(f"wrote {target}", file=sys.stderr)
