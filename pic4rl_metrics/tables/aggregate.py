"""Per-agent (or per-any-key) statistics of a per-episode result DataFrame.

Input: one row per bag, columns ``ID_COLUMNS + <metric columns> + (ERROR_COLUMN,)`` as in
``results.py``. Output: one row per group with ``<metric>_mean`` and ``<metric>_std`` for each
numeric metric, the episode counts per outcome and the paper's ``success`` cell ("n/total").

Trajectory-quality columns (time, path, velocities, accelerations, jerk, obstacle distances:
the metrics registered with ``quality=True``) are averaged over the successful episodes by
default, as the paper's table does: a crash's short path is no evidence of a good one.
Success, collisions, SPL and the other columns always cover every judged episode.
"""

from __future__ import annotations

import difflib
import math
from collections.abc import Sequence

import numpy as np
import pandas as pd

from pic4rl_base.errors import ConfigError

from ..contract import Outcome
from ..core.registry import METRIC_TABLE
from .results import ERROR_COLUMN

#: Group name of rows whose key is missing (and, for ``agent``, whose run is missing too).
UNKNOWN_GROUP = "(unknown)"
#: Cell shown when nothing can be said (no judged episode, NaN).
DASH = "–"
#: Outcomes counted in a column of their own (``n_<outcome>``).
COUNTED_OUTCOMES: tuple[str, ...] = (
    Outcome.COLLISION.value, Outcome.TIMEOUT.value, Outcome.DIVERGED.value,
    Outcome.ABORTED.value,
)
#: Event counts that a table gives as the number of episodes in which the event happened
#: (``<metric>_episodes``), not as a mean per episode: "collisions" counts episodes.
EPISODE_COUNTED: tuple[str, ...] = ("collision_count", "people_collision_count")
#: Episodes the trajectory-quality columns average over: the successful ones, or all.
OVER_CHOICES: tuple[str, ...] = ("success", "all")
#: Count columns of an aggregate, in the order they appear before the statistics:
#: ``n_averaged`` episodes entered the quality columns' means, as ``over`` says.
COUNT_COLUMNS: tuple[str, ...] = (
    "n_episodes", "n_failed", "n_judged", "n_success", "success", "n_full_runs", "n_ran",
    "full_runs",
    *(f"n_{o}" for o in COUNTED_OUTCOMES), "n_averaged", "over",
)
#: The headline of a row without a goal (person monitoring): its episodes that ran the time
#: budget out, ``timeout``, over those that ended so or otherwise (collision, diverged).
FULL_RUN = Outcome.TIMEOUT.value
#: The aggregate's column of those, "k/n"; the headline column of a table of such rows.
FULL_RUNS = "full_runs"
_RAN = (FULL_RUN, Outcome.COLLISION.value, Outcome.DIVERGED.value)


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
    """Registered numeric metric columns of ``df``, in registry (table) order."""
    return [n for n, m in METRIC_TABLE.metrics.items() if n in df.columns and not m.text]


def aggregate(
    df: pd.DataFrame, by: str | Sequence[str] = "agent", *, over: str = "success",
    count_aborted: bool = False,
) -> pd.DataFrame:
    """Mean and sample std (ddof=1, NaN-skipping) of every numeric metric per group.

    Error rows are left out of every statistic and counted in ``n_failed``. Columns:
    ``n_episodes`` (good rows), ``n_failed``, ``n_judged`` (success not NaN), ``n_success``
    (success == 1), ``success`` ("n_success/n_judged", "–" when none judged), for a group
    without a goal (no success judged, some episode ended) ``n_full_runs``, ``n_ran`` and
    ``full_runs`` ("k/n": timeouts over the episodes that ended in a timeout, a collision or
    diverged; "–" and 0 elsewhere), ``n_collision``, ``n_timeout``, ``n_diverged``,
    ``n_aborted`` (by outcome), ``n_averaged`` (episodes in the trajectory-quality means: the
    successful ones, or a group's full runs, for ``over="success"``; every good row for
    ``"all"``), ``over``, then ``<m>_mean`` and ``<m>_std`` per metric. The std of a single
    value is NaN; a quality column of a group without a success is NaN. Index: the group
    name(s), in order of first appearance. Aborted episodes (cut short, no outcome) are out of
    the success rate, unless ``count_aborted`` counts them as failures. Each metric of
    ``EPISODE_COUNTED`` also gets ``<m>_episodes``: the episodes where it is above 0.
    """
    by_cols = _check_request(df, by, over)
    metrics = numeric_metric_columns(df)
    quality = [m for m in metrics if METRIC_TABLE.metrics[m].quality]
    if over == "success" and quality and "success" not in metrics:
        msg = "aggregate: over='success' needs a 'success' column; pass over='all'"
        raise ConfigError(msg)
    failed = _error_mask(df).to_numpy()
    keys = _group_keys(df, by_cols)
    values = df[metrics].apply(pd.to_numeric, errors="coerce").astype(float).reset_index(drop=True)
    outcomes = (
        df["outcome"].reset_index(drop=True) if "outcome" in df.columns
        else pd.Series([None] * len(df), dtype=object)
    )
    if count_aborted and "success" in values.columns:
        values.loc[(outcomes == Outcome.ABORTED.value).to_numpy(), "success"] = 0.0
    groups: dict[tuple[object, ...], list[int]] = {}
    for pos, key in enumerate(keys.itertuples(index=False, name=None)):
        groups.setdefault(key, []).append(pos)
    rows = []
    for members in groups.values():
        good = [p for p in members if not failed[p]]
        row = _group_row(values.iloc[good], outcomes.iloc[good], metrics, quality, over)
        rows.append({"n_episodes": len(good), "n_failed": len(members) - len(good), **row})
    if len(by_cols) == 1:
        index = pd.Index([key[0] for key in groups], name=by_cols[0], dtype=object)
    else:
        arrays = [[key[i] for key in groups] for i in range(len(by_cols))]
        index = pd.MultiIndex.from_arrays(arrays, names=by_cols)
    stat_cols = [f"{m}_{s}" for m in metrics for s in ("mean", "std")]
    episode_cols = [f"{m}_episodes" for m in EPISODE_COUNTED if m in metrics]
    out = pd.DataFrame(rows, index=index, columns=list(COUNT_COLUMNS) + stat_cols + episode_cols)
    int_cols = [
        "n_episodes", "n_failed", "n_judged", "n_success", "n_full_runs", "n_ran",
        *(f"n_{o}" for o in COUNTED_OUTCOMES), "n_averaged", *episode_cols,
    ]
    return out.astype({c: "int64" for c in int_cols})


