"""A suite's results, from its bags alone through ``pic4rl_metrics``: one table (one row per
task × agent × world × robot × pair set, every repetition's episodes together) in the suite's
layout (``LAYOUTS``): the paper's columns, SPL, the success rate's Wilson 95 % interval and n;
or BARN's, success, collision and timeout rates with their Wilson intervals and the mean BARN
time and score with bootstrap intervals; or another of ``LAYOUTS`` (the crowd's: BARN's rates,
SPL and the social columns). The cells are computed once, in the metrics
(``pic4rl_metrics.tables.protocol``: ``pic4rl-metrics compare --table`` gives the same numbers
from the same bags); this module adds the suite's row keys and each row's status. A task without
a goal (person monitoring; the metrics' rule, ``pic4rl_metrics.tables.groups.headline``) heads
with its full runs instead of success: a ``full runs`` column (k/n, its Wilson interval) after
success, filled for that task's rows only.
A leaderboard per task ranks by its headline, then SPL (the BARN score; left out for a task
without a goal). A cell that failed makes its row read ``failed: <error>``.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd
from matplotlib.figure import Figure

from pic4rl_base import atomic
from pic4rl_metrics.core.registry import METRICS
from pic4rl_metrics.tables.aggregate import wilson_interval
from pic4rl_metrics.tables.batch import MetricsResult, compute
from pic4rl_metrics.tables.layouts import render_rows
from pic4rl_metrics.tables.paired import agent_names
from pic4rl_metrics.tables.protocol import (FULL_RUNS_LABEL, LAYOUTS, Layout, empty_cells,
                                            protocol_cells)
from pic4rl_metrics.tables.protocol import header as layout_header
from pic4rl_metrics.tables.text import plain_text
from pic4rl_metrics.viz.html_report import write_report
from pic4rl_metrics.viz.plots import save_figure
from pic4rl_metrics.viz.report_maps import SKETCH_SCANS

from .suite import Cell, Suite

ROW_KEYS = ("task", "agent", "world", "robot", "pairs")
TABLE_FORMATS = {"csv": "results.csv", "markdown": "results.md", "latex": "results.tex"}
REPORT = "report.html"  # the suite's page, beside its tables


@dataclass(frozen=True)
class SuiteTable:
    header: tuple[str, ...]
    rows: tuple[tuple[str | None, ...], ...]
    files: tuple[Path, ...]  # the tables and leaderboards written
    bag_errors: tuple[str, ...]  # bags that could not be judged


def _judged(suite: Suite, cells: Sequence[Cell]) -> tuple[pd.DataFrame, tuple[str, ...],
                                                         MetricsResult | None]:
    """Every cell's episodes with the cell's row keys, the errors of unjudged bags, and the
    metrics' result (None when no cell has bags)."""
    folders = [suite.root / c.name / c.agent for c in cells]
    folders = [f for f in folders if f.is_dir()]
    if not folders:
        return pd.DataFrame(columns=[*ROW_KEYS, "success"]), (), None
    # one process per core (the pass runs on the driver); a few whole scans: the report's maps
    result = compute(folders, jobs=0, scan_sample=SKETCH_SCANS)
    frame = result.frame
    by_name = {c.name: c for c in cells}
    rows = [by_name[Path(str(b)).resolve().relative_to(suite.root.resolve()).parts[0]].row
            for b in frame["bag"]]
    keys = pd.DataFrame(rows, index=frame.index, columns=list(ROW_KEYS))
    frame = pd.concat([keys, frame.drop(columns=[c for c in ROW_KEYS if c in frame])], axis=1)
    return frame, tuple(str(f.error) for f in result.failed), result


def _header(layout: Layout, full_runs: bool = False) -> tuple[str, ...]:
    """The table's columns: the row keys, the layout's (``protocol.header``), the status;
    ``full_runs``: some task heads with its full runs."""
    return (*ROW_KEYS, *layout_header(layout, full_runs), "status")


def build_rows(suite: Suite, errors: Mapping[str, str],
               judged: tuple[pd.DataFrame, tuple[str, ...], object] | None = None) -> tuple[
        tuple[str, ...], list[list[str | None]], tuple[str, ...]]:
    """The table's header and rows (in the suite's order) and the unjudged bags' errors;
    ``errors``: the failed cells' errors by cell name; ``judged``: ``_judged``'s, when the
    caller judged the bags already. The cells are the metrics' (``protocol.protocol_cells``,
    as ``pic4rl-metrics compare --table`` computes them)."""
    layout = LAYOUTS[suite.table]
    frame, bad, _ = judged if judged is not None else _judged(suite, suite.cells)
    columns, cells = protocol_cells(frame, ROW_KEYS, layout)
    rows: dict[tuple[str, ...], tuple[dict[str, str], list[str]]] = {}
    for cell in suite.cells:
        key = tuple(cell.row.values())
        rows.setdefault(key, (cell.row, []))
        if cell.name in errors:
            rows[key][1].append(f"{cell.name}: {errors[cell.name]}")
    out = []
    for key, (row, errs) in rows.items():
        error = "; ".join(errs)
        mine = cells.get(key)
        status = "ok" if mine is not None and not error else f"failed: {error}"
        out.append([*row.values(), *(empty_cells(columns) if mine is None else mine), status])
    return (*ROW_KEYS, *columns, "status"), out, bad


