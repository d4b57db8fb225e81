"""``pic4rl-metrics report``: one self-contained HTML page of a benchmark, from its bags alone.

In order: the leaderboard (``aggregate``'s counts and means, the Wilson interval), the logs
without a goal (``report_logs``: real-robot bags, not ranked), an exploration's coverage curves
(``coverage_plot``), the paired comparisons on shared
start–goal pairs (``paired``) — leaderboard and comparisons per task and world set
(``groups``) —, how each agent fails (outcome counts, the ends of its failed episodes on the
scan-built map), each pair's trajectories on one small map (``report_maps``), every episode
(sortable, filterable, linked to its bag and video), the bags that could not be read, and the
inputs (folders, config hashes, version, date). The page's
markup, style and script are ``html_page``'s. ``pic4rl-bench`` writes one beside its tables.
"""

from __future__ import annotations

import html
import math
import os
from collections.abc import Callable, Sequence
from pathlib import Path
from urllib.parse import quote

import pandas as pd

from pic4rl_base import atomic
from pic4rl_base.errors import ConfigError, OutputError

from ..contract import Outcome
from ..core.registry import METRICS
from ..tables.aggregate import FULL_RUNS, _group_keys, aggregate, wilson_interval
from ..tables.batch import MetricsResult
from ..tables.groups import Group, headline, split
from ..tables.paired import (N_BOOT, NOT_DISTINGUISHABLE, PAIRED_COLUMNS, grouped_paired,
                             pair_labels, paired_cells, seed_spread)
from ..tables.results import ROW_COLUMNS
from ..tables.text import plain_text, short_bag
from . import html_page as hp
from .coverage_plot import coverage_section
from .report_export import leaderboard_downloads
from .report_inputs import inputs_section, provenance
from .report_logs import goal_less, logs_section
from .report_maps import PALETTE, Sketch, failure_map, pair_map, png_uri, sketch

#: The social columns (an episode with people), shown as the task's own.
SOCIAL_COLUMNS = ("personal_intrusion_time_s", "people_dist_min_m", "people_ttc_min_s",
                  "people_collision_count")
#: A task's own columns, shown in the leaderboard when some episode has them.
TASK_COLUMNS = ("barn_score", *ROW_COLUMNS, "follow_heading_mae_rad", "person_in_view_fraction",
                "person_dist_error_mae_m", *SOCIAL_COLUMNS)
#: The leaderboard's mean columns besides success (quality ones: over successful episodes).
BOARD_MEANS = ("spl", "clearance_time_s", "path_length_m")
#: The episode table's metric columns.
EPISODE_COLUMNS = ("clearance_time_s", "path_length_m", "spl", "collision_count",
                   "obstacle_dist_min_m")
#: Outcomes that are no failure: success, and an end nothing can judge (no goal known).
_NOT_FAILED = (Outcome.GOAL.value, Outcome.UNKNOWN.value)
#: At most this many start–goal pairs get a map (the rest are counted).
MAX_PAIR_MAPS = 200


def _label(col: str) -> str:
    unit = plain_text(METRICS[col].unit)
    return f"{plain_text(METRICS[col].label)}" + (f" [{unit}]" if unit and unit != "–" else "")


def _per_group(frame: pd.DataFrame, section: Callable[[pd.DataFrame, int], str],
               groups: list[Group] | None = None) -> str:
    """``section(rows, table_id)`` for each group of ``frame`` (one task in one world set),
    under a heading per group when there are several; table ids ``<id>``, ``<id>-2``, ..."""
    groups = split(frame) if groups is None else groups
    return "".join((f"<h3>{html.escape(g.label)}</h3>" if len(groups) > 1 else "")
                   + section(frame.loc[list(g.rows)], k) for k, g in enumerate(groups, 1))


def _id(name: str, k: int) -> str:
    return name if k == 1 else f"{name}-{k}"


def _leaderboard(frame: pd.DataFrame) -> str:
    note = ("<p class=note>One table per task and world set. Success is k/n over the judged "
            "episodes (aborted and unknown ones are out of n and counted apart); a task "
            "without a goal heads with its full runs (timeouts over the episodes that ended); "
            "the interval is Wilson's score interval. Time and path are means over each "
            "agent's successful episodes (full runs), SPL over every judged one; a column "
            "shows where some episode has it. Collisions, timeouts, aborted: episodes that "
            "ended so; unreadable: bags of the agent that could not be judged (those whose "
            "agent is unknown are listed below). Click a header to sort.</p>")
    return note + _per_group(frame, _board)