def _check_request(df: pd.DataFrame, by: str | Sequence[str], over: str) -> list[str]:
    """The grouping columns, or ``ConfigError`` for an unknown ``over`` or column."""
    if over not in OVER_CHOICES:
        msg = f"aggregate: over={over!r}; expected one of {', '.join(OVER_CHOICES)}"
        raise ConfigError(msg)
    by_cols = [by] if isinstance(by, str) else list(by)
    if not by_cols:
        raise ConfigError("aggregate: by=[] names no column; expected at least one, e.g. 'agent'")
    for col in by_cols:
        if col not in df.columns:
            close = difflib.get_close_matches(col, [str(c) for c in df.columns], n=1)
            hint = f"; did you mean {close[0]!r}?" if close else ""
            msg = f"aggregate: by={col!r} is not a column of the results{hint}"
            raise ConfigError(msg)
    return by_cols


def _group_row(group: pd.DataFrame, outcomes: pd.Series, metrics: list[str],
               quality: list[str], over: str) -> dict[str, object]:
    """One group's counts and statistics, from its good rows (``group``, ``outcomes``)."""
    judged = group["success"].dropna() if "success" in metrics else pd.Series(dtype=float)
    n_success = int((judged == 1.0).sum())
    row: dict[str, object] = {"n_judged": len(judged), "n_success": n_success,
                              "success": f"{n_success}/{len(judged)}" if len(judged) else DASH}
    ran, full = outcomes.isin(_RAN), (outcomes == FULL_RUN).to_numpy()
    goal_less = not len(judged) and bool(ran.any())
    row["n_full_runs"] = int(full.sum()) if goal_less else 0
    row["n_ran"] = int(ran.sum()) if goal_less else 0
    row[FULL_RUNS] = f"{int(full.sum())}/{int(ran.sum())}" if goal_less else DASH
    for word in COUNTED_OUTCOMES:
        row[f"n_{word}"] = int((outcomes == word).sum())
    averaged = group
    if over == "success" and quality:  # the headline's episodes: successes, or full runs
        averaged = group[full if goal_less else (group["success"] == 1.0).to_numpy()]
    row["n_averaged"] = len(averaged)
    row["over"] = over
    means, stds = group.mean(skipna=True), group.std(ddof=1, skipna=True)
    q_means, q_stds = averaged.mean(skipna=True), averaged.std(ddof=1, skipna=True)
    for m in metrics:
        mean, std = (q_means, q_stds) if m in quality else (means, stds)
        row[f"{m}_mean"] = float(mean[m]) if len(group) else math.nan
        row[f"{m}_std"] = float(std[m]) if len(group) else math.nan
        if m in EPISODE_COUNTED:
            row[f"{m}_episodes"] = int((group[m] > 0).sum())
    return row


#: The normal quantile of a two-sided 95 % interval.
Z_95 = 1.959963984540054


def wilson_interval(successes: int, n: int, z: float = Z_95) -> tuple[float, float]:
    """Wilson score interval of a success rate ``successes/n`` (as statsmodels'
    ``proportion_confint(method="wilson")``): unlike the normal one it stays inside [0, 1]
    and says something at 0/n and n/n, where benchmark rows often sit. ``(nan, nan)`` for
    ``n == 0``."""
    if n <= 0:
        return math.nan, math.nan
    p = successes / n
    denom = 1.0 + z * z / n
    centre = (p + z * z / (2 * n)) / denom
    half = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / denom
    return max(0.0, centre - half), min(1.0, centre + half)


def bootstrap_interval(values: Sequence[float] | np.ndarray, *, resamples: int = 2000,
                       seed: int = 0, level: float = 0.95) -> tuple[float, float]:
    """Percentile bootstrap interval of the mean of ``values`` (NaN left out): ``resamples``
    resamples with replacement from a generator seeded with ``seed``, so a table is the same
    on every run. ``(nan, nan)`` without a value."""
    data = np.asarray(values, dtype=float)
    data = data[~np.isnan(data)]
    if not data.size:
        return math.nan, math.nan
    rng = np.random.default_rng(seed)
    means = data[rng.integers(0, data.size, (resamples, data.size))].mean(axis=1)
    tail = 100 * (1 - level) / 2
    low, high = np.percentile(means, [tail, 100 - tail])
    return float(low), float(high)
