"""Paired statistics of two agents on the episodes that share a start–goal pair (and world).

Two agents driven from the same start to the same goal face the same difficulty, so their
success difference is judged pair by pair: the i-th episode of agent A on a pair is matched
with the i-th episode of the reference on it (episodes in bag order: seeds, repetitions). An
episode without a partner — its pair never driven by the other, a repetition the other lacks,
an error row or an unjudged (aborted, unknown) partner — is left out and counted as unpaired.

On the matched couples: the success difference (mean of ``s_A − s_ref``), a percentile
bootstrap interval that resamples whole start–goal pairs (couples on one pair are not
independent), and McNemar's exact test on the discordant couples. Agents are compared within
one group only (``groups``: one task in one world set; ``grouped_paired``). ``compare
--paired`` prints these; the HTML report (``html_report``) shows them. Definitions in
``docs/metrics.md``.
"""

from __future__ import annotations

import json
import math
import textwrap
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
import pandas as pd

from pic4rl_base.errors import ConfigError

from .aggregate import _error_mask, _group_keys
from .groups import Group, join, split
from .layouts import check_format, render_rows

if TYPE_CHECKING:
    from .batch import BagResult, MetricsResult

#: Significance level of the verdict; the interval's coverage is ``1 − ALPHA``.
ALPHA = 0.05
#: Bootstrap resamples of an interval.
N_BOOT = 2000
NOT_DISTINGUISHABLE = "not distinguishable at this n"
#: Columns of ``render_paired``'s tables (and keys of its JSON records).
PAIRED_COLUMNS = ("agent", "reference", "pairs", "couples", "unpaired", "success",
                  "reference success", "difference", "95% CI", "b", "c", "McNemar p", "verdict")


def pair_key(result: BagResult) -> tuple[float, ...] | None:
    """The start–goal pair of a judged bag, to the centimetre (None: no goal or start)."""
    ep = result.episode
    if ep is None or ep.facts.goal is None:
        return None
    start = ep.facts.start[:2] if ep.facts.start is not None else (ep.pose.x[0], ep.pose.y[0])
    return tuple(round(float(v), 2) for v in (*start, *ep.facts.goal))


def pair_labels(result: MetricsResult) -> pd.Series:
    """Per row of ``result.frame``: ``<world> (sx, sy) → (gx, gy)``, or None (no pair known)."""
    labels = []
    for r in result.results:
        key = pair_key(r)
        world = (r.episode.facts.world if r.episode is not None else None) or "?"
        labels.append(None if key is None else
                      f"{world} ({key[0]:g}, {key[1]:g}) → ({key[2]:g}, {key[3]:g})")
    return pd.Series(labels, index=result.frame.index, dtype=object)


def mcnemar_exact(b: int, c: int) -> float:
    """Two-sided exact McNemar p-value: under H0 the ``b + c`` discordant couples split as a
    fair coin, ``p = min(1, 2 · P(X ≤ min(b, c)))`` with ``X ~ Binomial(b + c, 1/2)``; 1 when
    no couple is discordant."""
    if b < 0 or c < 0:
        raise ValueError(f"discordant counts must be >= 0, got b={b}, c={c}")
    n = b + c
    if n == 0:
        return 1.0
    tail = sum(math.comb(n, k) for k in range(min(b, c) + 1))
    return min(1.0, 2.0 * tail / 2.0**n)


def cluster_bootstrap(diffs: np.ndarray, clusters: np.ndarray, *, n_boot: int = N_BOOT,
                      seed: int = 0, level: float = 1 - ALPHA) -> tuple[float, float]:
    """Percentile interval of the mean of ``diffs``, resampling whole clusters (start–goal
    pairs) with replacement; with fewer than two clusters the couples themselves. NaN for no
    couple."""
    diffs = np.asarray(diffs, float)
    if diffs.size == 0:
        return math.nan, math.nan
    _, ids = np.unique(clusters, return_inverse=True)
    if ids.max(initial=0) < 1:
        ids = np.arange(diffs.size)
    sums = np.bincount(ids, weights=diffs)
    counts = np.bincount(ids).astype(float)
    rng = np.random.default_rng(seed)
    draw = rng.integers(0, sums.size, size=(n_boot, sums.size))
    means = sums[draw].sum(axis=1) / counts[draw].sum(axis=1)
    tail = (1 - level) / 2
    low, high = np.quantile(means, [tail, 1 - tail])
    return float(low), float(high)


