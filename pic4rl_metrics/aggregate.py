"""Per-agent (or per-any-key) statistics of a per-episode result DataFrame.

Input: one row per bag, columns ``ID_COLUMNS + METRIC_COLUMNS + (ERROR_COLUMN,)`` as in
``results.py``. Output: one row per group with ``<metric>_mean`` and ``<metric>_std`` for each
numeric metric, the episode counts and the paper's ``success`` cell ("n/total").
"""

from __future__ import annotations

import difflib
import math
from collections.abc import Sequence

import numpy as np
import pandas as pd

from .errors import ConfigError
from .results import ERROR_COLUMN, METRIC_COLUMNS

#: Group name of rows whose key is missing (and, for ``agent``, whose run is missing too).
UNKNOWN_GROUP = "(unknown)"
#: Cell shown when nothing can be said (no judged episode, NaN).
DASH = "–"
#: Count columns of an aggregate, in the order they appear before the statistics.
COUNT_COLUMNS: tuple[str, ...] = ("n_episodes", "n_failed", "n_judged", "n_success", "success")
#: Metric columns that are text, hence never averaged.
_TEXT_METRICS = frozenset({"outcome"})


def _missing(value: object) -> bool:
    """True for None, NaN, pd.NA and the empty string."""
    if value is None or value is pd.NA:
        return True
    if isinstance(value, (float, np.floating)):
        return math.isnan(value)
    return isinstance(value, str) and value == ""


def _error_mask(df: pd.DataFrame) -> pd.Series:
    """Rows of bags that failed: a non-empty ``error`` cell."""
    if ERROR_COLUMN not in df.columns:
        return pd.Series(False, index=df.index)
    return df[ERROR_COLUMN].map(lambda e: not _missing(e)).astype(bool)


def _group_keys(df: pd.DataFrame, by: Sequence[str]) -> pd.DataFrame:
    """Key columns with missing values filled: ``agent`` falls back to ``run``, then unknown."""
    keys = pd.DataFrame(index=df.index)
    for col in by:
        values = df[col].astype(object)
        if col == "agent" and "run" in df.columns:
            values = values.where(~values.map(_missing), df["run"].astype(object))
        keys[col] = values.map(lambda v: UNKNOWN_GROUP if _missing(v) else v)
    return keys


def numeric_metric_columns(df: pd.DataFrame) -> list[str]:
    """Metric columns of ``df`` that are averaged, in ``METRIC_COLUMNS`` order."""
    return [c for c in METRIC_COLUMNS if c in df.columns and c not in _TEXT_METRICS]


def aggregate(df: pd.DataFrame, by: str | Sequence[str] = "agent") -> pd.DataFrame:
    """Mean and sample std (ddof=1, NaN-skipping) of every numeric metric per group.

    Error rows are left out of every statistic and counted in ``n_failed``. Columns:
    ``n_episodes`` (good rows), ``n_failed``, ``n_judged`` (success not NaN), ``n_success``
    (success == 1), ``success`` ("n_success/n_judged", "–" when none judged), then
    ``<m>_mean`` and ``<m>_std`` per metric. The std of a single value is NaN. Index: the
    group name(s), in order of first appearance.
    """
    by_cols = [by] if isinstance(by, str) else list(by)
    if not by_cols:
        raise ConfigError("aggregate: by=[] names no column; expected at least one, e.g. 'agent'")
    for col in by_cols:
        if col not in df.columns:
            close = difflib.get_close_matches(col, [str(c) for c in df.columns], n=1)
            hint = f"; did you mean {close[0]!r}?" if close else ""
            msg = f"aggregate: by={col!r} is not a column of the results{hint}"
            raise ConfigError(msg)

    metrics = numeric_metric_columns(df)
    stat_cols = [f"{m}_{s}" for m in metrics for s in ("mean", "std")]
    failed = _error_mask(df).to_numpy()
    keys = _group_keys(df, by_cols)
    values = df[metrics].apply(pd.to_numeric, errors="coerce").astype(float).reset_index(drop=True)

    groups: dict[tuple[object, ...], list[int]] = {}
    for pos, key in enumerate(keys.itertuples(index=False, name=None)):
        groups.setdefault(key, []).append(pos)
    rows: list[dict[str, object]] = []
    for members in groups.values():
        good = [p for p in members if not failed[p]]
        group = values.iloc[good]
        row: dict[str, object] = {"n_episodes": len(good), "n_failed": len(members) - len(good)}
        judged = group["success"].dropna() if "success" in metrics else pd.Series(dtype=float)
        n_success = int((judged == 1.0).sum())
        row["n_judged"] = len(judged)
        row["n_success"] = n_success
        row["success"] = f"{n_success}/{len(judged)}" if len(judged) else DASH
        means, stds = group.mean(skipna=True), group.std(ddof=1, skipna=True)
        for m in metrics:
            row[f"{m}_mean"] = float(means[m]) if good else math.nan
            row[f"{m}_std"] = float(stds[m]) if good else math.nan
        rows.append(row)

    columns = list(COUNT_COLUMNS) + stat_cols
    if len(by_cols) == 1:
        index = pd.Index([key[0] for key in groups], name=by_cols[0], dtype=object)
    else:
        arrays = [[key[i] for key in groups] for i in range(len(by_cols))]
        index = pd.MultiIndex.from_arrays(arrays, names=by_cols)
    out = pd.DataFrame(rows, index=index, columns=columns)
    int_cols = ["n_episodes", "n_failed", "n_judged", "n_success"]
    return out.astype({c: "int64" for c in int_cols})
