"""The area an exploration has seen, drawn: the HTML report's coverage curves (and
``pic4rl-metrics plot``'s, the same as a PNG: ``coverage_figure``) and the episode videos' tint
of the floor seen so far.

An exploration is judged by how fast it sees, which the time-to columns only sample; the curve
shows it whole. Each episode's curve is ``Derived.seen`` (the one the coverage columns come
from), sampled on a grid shared by the group's episodes and held at its last value after the
episode ends (what was seen stays seen). Per agent, a line is the mean over its episodes and a
band the mean ± one standard deviation; one inline SVG per task and world set. The y axis is
coverage % when every episode of the group records its world's free area (``free_area_m2``),
else the area seen in m². An SVG of a few lines, not a PNG: crisp at any zoom and its numbers
readable in the page's text.

A video tints, frame after frame, the cells the scans up to its time have seen, integrated as
the metric integrates them (``tasks.seen.SeenStream``: the same grid, placement at the
interpolated pose and thinning of scans from the same place). The world point of every map
pixel is computed once; a frame tints only the pixels newly seen, on the video's persistent
map image, before that frame's scan points are drawn over it.
"""

from __future__ import annotations

import html
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import pandas as pd
from matplotlib.figure import Figure
from matplotlib.ticker import MaxNLocator

from ..core.derived import Derived
from ..core.series import Episode
from ..core.series_kinds import ScanSeries
from ..core.tasks.seen import SeenStream, wants_seen
from ..tables.batch import MetricsResult
from ..tables.groups import split
from . import html_page as hp
from .raster import View
from .report_maps import PALETTE

#: Points of the shared time grid.
GRID_POINTS = 121
#: The plot's size and its margins (px): left, top, right, bottom.
WIDTH, HEIGHT = 560, 300
MARGIN = (56, 14, 16, 40)

#: The videos' tint of the floor seen and how strongly it covers the picture beneath (0..1).
SHADE = np.array((110, 180, 250), dtype=float)
ALPHA = 0.35


def _rows(scan: ScanSeries, start: int, stop: int) -> ScanSeries:
    return ScanSeries(scan.t_ns[start:stop], scan.ranges[start:stop], scan.angles[start:stop],
                      scan.range_min[start:stop], scan.range_max[start:stop])


class SeenShade:
    """Tints, frame after frame, the cells an episode's scans have seen (``draw``)."""

    def __init__(self, episode: Episode, scan: ScanSeries, view: View, shape: tuple[int, int],
                 t0_ns: int) -> None:
        self.scan = scan
        self.stream = SeenStream(episode.pose, episode.facts.scan_mount,
                                 lambda start, n: scan.t_ns[start:start + n])
        self.t_s = (np.asarray(scan.t_ns, np.int64) - t0_ns) / 1e9
        self.next = 0
        rows, cols = shape
        cc, rr = np.meshgrid(np.arange(cols) + 0.5, np.arange(rows) + 0.5)
        self.xy = np.stack([((cc - view.col0) / view.sx).ravel(),
                            ((view.row0 - rr) / view.sy).ravel()], axis=1)
        self.shape = shape
        self.done = np.zeros(shape, dtype=bool)

    def draw(self, img: np.ndarray, t_s: float) -> None:
        """Integrate the scans up to ``t_s`` (s after the first pose) and tint in ``img`` the
        pixels whose cell they newly saw."""
        upto = int(np.searchsorted(self.t_s, t_s, side="right"))
        if upto <= self.next:
            return
        self.stream.add(_rows(self.scan, self.next, upto), self.next)
        self.next = upto
        new = self.stream.grid.seen_at(self.xy).reshape(self.shape) & ~self.done
        img[new] = np.round((1 - ALPHA) * img[new] + ALPHA * SHADE).astype(img.dtype)
        self.done |= new


def seen_shade(episode: Episode, view: View, shape: tuple[int, int],
               t0_ns: int) -> SeenShade | None:
    """The tint for ``episode``'s map (``view`` on an image of ``shape``: rows, columns); None
    unless it is an exploration whose whole scans were read."""
    scan = episode.scan
    if not wants_seen(episode.facts) or not isinstance(scan, ScanSeries) or not len(scan):
        return None
    return SeenShade(episode, scan, view, shape, t0_ns)


