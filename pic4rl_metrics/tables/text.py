"""Text renderings of results: per-episode rows and the paper's per-agent comparison table.

``render_episodes`` takes the per-episode DataFrame (one row per bag); ``render_comparison``
takes the output of ``aggregate.aggregate``. Both return one string in one of ``FORMATS``.
Missing values read "–" in table, markdown and LaTeX, are empty in CSV and ``null`` in JSON.
"""

from __future__ import annotations

import difflib
import json
import math
import re
from collections.abc import Sequence
from pathlib import PurePath

import numpy as np
import pandas as pd

from pic4rl_base.errors import ConfigError

from ..core.registry import METRICS
from .aggregate import DASH, EPISODE_COUNTED, FULL_RUNS
from .layouts import check_format, csv_text, fixed_width, latex_escape, markdown, tabular
from .results import ERROR_COLUMN, TABLE1_COLUMNS

#: Metric columns of the per-episode view and their short labels (units come from METRICS).
EPISODE_VIEW: dict[str, str] = {
    "outcome": "outcome",
    "success": "success",
    "clearance_time_s": "time",
    "path_length_m": "path",
    "distance_path_ratio": "dist/path",
    "lin_vel_mean_mps": "v mean",
    "ang_vel_std_radps": "ω std",
    "lin_acc_max_mps2": "max lin acc",
    "yaw_acc_max_radps2": "max yaw acc",
    "obstacle_dist_min_m": "min obst",
    "obstacle_dist_mean_m": "mean obst",
    "footprint_clearance_min_m": "min clearance",
    "personal_intrusion_time_s": "personal zone",
    "people_dist_min_m": "min person",
    "people_collision_count": "people coll.",
    "area_seen_m2": "area seen",
    "coverage_pct": "coverage",
}
#: View columns shown only when some episode has them (clearance needs a footprint, the
#: social columns people, the area seen an exploration).
_WHERE_DEFINED = frozenset({"footprint_clearance_min_m", "personal_intrusion_time_s",
                            "people_dist_min_m", "people_collision_count", "area_seen_m2",
                            "coverage_pct"})
_TEXT_COLUMNS = frozenset({"bag", "outcome", "optimal_path_source", "success", ERROR_COLUMN})
_SUPERSCRIPT = {"2": "²", "3": "³"}


def _is_missing(value: object) -> bool:
    if value is None or value is pd.NA or value is pd.NaT:
        return True
    return isinstance(value, (float, np.floating)) and math.isnan(value)


def _json_value(value: object) -> object:
    """A JSON-ready scalar: NaN/None/NA -> None, numpy scalars -> Python ones."""
    if _is_missing(value):
        return None
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, (pd.Timestamp, PurePath)):
        return str(value)
    return value


def _num(value: object, digits: int = 2) -> str | None:
    """``value`` with ``digits`` decimals, or None when missing."""
    return None if _is_missing(value) else f"{float(value):.{digits}f}"  # type: ignore[arg-type]


def plain_text(tex: str) -> str:
    """A METRICS label or unit in LaTeX ("$v_{mean}$", "m/s$^2$") as plain text ("v mean")."""
    text = tex.replace("$", "").replace("\\omega", "ω")
    text = re.sub(r"\^\{?([23])\}?", lambda m: _SUPERSCRIPT[m.group(1)], text)
    return re.sub(r"_\{([^}]*)\}", r" \1", text)


def short_bag(bag: object) -> str:
    """The last two components of a bag path ("run1/episode_03"), "–" when missing."""
    if _is_missing(bag) or bag == "":
        return DASH
    parts = [p for p in PurePath(str(bag)).parts if p not in ("/", "\\")]
    return "/".join(parts[-2:]) or str(bag)


# --- per-episode rows -----------------------------------------------------------------------


def _episode_cell(col: str, value: object) -> str | None:
    if col == "bag":
        return short_bag(value)
    if col == ERROR_COLUMN:
        return "" if _is_missing(value) else str(value)
    if _is_missing(value):
        return None
    if col == "success":
        return "yes" if float(value) == 1.0 else "no"  # type: ignore[arg-type]
    return str(value) if col in METRICS and METRICS[col].text else _num(value)