def _board(frame: pd.DataFrame, index: int) -> str:
    agg = aggregate(frame, by="agent")
    full = headline(agg) == FULL_RUNS
    task = [c for c in TASK_COLUMNS if f"{c}_mean" in agg and agg[f"{c}_mean"].notna().any()]
    means = [c for c in (*BOARD_MEANS, *task) if c in frame and frame[c].notna().any()]
    header = ["agent", "episodes", "full runs" if full else "success", "Wilson 95% CI",
              *(_label(c) for c in means), "collisions", "timeouts", "aborted", "unreadable"]
    rows = []
    for name, r in agg[agg["n_episodes"] > 0].iterrows():
        k, n = (int(r["n_full_runs"]), int(r["n_ran"])) if full else (int(r["n_success"]),
                                                                       int(r["n_judged"]))
        low, high = wilson_interval(k, n)
        rate = k / n if n else math.nan
        rows.append((rate, [
            hp.text(name), hp.number(r["n_episodes"], 0),
            hp.shown_as(f"{k}/{n} ({100 * rate:.0f}%)" if n else "–", rate),
            hp.shown_as(f"[{100 * low:.0f}, {100 * high:.0f}]%" if n else "–", low),
            *(hp.number(r[f"{c}_mean"]) for c in means),
            hp.number(r["n_collision"], 0), hp.number(r["n_timeout"], 0),
            hp.number(r["n_aborted"], 0), hp.number(r["n_failed"], 0)]))
    rows.sort(key=lambda item: -1.0 if math.isnan(item[0]) else item[0], reverse=True)
    return hp.table(_id("leaderboard", index), header, [r for _, r in rows])


def _paired(frame: pd.DataFrame, pairs: pd.Series, references: Sequence[str] | None,
            n_boot: int) -> str:
    grouped = grouped_paired(frame, pairs, references, n_boot=n_boot)

    def section(rows: pd.DataFrame, k: int) -> str:
        cells = [(paired_cells(d), [None, None, d.pairs, d.couples, d.unpaired, d.success,
                                    d.reference_success, d.difference, d.ci_low, d.b, d.c,
                                    d.p_value, None]) for d in grouped[k - 1][1]]
        table = [[hp.text(c) if s is None else hp.shown_as(c or "–", s) for c, s in zip(*row)]
                 for row in cells]
        body = (hp.table(_id("paired", k), PAIRED_COLUMNS, table) if table else
                "<p>No comparison: fewer than two agents (or no reference) here.</p>")
        return body + _spread(rows, k)

    good = frame["error"].fillna("") == ""
    lone = int((pairs.isna() & good).sum())
    note = (
        "<p class=note>Within one task and world set, each agent against each reference on "
        "the episodes that share a start–goal pair and world: the i-th episode of one on a "
        "pair is matched with the i-th of the other. <b>difference</b>: success of the agent "
        "minus the reference's, over the matched couples, in percentage points; <b>95% "
        f"CI</b>: percentile bootstrap ({n_boot} resamples of whole start–goal pairs); "
        "<b>b</b>, <b>c</b>: couples only the agent, only the reference succeeded in; "
        "<b>McNemar p</b>: exact two-sided test on those. "
        f"<b>{NOT_DISTINGUISHABLE}</b> unless p &lt; 0.05 and the interval excludes 0. "
        "<b>unpaired</b>: episodes (agent + reference) without a partner, left out. "
        f"Episodes without a start–goal pair in their facts: {lone}.</p>")
    return note + _per_group(frame, section, [g for g, _ in grouped])


def _spread(frame: pd.DataFrame, k: int) -> str:
    """The spread of each agent's success rate between its runs, when some has two."""
    spread, body = seed_spread(frame), ""
    if len(spread):
        srows = [[hp.text(r.agent), hp.number(r.runs, 0),
                  hp.text(", ".join(f"{100 * v:.0f}%" for v in r.rates)),
                  hp.number(100 * r.mean, 1, "%"), hp.number(100 * r.std, 1, " pts"),
                  hp.number(100 * (r.max - r.min), 1, " pts")] for r in spread.itertuples()]
        body += ("<h3>Spread between runs (seeds, repetitions)</h3><p class=note>Success rate "
                 "of each run of an agent; a difference between agents smaller than this "
                 "spread is seed noise.</p>" + hp.table(
                     _id("spread", k), ["agent", "runs", "success per run", "mean", "std",
                                        "max − min"], srows))
    return body