@dataclass(frozen=True)
class PairedDiff:
    """Agent against reference on shared start–goal pairs (see the module)."""

    agent: str
    reference: str
    pairs: int  # start–goal pairs with at least one couple
    couples: int  # matched episodes
    unpaired_agent: int  # the agent's good episodes without a partner
    unpaired_reference: int
    success: float  # the agent's success rate over the couples
    reference_success: float
    difference: float  # success − reference_success
    ci_low: float
    ci_high: float
    b: int  # couples where the agent succeeded and the reference failed
    c: int  # and the other way round
    p_value: float

    @property
    def verdict(self) -> str:
        """Who is better, when the test and the interval agree; else not distinguishable."""
        apart = self.p_value < ALPHA and (self.ci_low > 0 or self.ci_high < 0)
        if not apart or self.couples == 0:
            return NOT_DISTINGUISHABLE
        return f"{self.agent if self.difference > 0 else self.reference} better"

    @property
    def unpaired(self) -> int:
        return self.unpaired_agent + self.unpaired_reference


def _couples(frame: pd.DataFrame, pairs: pd.Series, agent: str, reference: str
             ) -> tuple[list[tuple[float, float, object]], int, int]:
    """Matched (s_agent, s_ref, pair) couples, and each side's episodes left unpaired."""
    names = _group_keys(frame, ["agent"])["agent"]
    good = ~_error_mask(frame)
    success = pd.to_numeric(frame["success"], errors="coerce")
    sides: list[dict[object, list[float]]] = [{}, {}]
    for side, name in enumerate((agent, reference)):
        for i in frame.index[(names == name) & good]:
            sides[side].setdefault(pairs.get(i), []).append(float(success[i]))
    couples: list[tuple[float, float, object]] = []
    used = [0, 0]
    for key, mine in sides[0].items():
        theirs = sides[1].get(key, [])
        if key is None:
            continue
        for s_a, s_r in zip(mine, theirs):
            if not (math.isnan(s_a) or math.isnan(s_r)):
                couples.append((s_a, s_r, key))
                used[0] += 1
                used[1] += 1
    total = [sum(len(v) for v in side.values()) for side in sides]
    return couples, total[0] - used[0], total[1] - used[1]


def paired_diff(frame: pd.DataFrame, pairs: pd.Series, agent: str, reference: str, *,
                n_boot: int = N_BOOT, seed: int = 0) -> PairedDiff:
    """``agent`` against ``reference`` on the rows of ``frame`` (a result frame; ``pairs``:
    ``pair_labels``, aligned with it)."""
    couples, lone_a, lone_r = _couples(frame, pairs, agent, reference)
    s_a = np.array([c[0] for c in couples])
    s_r = np.array([c[1] for c in couples])
    keys = np.array([str(c[2]) for c in couples], dtype=object)
    b, c = int(((s_a == 1) & (s_r == 0)).sum()), int(((s_a == 0) & (s_r == 1)).sum())
    low, high = cluster_bootstrap(s_a - s_r, keys, n_boot=n_boot, seed=seed)
    n = len(couples)
    mean = (lambda v: float(v.mean()) if n else math.nan)
    return PairedDiff(agent, reference, len(set(keys)), n, lone_a, lone_r, mean(s_a), mean(s_r),
                      mean(s_a - s_r), low, high, b, c, mcnemar_exact(b, c))


def agent_names(frame: pd.DataFrame) -> list[str]:
    """The agents of a result frame (``agent``, else ``run``), in order of appearance."""
    names = _group_keys(frame, ["agent"])["agent"][~_error_mask(frame)]
    return [str(n) for n in dict.fromkeys(names)]


def paired_table(frame: pd.DataFrame, pairs: pd.Series,
                 references: Sequence[str] | None = None, *, n_boot: int = N_BOOT,
                 seed: int = 0) -> list[PairedDiff]:
    """Every agent against every reference (default: every pair of agents, once each, the
    later one as the reference; two references against each other once); ``ConfigError``
    naming a reference with no episode."""
    agents = agent_names(frame)
    if references is None:
        return [paired_diff(frame, pairs, a, r, n_boot=n_boot, seed=seed)
                for i, a in enumerate(agents) for r in agents[i + 1:]]
    _check_references(agents, references)
    chosen: dict[frozenset[str], tuple[str, str]] = {}
    for ref in references:  # two references against each other: once
        for a in agents:
            if a != ref:
                chosen.setdefault(frozenset((a, ref)), (a, ref))
    return [paired_diff(frame, pairs, a, r, n_boot=n_boot, seed=seed)
            for a, r in chosen.values()]


def _check_references(agents: Sequence[str], references: Sequence[str]) -> None:
    for ref in references:
        if ref not in agents:
            msg = (f"--paired/--reference {ref!r}: no episode of that agent; the agents are "
                   f"{', '.join(agents) or 'none'}")
            raise ConfigError(msg)


def grouped_paired(frame: pd.DataFrame, pairs: pd.Series,
                   references: Sequence[str] | None = None, *, n_boot: int = N_BOOT,
                   seed: int = 0) -> list[tuple[Group, list[PairedDiff]]]:
    """``paired_table`` within each group of ``frame`` (``groups.split``: one task in one
    world set), never across two: each group's agents against the ``references`` it has
    (``ConfigError`` for a reference with no episode at all)."""
    if references is not None:
        _check_references(agent_names(frame), references)
    out = []
    for group in split(frame):
        rows = frame.loc[list(group.rows)]
        mine = None if references is None else [r for r in references if r in agent_names(rows)]
        out.append((group, paired_table(rows, pairs.loc[rows.index], mine, n_boot=n_boot,
                                        seed=seed)))
    return out