def render_episodes(df: pd.DataFrame, fmt: str, *, columns: Sequence[str] | None = None) -> str:
    """One line per episode. csv and json hold every column; table, markdown and latex show
    the bag (last two path components), the metrics ``columns`` (default: the EPISODE_VIEW
    metrics) present — the footprint's clearance only where a footprint gave one — and the
    error."""
    check_format(fmt)
    if fmt == "csv":
        return df.to_csv(index=False)
    if fmt == "json":
        records = [{str(k): _json_value(v) for k, v in r.items()} for r in df.to_dict("records")]
        return json.dumps(records, indent=2, ensure_ascii=False, allow_nan=False) + "\n"
    view = EPISODE_VIEW if columns is None else columns
    cols = [c for c in ("bag", *view, ERROR_COLUMN) if c in df.columns
            and not (c in _WHERE_DEFINED and df[c].isna().all())]
    rows = [[_episode_cell(c, v) for c, v in zip(cols, r)] for r in df[cols].itertuples(False)]
    right = [c not in _TEXT_COLUMNS for c in cols]
    units = [plain_text(METRICS[c].unit) if c in METRICS and c != "success" else "" for c in cols]
    labels = [EPISODE_VIEW.get(c, c) for c in cols]
    if fmt == "table":
        return fixed_width([labels, [f"[{u}]" if u else "" for u in units]], rows, right)
    if fmt == "markdown":
        return markdown([f"{lb} [{u}]" if u else lb for lb, u in zip(labels, units)], rows, right)
    tex_labels = [METRICS[c].label if c in METRICS else latex_escape(c) for c in cols]
    tex_units = [f"[{METRICS[c].unit}]" if c in METRICS and METRICS[c].unit else "" for c in cols]
    tex_rows = [[c if c is None else latex_escape(c) for c in r] for r in rows]
    return "\n".join(tabular([tex_labels, tex_units], tex_rows)) + "\n"


# --- per-agent comparison (the paper's Table 1) --------------------------------------------


def _check_columns(agg: pd.DataFrame, columns: Sequence[str]) -> None:
    for col in columns:
        if col == FULL_RUNS and "full_runs" in agg.columns:
            continue
        if col not in METRICS:
            close = difflib.get_close_matches(col, list(METRICS), n=1)
            hint = f"; did you mean {close[0]!r}?" if close else ""
            raise ConfigError(f"comparison column {col!r} is not a metric{hint}")
        needed = "success" if col == "success" else f"{col}_mean"
        if needed not in agg.columns:
            msg = f"comparison column {col!r}: the aggregate has no {needed!r} column"
            raise ConfigError(msg)


def _row_name(name: object) -> str:
    if isinstance(name, tuple):
        return " / ".join(DASH if _is_missing(n) else str(n) for n in name)
    return DASH if _is_missing(name) else str(name)


def _success_cell(value: object) -> str | None:
    """The aggregate's "n/total", or None when missing or "–" (nothing judged)."""
    return None if _is_missing(value) or value == DASH else str(value)


#: The aggregate's outcome counts a comparison can show first (``counts``), by default label.
OUTCOME_COUNTS: dict[str, str] = {"n_success": "goals", "n_collision": "collisions",
                                  "n_timeout": "timeouts", "n_aborted": "aborted"}


def _unit(col: str) -> str:
    """A comparison column's unit: episodes for an ``EPISODE_COUNTED`` metric."""
    if col == FULL_RUNS:
        return "n/total"
    return "episodes" if col in EPISODE_COUNTED else METRICS[col].unit


def _tex_label(col: str) -> str:
    """A comparison column's label in LaTeX (``full runs`` for a task without a goal)."""
    return "full runs" if col == FULL_RUNS else METRICS[col].label


def _comparison_cell(row: pd.Series, col: str, with_std: bool, pm: str) -> str | None:
    if col in ("success", FULL_RUNS):
        return _success_cell(row[col])
    if col in EPISODE_COUNTED:
        value = row.get(f"{col}_episodes")
        return None if _is_missing(value) else str(int(value))
    mean = _num(row[f"{col}_mean"])
    if mean is None or not with_std:
        return mean
    return f"{mean}{pm}{_num(row.get(f'{col}_std')) or DASH}"


def footnote(agg: pd.DataFrame, columns: Sequence[str]) -> str | None:
    """What the quality columns among ``columns`` average over, or None when ``agg`` does not
    say (an aggregate from before ``over`` existed) or no column is a quality column."""
    notes = [note for note in (_over_note(agg, columns), _aborted_note(agg)) if note]
    return " ".join(notes) or None


def _over_note(agg: pd.DataFrame, columns: Sequence[str]) -> str | None:
    quality = [c for c in columns if c in METRICS and METRICS[c].quality]
    if "over" not in agg.columns or not quality or agg.empty:
        return None
    labels = ", ".join(plain_text(METRICS[c].label) for c in quality)
    if agg["over"].iloc[0] == "all":
        return "All columns: mean over every judged episode of the row (--over all)."
    counts = ", ".join(str(int(n)) for n in agg["n_averaged"])
    which = "full runs" if FULL_RUNS in columns else "successful episodes"
    return (
        f"{labels}: mean over the row's {which} only (n = {counts}); the other "
        "columns over every judged episode. --over all averages every episode."
    )


def _aborted_note(agg: pd.DataFrame) -> str | None:
    """Aborted episodes (cut short: no outcome, or a sensor gone silent) per row, when any:
    they are not in "success"."""
    if "n_aborted" not in agg.columns or not agg["n_aborted"].any():
        return None
    counts = ", ".join(str(int(n)) for n in agg["n_aborted"])
    return (f"Aborted (cut short: no outcome recorded, or a sensor went silent): n = {counts}; "
            "in the success "
            "rate only with --count-aborted, as failures.")


