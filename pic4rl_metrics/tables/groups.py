"""Which episodes a table may pool: those of one task in one world set.

An agent's indoor and BARN episodes, or a person-monitoring run and a goToPose run, are not
one row: every table (``compare``, ``compare --paired``, the report's leaderboard and paired
comparisons) splits the episodes into groups by ``GROUP_DIMENSIONS`` — the task (the ``task``
fact without its sensor, ``contract.task_name``) and the world set (``contract.world_set``:
``barn:12`` is in ``barn``) — and shows a header per group when there are several. A
dimension named in the row key (``compare --by task,agent``) is in the rows instead. Within a
group a column appears only where some row has a value (``results.table_columns``), and a
group without a goal heads with its full runs instead of a success rate (``headline``).
"""

from __future__ import annotations

import csv
import difflib
import io
import json
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import pandas as pd

from pic4rl_base.errors import ConfigError

from ..contract import task_name, world_set
from ..core.registry import METRIC_TABLE
from .aggregate import DASH, FULL_RUNS, UNKNOWN_GROUP, _missing, aggregate
from .layouts import check_format, latex_escape
from .text import render_comparison

#: A group dimension: its header's name, the fact column it is read from and how, and the
#: row-key columns that hold it already.
GROUP_DIMENSIONS: dict[str, tuple[str, Callable[[str | None], str | None], tuple[str, ...]]] = {
    "task": ("task", task_name, ("task",)),
    "worlds": ("world", world_set, ("world", "world_set")),
}
#: Columns a comparison's rows may be keyed by (``compare --by``): facts, and the world set.
BY_CHOICES: tuple[str, ...] = ("agent", "run", "task", "world", "world_set")


@dataclass(frozen=True)
class Group:
    """One group of a result frame: its values per dimension (``(dimension, value)``, in
    ``GROUP_DIMENSIONS`` order; empty for the one group of a frame split by nothing) and the
    frame's index labels of its rows (error rows included)."""

    key: tuple[tuple[str, str], ...]
    rows: tuple[object, ...]

    @property
    def label(self) -> str:
        """``task goToPose, worlds barn`` ("" for the whole frame)."""
        return ", ".join(f"{name} {value}" for name, value in self.key)

    def record(self) -> dict[str, str]:
        """The group's values by dimension, for JSON and CSV."""
        return dict(self.key)


def parse_by(text: str | Sequence[str]) -> tuple[str, ...]:
    """``--by``'s columns (comma-separated), each one of ``BY_CHOICES``; ``ConfigError``
    naming the unknown one."""
    names = [n.strip() for n in text.split(",")] if isinstance(text, str) else list(text)
    names = [n for n in names if n]
    if not names:
        raise ConfigError(f"--by {text!r}: expected one or more of {', '.join(BY_CHOICES)}")
    for name in names:
        if name not in BY_CHOICES:
            close = difflib.get_close_matches(name, BY_CHOICES, n=1)
            hint = f"; did you mean {close[0]!r}?" if close else ""
            raise ConfigError(f"--by {name!r} is not a row key; expected one of "
                              f"{', '.join(BY_CHOICES)}{hint}")
    return tuple(dict.fromkeys(names))


def with_world_set(frame: pd.DataFrame) -> pd.DataFrame:
    """``frame`` with a ``world_set`` column (from ``world``) for a row key that names it."""
    if "world_set" in frame.columns or "world" not in frame.columns:
        return frame
    return frame.assign(world_set=frame["world"].map(lambda w: None if _missing(w)
                                                      else world_set(str(w))))


def split(frame: pd.DataFrame, by: Sequence[str] = ("agent",)) -> list[Group]:
    """``frame``'s groups, in order of first appearance: by the ``GROUP_DIMENSIONS`` that the
    row key ``by`` does not hold. A missing fact is ``(unknown)``. One group, keyed by the
    dimensions all its rows share, when the frame holds a single group (no header needed)."""
    dims = [(name, column, read) for name, (column, read, held) in GROUP_DIMENSIONS.items()
            if not set(held) & set(by)]
    members: dict[tuple[tuple[str, str], ...], list[object]] = {}
    for label, row in frame.iterrows():
        key = tuple((name, _value(row.get(column), read)) for name, column, read in dims)
        members.setdefault(key, []).append(label)
    return [Group(key, tuple(rows)) for key, rows in members.items()]