def seed_spread(frame: pd.DataFrame) -> pd.DataFrame:
    """Per agent with episodes in two or more runs (seeds, repetitions): the success rate of
    each run, their mean, sample std, min and max. Columns ``agent``, ``runs``, ``rates``,
    ``mean``, ``std``, ``min``, ``max``."""
    keep = ~_error_mask(frame)
    sub = frame[keep]
    names = _group_keys(sub, ["agent"])["agent"]
    success = pd.to_numeric(sub["success"], errors="coerce")
    runs = sub["run"].astype(object).where(sub["run"].notna(), "?") if "run" in sub else None
    rows = []
    if runs is None:
        return pd.DataFrame(columns=["agent", "runs", "rates", "mean", "std", "min", "max"])
    for agent in dict.fromkeys(names):
        mine = success[names == agent]
        rates = mine.groupby(runs[names == agent], sort=False).mean().dropna()
        if len(rates) >= 2:
            rows.append({"agent": agent, "runs": len(rates), "rates": rates.round(3).tolist(),
                         "mean": rates.mean(), "std": rates.std(ddof=1), "min": rates.min(),
                         "max": rates.max()})
    return pd.DataFrame(rows, columns=["agent", "runs", "rates", "mean", "std", "min", "max"])


def _pct(value: float) -> str | None:
    return None if math.isnan(value) else f"{100 * value:.1f}%"


def paired_cells(d: PairedDiff) -> list[str | None]:
    """One comparison as text cells, in ``PAIRED_COLUMNS`` order."""
    ci = None if math.isnan(d.ci_low) else f"[{100 * d.ci_low:+.1f}, {100 * d.ci_high:+.1f}] pts"
    diff = None if math.isnan(d.difference) else f"{100 * d.difference:+.1f} pts"
    return [d.agent, d.reference, str(d.pairs), str(d.couples),
            f"{d.unpaired_agent} + {d.unpaired_reference}", _pct(d.success),
            _pct(d.reference_success), diff, ci, str(d.b), str(d.c), f"{d.p_value:.3g}",
            d.verdict]


def paired_record(d: PairedDiff) -> dict[str, object]:
    """One comparison as JSON values (rates and differences as fractions, NaN as null)."""
    def num(v: float) -> float | None:
        return None if math.isnan(v) else v
    return {"agent": d.agent, "reference": d.reference, "pairs": d.pairs, "couples": d.couples,
            "unpaired_agent": d.unpaired_agent, "unpaired_reference": d.unpaired_reference,
            "success": num(d.success), "reference_success": num(d.reference_success),
            "difference": num(d.difference), "ci_low": num(d.ci_low),
            "ci_high": num(d.ci_high), "b": d.b, "c": d.c, "p_value": d.p_value,
            "verdict": d.verdict}


def render_paired(result: MetricsResult, references: Sequence[str], fmt: str, *,
                  n_boot: int = N_BOOT, seed: int = 0) -> str:
    """``compare --paired``: every agent of ``result`` against each of ``references``, as
    text, markdown, CSV, LaTeX or JSON (numbers as fractions), with a note on what the
    columns mean below the text tables."""
    check_format(fmt)
    grouped = grouped_paired(result.frame, pair_labels(result), references, n_boot=n_boot,
                             seed=seed)
    shown = [(g, diffs) for g, diffs in grouped if diffs]  # groups with a comparison
    if fmt == "json":
        parts = [(g, json.dumps([paired_record(d) for d in diffs], allow_nan=False))
                 for g, diffs in shown]
    else:
        parts = [(g, render_rows(PAIRED_COLUMNS, [paired_cells(d) for d in diffs], fmt))
                 for g, diffs in shown]
    several = len(grouped) > 1
    text = join(parts, fmt, several=several) if parts else render_rows(PAIRED_COLUMNS, [], fmt)
    if fmt == "json" and not several:  # one group: the records as they always were
        text = json.dumps(json.loads(text), indent=2, allow_nan=False) + "\n"
    if fmt in ("table", "markdown"):
        note = (f"Within one task and world set, on episodes sharing a start–goal pair and "
                f"world; difference: success minus "
                f"the reference's; CI: percentile bootstrap over pairs ({n_boot} resamples); "
                "b, c: couples only the agent / only the reference succeeded in; McNemar p: "
                f"exact, two-sided; {NOT_DISTINGUISHABLE} unless p < {ALPHA} and the CI "
                "excludes 0; unpaired: agent + reference episodes without a partner, left out.")
        text += "\n" + textwrap.fill(note, 96) + "\n"
    return text