@dataclass(frozen=True)
class Curve:
    """One episode's area seen: ``t_s`` after its first pose, ``area_m2`` cumulative."""

    t_s: np.ndarray
    area_m2: np.ndarray
    free_area_m2: float | None


@dataclass(frozen=True)
class Band:
    """One agent's curves on the shared grid: ``mean`` and ``std`` over its ``n`` episodes."""

    agent: str
    mean: np.ndarray
    std: np.ndarray
    n: int


def episode_curve(episode: Episode) -> Curve | None:
    """``episode``'s area seen over time; None unless it is an exploration with scans."""
    seen = Derived(episode).seen
    if seen is None or not len(seen.t_ns):
        return None
    t_s = (np.asarray(seen.t_ns, np.int64) - int(episode.pose.t_ns[0])) * 1e-9
    return Curve(t_s, np.asarray(seen.area_m2, float), episode.facts.free_area_m2)


def bands(curves: Sequence[tuple[str, Curve]]) -> tuple[np.ndarray, list[Band], str]:
    """The shared grid (s), per agent (in order of first appearance) its band, and the unit:
    "%" when every curve knows its free area, else "m²"."""
    percent = all(c.free_area_m2 for _, c in curves)
    t_end = max(float(c.t_s[-1]) for _, c in curves)
    grid = np.linspace(0.0, max(t_end, 1e-3), GRID_POINTS)
    sampled: dict[str, list[np.ndarray]] = {}
    for agent, c in curves:
        value = 100.0 * c.area_m2 / c.free_area_m2 if percent and c.free_area_m2 else c.area_m2
        sampled.setdefault(agent, []).append(np.interp(grid, c.t_s, value, left=0.0))
    out = [Band(agent, np.mean(rows, axis=0), np.std(rows, axis=0), len(rows))
           for agent, rows in sampled.items()]
    return grid, out, "%" if percent else "m²"


def _points(xs: np.ndarray, ys: np.ndarray, sx: float, sy: float) -> str:
    left, top = MARGIN[0], HEIGHT - MARGIN[3]
    return " ".join(f"{left + sx * x:.1f},{top - sy * y:.1f}" for x, y in zip(xs, ys))


def coverage_svg(grid: np.ndarray, agent_bands: Sequence[Band], unit: str) -> str:
    """The curves as an inline SVG: an axis box with ticks, per agent a band and a mean line
    (``data-agent`` names the agent, ``data-final`` its mean at the end)."""
    y_top = max(float(np.max(b.mean + b.std)) for b in agent_bands)
    y_top = 100.0 if unit == "%" else max(y_top, 1e-3)
    t_end = float(grid[-1])
    plot_w, plot_h = WIDTH - MARGIN[0] - MARGIN[2], HEIGHT - MARGIN[1] - MARGIN[3]
    sx, sy = plot_w / t_end, plot_h / y_top
    left, top, bottom = MARGIN[0], MARGIN[1], HEIGHT - MARGIN[3]
    parts = [(f'<rect x="{left}" y="{top}" width="{plot_w}" height="{plot_h}" fill="none" '
              'stroke="#888"/>')]
    for t in MaxNLocator(6).tick_values(0.0, t_end):
        if 0.0 <= t <= t_end:
            x = left + sx * t
            parts.append(f'<line x1="{x:.1f}" y1="{bottom}" x2="{x:.1f}" y2="{bottom + 4}" '
                         f'stroke="#888"/><text x="{x:.1f}" y="{bottom + 16}" '
                         f'text-anchor="middle">{t:g}</text>')
    for v in MaxNLocator(5).tick_values(0.0, y_top):
        if 0.0 <= v <= y_top:
            y = bottom - sy * v
            parts.append(f'<line x1="{left - 4}" y1="{y:.1f}" x2="{left}" y2="{y:.1f}" '
                         f'stroke="#888"/><text x="{left - 6}" y="{y + 4:.1f}" '
                         f'text-anchor="end">{v:g}</text>')
    for k, b in enumerate(agent_bands):
        r, g, bl = PALETTE[k % len(PALETTE)]
        name = html.escape(b.agent)
        low = np.clip(b.mean - b.std, 0.0, y_top)
        high = np.clip(b.mean + b.std, 0.0, y_top)
        outline = _points(np.r_[grid, grid[::-1]], np.r_[high, low[::-1]], sx, sy)
        parts.append(f'<polygon class="spread" data-agent="{name}" points="{outline}" '
                     f'fill="rgb({r},{g},{bl})" fill-opacity="0.2" stroke="none"/>')
        parts.append(f'<polyline class="mean" data-agent="{name}" '
                     f'data-final="{float(b.mean[-1]):.2f}" points="'
                     f'{_points(grid, np.minimum(b.mean, y_top), sx, sy)}" fill="none" '
                     f'stroke="rgb({r},{g},{bl})" stroke-width="2"/>')
    label = "coverage [%]" if unit == "%" else "area seen [m²]"
    parts.append(f'<text x="{left + plot_w / 2}" y="{HEIGHT - 6}" text-anchor="middle">'
                 "time [s]</text>")
    parts.append(f'<text transform="translate(14 {top + plot_h / 2}) rotate(-90)" '
                 f'text-anchor="middle">{label}</text>')
    return (f'<svg class="coverage" viewBox="0 0 {WIDTH} {HEIGHT}" width="{WIDTH}" '
            f'height="{HEIGHT}" font-size="11" role="img" aria-label="{label} against time">'
            + "".join(parts) + "</svg>")