def _value(raw: object, read: Callable[[str | None], str | None]) -> str:
    value = None if _missing(raw) else read(str(raw))
    return UNKNOWN_GROUP if value is None else value


def headline(agg: pd.DataFrame) -> str:
    """``success``, or ``FULL_RUNS`` for a group's aggregate where no row has a success rate
    and some row has full runs (a task without a goal: person monitoring)."""
    if FULL_RUNS not in agg.columns or agg.empty:
        return "success"
    goal_less = (agg["success"] == DASH).all() and (agg[FULL_RUNS] != DASH).any()
    return FULL_RUNS if goal_less else "success"


def headline_columns(agg: pd.DataFrame, columns: Sequence[str]) -> list[str]:
    """``columns``, or where ``headline`` says the group has no goal: ``success`` replaced by
    ``FULL_RUNS`` and the columns that need a goal (heading error, SPL, ...) left out."""
    if headline(agg) == "success":
        return list(columns)
    return [FULL_RUNS if c == "success" else c for c in columns
            if c == "success" or c not in METRIC_TABLE.metrics or "goal" not in
            METRIC_TABLE.metrics[c].needs]


def join(parts: Sequence[tuple[Group, str]], fmt: str, *, several: bool | None = None) -> str:
    """Groups' tables (each rendered in ``fmt``) as one text: a header per group in table,
    markdown and LaTeX; one CSV and one JSON list whose rows lead with the group's dimensions
    (``Group.record``). A single group's table (``several`` false; default: one part) is
    returned as it is."""
    check_format(fmt)
    if len(parts) == 1 and not several:
        return parts[0][1]
    if fmt == "json":
        records = [{**g.record(), **r} for g, text in parts for r in json.loads(text)]
        return json.dumps(records, indent=2, ensure_ascii=False, allow_nan=False) + "\n"
    if fmt == "csv":
        readers = [(g, csv.DictReader(io.StringIO(text))) for g, text in parts]
        rows = [{**g.record(), **r} for g, reader in readers for r in reader]
        header = [*(k for g, _ in parts[:1] for k in g.record()),
                  *(f for _, reader in readers for f in reader.fieldnames or ())]
        buf = io.StringIO()
        writer = csv.DictWriter(buf, list(dict.fromkeys(header)), restval="",
                                lineterminator="\n")
        writer.writeheader()
        writer.writerows(rows)
        return buf.getvalue()
    heads = {"table": "== {} ==\n", "markdown": "### {}\n\n", "latex": "% {}\n"}[fmt]
    return "\n".join(heads.format(g.label) + text for g, text in parts)


def render_groups(frame: pd.DataFrame, fmt: str, *, by: Sequence[str] = ("agent",),
                  columns: Callable[[pd.DataFrame], Sequence[str]], over: str = "success",
                  count_aborted: bool = False, with_std: bool = False,
                  caption: str | None = None, label: str | None = None) -> str:
    """``compare``'s table: ``frame``'s rows aggregated by ``by`` (``aggregate``) in each of
    its groups (``split``), each group with the ``columns`` its own episodes have (a function
    of the group's rows) and its ``headline``; joined by ``join``. With several groups a LaTeX
    table names its group in its caption, and its ``label`` gets ``-1``, ``-2``, ..."""
    frame = with_world_set(frame) if "world_set" in by else frame
    groups = split(frame, by)
    parts = []
    for k, group in enumerate(groups, 1):
        rows = frame.loc[list(group.rows)]
        agg = aggregate(rows, by=list(by), over=over, count_aborted=count_aborted)
        cols = headline_columns(agg, columns(rows))
        several = len(groups) > 1
        name = latex_escape(group.label)
        cap = caption if not several else f"{caption} ({name})" if caption else name
        text = render_comparison(agg, fmt, columns=cols, with_std=with_std, caption=cap,
                                 label=f"{label}-{k}" if label and several else label)
        parts.append((group, text))
    return join(parts, fmt)
