"""A benchmark protocol's table: the layouts that ``pic4rl-bench``'s ``table:`` and
``pic4rl-metrics compare --table`` name, and their cells, computed from judged episodes alone.

One implementation for both: ``protocol_cells`` aggregates a result frame by its row key
(``aggregate``) and gives each row ``n``, its rates as k/n with their Wilson 95 % intervals
(``wilson_interval``) and the layout's metric means, with their bootstrap 95 % intervals
(``bootstrap_interval``) where the layout says so. ``barn``: success, collision and timeout
rates, the mean BARN time (over the successes) and the mean BARN score (over every judged
episode); ``paper``: success and the paper's columns with SPL; ``explore``: the BARN rates,
then the mean coverage, area seen, times to 50 % and 90 % and path per area seen, ranked by
coverage; ``crowd``: the BARN rates, SPL and the social columns (``crowd.SOCIAL_COLUMNS``:
each zone's entries and time, closest approach, time to collision, people contacts, speed
near people), ranked by SPL. A task without a goal
(``groups.headline``) heads with its full runs: a ``full runs`` column after success. An agent
is a row key like any other: a plugin's, a ROS stack's or a shipped agent's name is one more
row. ``render_protocol`` lays the rows out per task and world set (``groups.split``), as
``compare`` does; ``layout_episodes`` keeps the episodes a layout may judge (BARN's: those in
a BARN world, the ``barn_world`` input of the BARN metrics).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import pandas as pd

from pic4rl_base.errors import ConfigError

from ..core.derived import INPUT_TESTS, Derived
from ..core.registry import METRICS
from ..core.tasks.crowd import SOCIAL_COLUMNS
from .aggregate import (FULL_RUN, FULL_RUNS, _error_mask, _group_keys, aggregate,
                        bootstrap_interval, wilson_interval)
from .groups import headline, join, split, with_world_set
from .layouts import render_rows
from .results import TABLE1_COLUMNS
from .text import plain_text

if TYPE_CHECKING:
    from .batch import MetricsResult


@dataclass(frozen=True)
class Layout:
    """A table's columns after the row keys and n: ``rates`` (outcomes as k/n over the judged
    episodes, each with its Wilson 95 % interval; success first), ``means`` (metrics' means,
    each with a bootstrap 95 % interval when ``intervals``), the leaderboards' ``rank`` metric
    after success, and ``worlds``: the input (``derived.INPUT_TESTS``) an episode needs to be
    judged in this table (None: any episode)."""

    rates: tuple[str, ...]
    means: tuple[str, ...]
    intervals: bool
    rank: str
    worlds: str | None = None


#: The paper layout's means: Table 1's columns after success, then SPL.
PAPER_MEANS = (*[c for c in TABLE1_COLUMNS if c != "success"], "spl")
#: The explore layout's means: the coverage columns (``core.tasks.coverage``).
EXPLORE_MEANS = ("coverage_pct", "area_seen_m2", "time_to_50pct_s", "time_to_90pct_s",
                 "path_per_area_seen_mpm2")
#: The layouts a suite's ``table`` and ``compare --table`` name.
LAYOUTS = {"paper": Layout(("success",), PAPER_MEANS, False, "spl"),
           "barn": Layout(("success", "collision", "timeout"), ("barn_time_s", "barn_score"),
                          True, "barn_score", worlds="barn_world"),
           "explore": Layout(("success", "collision", "timeout"), EXPLORE_MEANS, True,
                             "coverage_pct"),
           "crowd": Layout(("success", "collision", "timeout"), ("spl", *SOCIAL_COLUMNS),
                           False, "spl")}
#: The header of the full runs' column (``aggregate``'s ``full_runs``: a task without a goal).
FULL_RUNS_LABEL = "full runs"
#: Where the BARN layout's worlds are told apart, in words (for its notes and errors).
WORLDS_IN_WORDS = {"barn_world": "in a BARN world (a world fact 'barn:<n>' or a "
                                 "reference_path_m fact)"}


def _num(value: object) -> str | None:
    return None if value is None or pd.isna(value) else f"{float(value):.2f}"


def _interval(low: float, high: float) -> str | None:
    return None if math.isnan(low) else f"[{low:.2f}, {high:.2f}]"


def _rates(layout: Layout, full_runs: bool) -> tuple[str, ...]:
    """The layout's rates, with ``FULL_RUNS`` after success when some task heads with it."""
    extra = (FULL_RUNS,) if full_runs else ()
    return (*layout.rates[:1], *extra, *layout.rates[1:])