def coverage_figure(episodes: Sequence[Episode], *, group_by: str = "agent") -> Figure | None:
    """The curves of ``episodes`` as a figure: per value of the fact ``group_by`` (its bag's
    name where an episode lacks it) the mean line and the ± one standard deviation band, as
    the report draws them; None when none of them explores."""
    curves = []
    for ep in episodes:
        curve = episode_curve(ep)
        if curve is not None:
            value = getattr(ep.facts, group_by, None)
            curves.append((ep.bag.name if value is None else str(value), curve))
    if not curves:
        return None
    grid, agent_bands, unit = bands(curves)
    fig = Figure(figsize=(8, 4.5), layout="constrained")
    ax = fig.subplots()
    for k, b in enumerate(agent_bands):
        color = tuple(c / 255 for c in PALETTE[k % len(PALETTE)])
        ax.fill_between(grid, b.mean - b.std, b.mean + b.std, color=color, alpha=0.2, lw=0)
        ax.plot(grid, b.mean, color=color, lw=2, label=f"{b.agent} (n = {b.n})")
    ax.set_xlabel("time [s]")
    ax.set_ylabel("coverage [%]" if unit == "%" else "area seen [m²]")
    ax.set_ylim(bottom=0.0)
    ax.grid(True, alpha=0.3)
    ax.legend(title=group_by, fontsize="small")
    return fig


def coverage_section(result: MetricsResult, names: pd.Series) -> str:
    """The report's coverage curves (``names``: each frame row's agent), one plot per task and
    world set with a key; "" when no episode is an exploration."""
    frame = result.frame
    curves: dict[object, Curve] = {}
    for i, r in zip(frame.index, result.results):
        curve = None if r.episode is None else episode_curve(r.episode)
        if curve is not None:
            curves[i] = curve
    if not curves:
        return ""
    groups = split(frame.loc[list(curves)])
    parts = [("<p class=note>Per agent, the mean over its episodes (line) and the mean ± one "
              "standard deviation (band); an episode holds its last value after it ends.</p>")]
    for g in groups:
        grid, agent_bands, unit = bands([(str(names[i]), curves[i]) for i in g.rows])
        key = "".join(hp.swatch(PALETTE[k % len(PALETTE)], f"{b.agent} (n = {b.n})")
                      for k, b in enumerate(agent_bands))
        head = f"<h3>{html.escape(g.label)}</h3>" if len(groups) > 1 else ""
        parts.append(f'{head}<div class="key">{key}</div>'
                     + coverage_svg(grid, agent_bands, unit))
    return "\n".join(parts)