def _outcome_counts(frame: pd.DataFrame, names: pd.Series) -> str:
    words = [o.value for o in Outcome]
    outcomes = frame["outcome"].where(frame["error"].fillna("") == "", "unreadable")
    counts = pd.crosstab(names, outcomes.fillna("unknown"))
    cols = [w for w in (*words, "unreadable") if w in counts.columns]
    rows = [[hp.text(agent), *(hp.number(counts.at[agent, w], 0) for w in cols)]
            for agent in dict.fromkeys(names)]
    return hp.table("outcomes", ["agent", *cols], rows)


def _failures(frame: pd.DataFrame, names: pd.Series, sketches: dict[int, Sketch]) -> str:
    parts = [_outcome_counts(frame, names), "<p class=note>Each agent's failed episodes end "
             "where the dot is (red: collision, orange: timeout, purple: diverged, grey: "
             "aborted), on the map the scans of every episode in that world build.</p>"]
    worlds = frame["world"].fillna("a world not recorded").to_dict()
    agent_of = names.to_dict()
    by_world: dict[object, list[int]] = {}
    for i in sketches:
        by_world.setdefault(worlds[i], []).append(i)
    figures: list[str] = []
    clean: list[str] = []
    for world, members in by_world.items():
        for agent in dict.fromkeys(agent_of[i] for i in members):
            failed = [sketches[i] for i in members
                      if agent_of[i] == agent and sketches[i].outcome not in _NOT_FAILED]
            caption = f"<b>{html.escape(str(agent))}</b> in {html.escape(str(world))}: " \
                      f"{len(failed)} failed"
            if not failed:
                clean.append(caption.replace(": 0 failed", ": no failed episode"))
                continue
            figures.append(hp.figure(png_uri(failure_map([sketches[i] for i in members],
                                                         failed)), caption, f"{agent} failures"))
    tail = f"<p>{'; '.join(clean)}.</p>" if clean else ""
    return "\n".join(parts) + f'<div class="maps">{"".join(figures)}</div>' + tail


def _pair_maps(frame: pd.DataFrame, names: pd.Series, pairs: pd.Series,
               sketches: dict[int, Sketch]) -> str:
    agent_of = names.to_dict()
    agents = list(dict.fromkeys(agent_of[i] for i in sketches))
    colour = {a: PALETTE[i % len(PALETTE)] for i, a in enumerate(agents)}
    key = '<p class="key">' + "".join(hp.swatch(colour[a], str(a)) for a in agents) + "</p>"
    by_pair: dict[str, list[int]] = {}
    for i in sketches:
        if pairs[i] is not None:
            by_pair.setdefault(pairs[i], []).append(i)
    labels = list(by_pair)
    figures = []
    for label in labels[:MAX_PAIR_MAPS]:
        members = by_pair[label]
        drawn = [(sketches[i], colour[agent_of[i]]) for i in members]
        ends = ", ".join(f"{html.escape(str(agent_of[i]))}: {sketches[i].outcome}"
                         for i in members)
        figures.append(hp.figure(png_uri(pair_map(drawn)),
                                 f"<b>{html.escape(label)}</b><br>{ends}", label))
    if not labels:
        return ("<p>No episode records its start–goal pair (the facts' start and goal, which "
                "pic4rl's env writes; a topic map's facts for a real bag).</p>")
    more = len(labels) - MAX_PAIR_MAPS
    tail = f"<p class=note>{more} more pairs are not drawn.</p>" if more > 0 else ""
    note = ("<p class=note>Each start–goal pair: every agent's path in its colour, the start "
            "(black ring), the goal (green ring: its tolerance), each end in its outcome's "
            "colour, on the map its episodes' scans build; with a crowd, each person's track (pink, a "
            "ring where it was last seen).</p>")
    return note + key + f'<div class="maps">{"".join(figures)}</div>' + tail


def _href(path: Path, out_dir: Path) -> str:
    return quote(os.path.relpath(path.resolve(), out_dir.resolve()).replace(os.sep, "/"))


def _video(bag: Path) -> Path | None:
    stem = bag.with_name(bag.name.removesuffix(".db3").removesuffix(".mcap"))
    for suffix in (".mp4", ".gif"):
        if (candidate := stem.with_name(stem.name + suffix)).is_file():
            return candidate
    return None