def header(layout: Layout, full_runs: bool = False) -> tuple[str, ...]:
    """The columns after the row keys: n, each rate and its interval, each mean (and its
    interval); ``full_runs``: some task heads with its full runs."""
    names = [FULL_RUNS_LABEL if r == FULL_RUNS else r for r in _rates(layout, full_runs)]
    rates = [c for r in names for c in (r, f"{r} 95% CI")]
    means = []
    for m in layout.means:
        label = plain_text(METRICS[m].label)
        means += [f"{label} [{plain_text(METRICS[m].unit)}]"] + (
            [f"{label} 95% CI"] if layout.intervals else [])
    return ("n", *rates, *means)


def row_cells(stats: pd.Series, episodes: pd.DataFrame, layout: Layout, *,
              heads: str = "success", full_runs: bool = False) -> list[str | None]:
    """One row's cells after its keys (``header``'s): ``stats``, its ``aggregate`` row;
    ``episodes``, its judged episodes (for the bootstrap intervals); ``heads``, its task's
    headline (``success`` or ``FULL_RUNS``: its full runs' cells are filled and the quality
    columns' intervals are over its full runs, as ``aggregate``'s means)."""
    cells: list[str | None] = [str(int(stats["n_episodes"]))]
    n = int(stats["n_judged"])
    for rate in _rates(layout, full_runs):
        if rate == FULL_RUNS:
            k, ran = (int(stats["n_full_runs"]), int(stats["n_ran"])) if heads == FULL_RUNS \
                else (0, 0)
            cells += [f"{k}/{ran}" if ran else None, _interval(*wilson_interval(k, ran))]
            continue
        k = int(stats["n_success" if rate == "success" else f"n_{rate}"])
        cells += [f"{k}/{n}" if n else None, _interval(*wilson_interval(k, n))]
    for m in layout.means:
        cells.append(_num(stats.get(f"{m}_mean")))
        if layout.intervals:
            best = (episodes["outcome"] == FULL_RUN) if heads == FULL_RUNS else (
                episodes["success"] == 1.0)
            over = episodes[best] if METRICS[m].quality else episodes
            values = over.get(m, [])
            cells.append(_interval(*bootstrap_interval(pd.to_numeric(values, errors="coerce"))))
    return cells


def empty_cells(columns: Sequence[str]) -> list[str | None]:
    """The cells of a row without a judged episode (``columns``: ``header``'s): n 0."""
    return ["0", *[None] * (len(columns) - 1)]