def _rate(row: Sequence[str | None], col: int) -> float:
    text = row[col]
    if text is None:
        return -1.0
    if "/" in text:
        k, n = text.split("/")
        return int(k) / int(n)
    return float(text)


def headline_column(header: Sequence[str], rows: Sequence[Sequence[str | None]]) -> str:
    """The column that heads ``rows`` (one task's): ``full runs`` where ``build_rows`` filled
    it for them (their task has no goal: ``groups.headline``), else ``success``."""
    if FULL_RUNS_LABEL in header:
        col = header.index(FULL_RUNS_LABEL)
        if any(r[col] is not None for r in rows):
            return FULL_RUNS_LABEL
    return "success"


def leaderboards(header: Sequence[str], rows: Sequence[Sequence[str | None]],
                 layout: Layout = LAYOUTS["paper"]) -> dict[str, str]:
    """Markdown per task: its rows by their headline (success, or full runs for a task
    without a goal: ``headline_column``), then the layout's rank metric (SPL, the BARN score;
    left out where it needs a goal that the task has not), best first; a row with a failed
    cell is never ranked (its episodes are not all there): it is listed below the ranked
    rows, its rank ``failed``."""
    label = plain_text(METRICS[layout.rank].label)
    spl = header.index(f"{label} [{plain_text(METRICS[layout.rank].unit)}]")
    boards = {}
    for task in dict.fromkeys(r[0] for r in rows):
        mine = [r for r in rows if r[0] == task]
        head = headline_column(header, mine)
        first = header.index(head)
        by = [spl] if head == "success" or "goal" not in METRICS[layout.rank].needs else []
        mine.sort(key=lambda r: (r[-1] == "ok", _rate(r, first), *(_rate(r, c) for c in by)),
                  reverse=True)
        ranked = sum(r[-1] == "ok" for r in mine)
        cols = ["rank", *header[1:5], "n", head, f"{head} 95% CI", *[label] * len(by),
                "status"]
        body = [[str(i + 1) if i < ranked else "failed", *r[1:5], r[5], r[first],
                 r[first + 1], *(r[c] for c in by), r[-1]] for i, r in enumerate(mine)]
        boards[str(task)] = render_rows(cols, body, "markdown")
    return boards


def success_figure(task: str, header: Sequence[str],
                      rows: Sequence[Sequence[str | None]]) -> Figure:
    """One task's rows as bars of their success rate (their full-run rate for a task without
    a goal: ``headline_column``) with its Wilson 95 % interval (a failed or unjudged row is an
    empty bar, labelled so)."""
    mine = [r for r in rows if r[0] == task]
    head = headline_column(header, mine)
    success = header.index(head)
    labels, rates, lows, highs = [], [], [], []
    for r in mine:
        k, _, n = (r[success] or "0/0").partition("/")
        low, high = wilson_interval(int(k), int(n or 0))
        rate = int(k) / int(n) if n and int(n) else math.nan
        labels.append(" · ".join(str(v) for v in r[1:5]) + ("" if r[-1] == "ok" else " (failed)"))
        rates.append(rate)
        lows.append(max(rate - low, 0.0) if n and int(n) else 0.0)  # rounding: never < 0
        highs.append(max(high - rate, 0.0) if n and int(n) else 0.0)
    fig = Figure(figsize=(9, 1.2 + 0.45 * len(mine)), layout="constrained")
    ax = fig.subplots()
    y = np.arange(len(mine))[::-1]
    ax.barh(y, np.nan_to_num(rates), xerr=[lows, highs], color="tab:blue", capsize=3)
    ax.set_yticks(y, labels, fontsize=8)
    ax.set_xlim(0, 1)
    rate_name = "success rate" if head == "success" else "full-run rate"
    ax.set_xlabel(f"{rate_name} (bars: Wilson 95 % interval)")
    ax.set_title(f"{task}: agent · world · robot · pairs")
    return fig


def _report(suite: Suite, result: MetricsResult) -> Path:
    """``report.html``: the suite's page (``pic4rl_metrics.viz.html_report``), every agent
    compared with each of the suite's baselines that has episodes (else every pair)."""
    present = set(agent_names(result.frame))
    baselines = [b for b in dict.fromkeys(c.baseline for c in suite.cells) if b in present]
    return write_report(result, suite.root / REPORT, overwrite=True,
                        references=baselines or None, inputs=[str(suite.path)],
                        title=f"{suite.name}: pic4rl-bench report")


def write_results(suite: Suite, errors: Mapping[str, str]) -> SuiteTable:
    """Judge the suite's bags and write its tables (CSV, Markdown, LaTeX), its page
    (``report.html``), leaderboards and comparison figures (``comparison_<task>.png``) into
    the suite's bags folder, each atomically."""
    judged = _judged(suite, suite.cells)
    header, rows, bad = build_rows(suite, errors, judged)
    files = [atomic.write_text(suite.root / name, render_rows(header, rows, fmt))
             for fmt, name in TABLE_FORMATS.items()]
    if judged[2] is not None:
        files.append(_report(suite, judged[2]))
    files += [atomic.write_text(suite.root / f"leaderboard_{task}.md", text)
              for task, text in leaderboards(header, rows, LAYOUTS[suite.table]).items()]
    files += [save_figure(success_figure(task, header, rows),
                          suite.root / f"comparison_{task}.png", overwrite=True)
              for task in dict.fromkeys(r[0] for r in rows)]
    return SuiteTable(tuple(header), tuple(tuple(r) for r in rows), tuple(files), bad)