def _episodes(frame: pd.DataFrame, names: pd.Series, pairs: pd.Series, out_dir: Path) -> str:
    header = ["agent", "world", "pair", "run", "episode", "outcome",
              *(_label(c) for c in EPISODE_COLUMNS), "bag", "video", "error"]
    rows, classes = [], []
    for i, r in frame.iterrows():
        bag = Path(str(r["bag"]))
        video = _video(bag)
        rows.append([
            hp.text(names[i]), hp.text(r.get("world")), hp.text(pairs[i]), hp.text(r.get("run")),
            hp.text(r.get("episode")), hp.text(r["outcome"]),
            *(hp.number(r.get(c), 0 if c == "collision_count" else 2) for c in EPISODE_COLUMNS),
            hp.link(bag.name, _href(bag, out_dir) if bag.exists() else None, "bag",
                    short_bag(bag)),  # the folder's name: the table fits a laptop's width
            hp.link(video.name, _href(video, out_dir), "video") if video else hp.text(None),
            hp.text(r["error"] or "")])
        classes.append("error" if r["error"] else "")
    return hp.table("episodes", header, rows, filterable=True, row_classes=classes, scroll=True)


def build_report(result: MetricsResult, out_dir: Path, *,
                 references: Sequence[str] | None = None, inputs: Sequence[str] = (),
                 title: str = "pic4rl benchmark report", n_boot: int = N_BOOT) -> str:
    """The page of ``result`` (every bag's row and episode), its links relative to
    ``out_dir``; ``references``: the agents every other is compared with (default: every
    pair of agents once)."""
    frame = result.frame
    names = _group_keys(frame, ["agent"])["agent"]
    pairs = pair_labels(result)
    sketches = {i: sketch(r.episode, str(frame.at[i, "outcome"]))
                for i, r in zip(frame.index, result.results) if r.episode is not None}
    failed = result.failed
    errors = ("<p>None: every bag was read.</p>" if not failed else hp.table(
        "errors", ["bag", "error"], [[hp.text(f.bag), hp.text(f.error)] for f in failed]))
    good = len(result.results) - len(failed)
    intro = (provenance(result) + f"<p class=note>{good} episodes from {len(result.results)} "
             f"bags ({len(failed)} unreadable), {names[~frame['error'].astype(bool)].nunique()} "
             "agents; every figure from the bags alone.</p>")
    free = goal_less(frame)  # logs without a goal: their own section, not ranked nor failed
    logs = logs_section(frame, names, sketches, _label)
    coverage = coverage_section(result, names)  # exploration episodes' area seen over time
    ranked = ~free & (frame["error"].fillna("") == "")
    board = (_leaderboard(frame[~free]) + leaderboard_downloads(frame[~free]) if ranked.any()
             else "<p>No episode has a goal: nothing to rank (see Logs without a goal).</p>")
    sections = [
        ("leaderboard", "Leaderboard", board),
        *([("logs", "Logs without a goal", logs)] if logs else []),
        *([("coverage", "Coverage over time", coverage)] if coverage else []),
        ("paired", "Paired comparisons", _paired(frame, pairs, references, n_boot)),
        ("failures", "How each agent fails", _failures(
            frame, names, {i: s for i, s in sketches.items() if not free[i]})),
        ("pairs", "Start–goal pairs", _pair_maps(frame, names, pairs, sketches)),
        ("episodes", "Episodes", _episodes(frame, names, pairs, out_dir)),
        ("errors", "Unreadable bags", errors),
        ("inputs", "Inputs", inputs_section(result, names, inputs)),
    ]
    return hp.page(title, sections, intro)


def write_report(result: MetricsResult, out: Path, *, overwrite: bool = False,
                 **options: object) -> Path:
    """Write ``build_report``'s page to ``out`` whole (``ConfigError`` when it exists and not
    ``overwrite``; ``OutputError`` naming it when it cannot be written)."""
    out = Path(out)
    if out.exists() and not overwrite:
        raise ConfigError(f"--out {str(out)!r} exists; pass --force to replace it")
    text = build_report(result, out.parent, **options)  # type: ignore[arg-type]
    try:
        return atomic.write_text(out, text)
    except OSError as err:
        raise OutputError(f"--out {str(out)!r}: cannot write it: {err.strerror or err}") from err