def render_comparison(
    agg: pd.DataFrame,
    fmt: str,
    *,
    columns: Sequence[str] = TABLE1_COLUMNS,
    caption: str | None = None,
    label: str | None = None,
    with_std: bool = False,
    counts: dict[str, str] | None = None,
) -> str:
    """One row per group of ``agg`` (from ``aggregate``), one column per metric in ``columns``,
    after the outcome counts ``counts`` names (aggregate column → label, e.g.
    ``OUTCOME_COUNTS``: episodes per outcome). An ``EPISODE_COUNTED`` metric's cell is the
    number of episodes in which it happened.

    Cells are means with 2 decimals ("mean ± std" with ``with_std``); success is "n/total".
    table/markdown/csv carry labels and units ("time [s]"); latex is a ``table*`` with a label
    row and a unit row like the paper (``caption`` and ``label`` are inserted as given, LaTeX);
    json is a list of records keyed by metric column with unrounded means (``<m>_std`` too
    with ``with_std``) and null for NaN. What the trajectory-quality columns average over is
    said below the table (table, markdown, latex) or in the columns ``over`` and
    ``n_averaged`` (csv, json).
    """
    check_format(fmt)
    columns = list(columns)
    _check_columns(agg, columns)
    names = [_row_name(n) for n in agg.index]
    first = " / ".join(str(n) for n in agg.index.names if n is not None) or "agent"
    note = footnote(agg, columns)
    counts = dict(counts or {})
    if fmt == "json":
        return _comparison_json(agg, names, first, columns, with_std=with_std,
                                averaged=note is not None, counts=counts)

    pm = r" $\pm$ " if fmt == "latex" else " ± "
    rows = [
        [name, *(str(int(row[c])) for c in counts),
         *(_comparison_cell(row, c, with_std, pm) for c in columns)]
        for name, (_, row) in zip(names, agg.iterrows())
    ]
    labels = [*counts.values(), *(plain_text(_tex_label(c)) for c in columns)]
    units = [*(["[episodes]"] * len(counts)), *(f"[{plain_text(_unit(c))}]" for c in columns)]
    right = [False] + [True] * len(labels)
    below = f"\n{note}\n" if note is not None else ""
    if fmt == "table":
        return fixed_width([[first, *labels], ["", *units]], rows, right) + below
    if fmt == "markdown":
        return markdown([first, *(f"{a} {u}" for a, u in zip(labels, units))], rows, right) + below
    if fmt == "csv":
        header = [first, *(f"{a} {u}" for a, u in zip(labels, units))]
        if note is not None:
            header += ["over", "n_averaged"]
            rows = [[*r, str(o), str(int(n))] for r, o, n in zip(rows, agg["over"], agg["n_averaged"])]
        return csv_text(header, rows)

    headers = [["", *(latex_escape(c) for c in counts.values()),
                *(_tex_label(c) for c in columns)],
               ["", *(["[episodes]"] * len(counts)), *(f"[{_unit(c)}]" for c in columns)]]
    return _comparison_latex(rows, headers, caption=caption, label=label, note=note)


def _comparison_json(agg: pd.DataFrame, names: list[str], first: str, columns: list[str], *,
                     with_std: bool, averaged: bool, counts: dict[str, str]) -> str:
    """``render_comparison``'s json: records with unrounded means, null for NaN."""
    records: list[dict[str, object]] = []
    for name, (_, row) in zip(names, agg.iterrows()):
        rec: dict[str, object] = {first: name}
        rec.update({label: int(row[c]) for c, label in counts.items()})
        for col in columns:
            if col in ("success", FULL_RUNS):
                rec[col] = _success_cell(row[col])
                continue
            if col in EPISODE_COUNTED:
                rec[col] = _json_value(row.get(f"{col}_episodes"))
                continue
            rec[col] = _json_value(row[f"{col}_mean"])
            if with_std:
                rec[f"{col}_std"] = _json_value(row.get(f"{col}_std"))
        if averaged:
            rec["over"], rec["n_averaged"] = row["over"], int(row["n_averaged"])
        records.append(rec)
    return json.dumps(records, indent=2, ensure_ascii=False, allow_nan=False) + "\n"


def _comparison_latex(rows: list[list[str]], headers: list[list[str]], *, caption: str | None,
                      label: str | None, note: str | None) -> str:
    """``render_comparison``'s latex: a ``table*`` with a label row and a unit row."""
    tex_rows = [[latex_escape(r[0]), *r[1:]] for r in rows]
    lines = [r"\begin{table*}[ht]", r"\centering"]
    lines += [rf"\caption{{{caption}}}"] if caption is not None else []
    lines += [rf"\label{{{label}}}"] if label is not None else []
    lines += [r"\resizebox{\textwidth}{!}{%", *tabular(headers, tex_rows)]
    lines[-1] += "%"
    lines.append("}")
    if note is not None:
        lines.append(rf"\par\footnotesize {latex_escape(note)}")
    return "\n".join([*lines, r"\end{table*}"]) + "\n"