def protocol_cells(frame: pd.DataFrame, by: Sequence[str], layout: Layout, *,
                   count_aborted: bool = False) -> tuple[tuple[str, ...],
                                                         dict[tuple[object, ...],
                                                              list[str | None]]]:
    """``frame``'s episodes (a result frame; error rows counted apart, as ``aggregate``
    does) as rows keyed by the columns ``by``: the columns after the keys (``header``) and
    each key's cells (``row_cells``), in order of first appearance. Each task's headline is
    ``groups.headline`` over its rows (the task is the ``task`` key where ``by`` names it;
    else the frame is one task)."""
    if not len(frame):
        return header(layout), {}
    by = list(by)
    agg = aggregate(frame, by=by, count_aborted=count_aborted)
    good = frame[~_error_mask(frame)]
    keys = _group_keys(good, by)
    members: dict[tuple[object, ...], list[int]] = {}
    for pos, key in enumerate(keys.itertuples(index=False, name=None)):
        members.setdefault(key, []).append(pos)
    rows = [(k if isinstance(k, tuple) else (k,), stats) for k, stats in agg.iterrows()]
    task = by.index("task") if "task" in by else None
    tasks = [None] if task is None else list(dict.fromkeys(k[task] for k, _ in rows))
    heads = {t: headline(agg if task is None else
                         agg[agg.index.get_level_values("task") == t]) for t in tasks}
    full_runs = FULL_RUNS in heads.values()
    empty = pd.DataFrame(columns=["success", "outcome"])
    cells = {key: row_cells(stats, good.iloc[members[key]] if key in members else empty,
                            layout, heads=heads[None if task is None else key[task]],
                            full_runs=full_runs)
             for key, stats in rows}
    return header(layout, full_runs), cells


def layout_episodes(result: MetricsResult, layout: Layout) -> tuple[pd.DataFrame,
                                                                    tuple[str, ...]]:
    """The rows of ``result.frame`` whose episode the layout may judge (an unreadable bag's
    error row is not one: ``compare`` reports it as an error), and the bags of the episodes
    left out for not having the layout's ``worlds`` input."""
    test = INPUT_TESTS[layout.worlds] if layout.worlds else None
    keep, out = [], []
    for r in result.results:
        fits = r.episode is not None and (test is None or test(Derived(r.episode)))
        keep.append(fits)
        if r.episode is not None and not fits:
            out.append(r.bag)
    return result.frame[keep], tuple(out)


def render_protocol(frame: pd.DataFrame, fmt: str, layout: Layout, *,
                    by: Sequence[str] = ("agent",), count_aborted: bool = False) -> str:
    """``compare --table``: ``frame``'s rows keyed by ``by`` in the layout's columns, in each
    of its task and world-set groups (``groups.split``; a header per group when there are
    several, as ``compare``'s own table), in one of ``layouts.FORMATS``."""
    frame = with_world_set(frame) if "world_set" in by else frame
    groups = split(frame, by)
    if not groups:  # no episode: the header alone
        return render_rows((*by, *header(layout)), [], fmt)
    parts = []
    for group in groups:
        columns, cells = protocol_cells(frame.loc[list(group.rows)], by, layout,
                                        count_aborted=count_aborted)
        body = [[str(v) for v in key] + c for key, c in cells.items()]
        parts.append((group, render_rows((*by, *columns), body, fmt)))
    return join(parts, fmt)


def protocol_table(result: MetricsResult, name: str, fmt: str, *,
                   by: Sequence[str] = ("agent",), count_aborted: bool = False) -> tuple[str,
                                                                                     str]:
    """``compare --table NAME``'s text and its note ("" when none). Episodes the layout cannot
    judge (BARN's: outside a BARN world) are left out, the note naming how many and the first
    few bags; ``ConfigError`` when no episode is left. Unreadable bags are not in the table
    (``compare`` reports each as an error)."""
    layout = LAYOUTS[name]
    frame, left_out = layout_episodes(result, layout)
    if not left_out:
        return render_protocol(frame, fmt, layout, by=by, count_aborted=count_aborted), ""
    where = WORLDS_IN_WORDS[str(layout.worlds)]
    shown = ", ".join(left_out[:3]) + (", ..." if len(left_out) > 3 else "")
    if not len(frame):
        raise ConfigError(f"compare --table {name}: none of the {len(left_out)} episode(s) "
                          f"is {where}: {shown}")
    note = (f"compare --table {name}: left out {len(left_out)} of "
            f"{len(left_out) + len(frame)} episode(s), not {where}: {shown}")
    return render_protocol(frame, fmt, layout, by=by, count_aborted=count_aborted), note
