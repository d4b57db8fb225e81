"""Paired statistics (``pic4rl_metrics.tables.paired``) against known answers, and ``compare
--paired`` end to end on real bags.

McNemar's exact p is checked against a published value (Fagerland, Lydersen & Laake 2013,
BMC Med Res Methodol 13:91, their example: b = 1, c = 7, exact conditional p = 0.070), against
a brute-force enumeration of every split of the discordant couples (no binomial formula), and
against scipy's binomial test when scipy is installed. The bootstrap interval's coverage is
measured on synthetic couples whose true difference is known.
"""

from __future__ import annotations

import io
import itertools
import json
import math
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from pic4rl_metrics.cli import commands as cli
from pic4rl_metrics.tables.paired import (
    NOT_DISTINGUISHABLE,
    cluster_bootstrap,
    mcnemar_exact,
    paired_diff,
    paired_table,
    seed_spread,
)


def _brute_force(b: int, c: int) -> float:
    """P(a split of the b + c discordant couples at least as uneven as (b, c)) when each
    couple goes either way with probability 1/2: every one of the 2^n splits enumerated."""
    n = b + c
    uneven = min(b, c)
    hits = sum(1 for split in itertools.product((0, 1), repeat=n)
               if min(sum(split), n - sum(split)) <= uneven)
    return hits / 2**n


def test_mcnemar_exact_matches_the_published_example() -> None:
    assert mcnemar_exact(1, 7) == pytest.approx(18 / 256)
    assert round(mcnemar_exact(1, 7), 3) == 0.070


@pytest.mark.parametrize(("b", "c"), [(0, 0), (0, 1), (0, 5), (5, 0), (1, 9), (3, 3), (2, 7),
                                      (4, 6), (6, 5), (0, 12)])
def test_mcnemar_exact_matches_an_enumeration(b: int, c: int) -> None:
    assert mcnemar_exact(b, c) == pytest.approx(min(1.0, _brute_force(b, c)), abs=1e-12)


def test_mcnemar_exact_matches_scipy_when_installed() -> None:
    stats = pytest.importorskip("scipy.stats", reason="scipy is not installed in this venv; "
                                "the enumeration and the published value check the formula")
    for b, c in [(1, 7), (10, 25), (40, 31), (0, 20)]:
        assert mcnemar_exact(b, c) == pytest.approx(stats.binomtest(b, b + c, 0.5).pvalue)


def test_mcnemar_rejects_negative_counts() -> None:
    with pytest.raises(ValueError, match="b=-1"):
        mcnemar_exact(-1, 3)


def test_bootstrap_interval_covers_the_true_difference_at_about_its_rate() -> None:
    """30 start–goal pairs of varying difficulty, 2 couples each; the agent succeeds with
    p_i, the reference with p_i − 0.15 (correlated on half the couples): the true difference
    is 0.15. The 95 % interval should hold it in about 95 % of 300 seeded experiments."""
    rng = np.random.default_rng(7)
    hits, n_exp = 0, 300
    for exp in range(n_exp):
        p = rng.uniform(0.2, 0.9, 30)
        pair = np.repeat(np.arange(30), 2)
        z = rng.random(60)
        shared = rng.random(60) < 0.5
        z_ref = np.where(shared, z, rng.random(60))
        s_a = (z < p[pair]).astype(float)
        s_r = (z_ref < p[pair] - 0.15).astype(float)
        low, high = cluster_bootstrap(s_a - s_r, pair, n_boot=1000, seed=exp)
        hits += low <= 0.15 <= high
    assert 0.90 <= hits / n_exp <= 0.985, hits / n_exp


def test_bootstrap_of_one_pair_resamples_the_couples_and_none_is_nan() -> None:
    low, high = cluster_bootstrap(np.array([1.0, 0.0, 1.0, 1.0]), np.zeros(4), seed=0)
    assert low < high
    assert all(math.isnan(v) for v in cluster_bootstrap(np.zeros(0), np.zeros(0)))


def _frame(rows: list[tuple[str, str | None, float, str]]) -> tuple[pd.DataFrame, pd.Series]:
    """(agent, pair, success, error) rows as a result frame and its pair labels."""
    frame = pd.DataFrame({"agent": [r[0] for r in rows], "run": "r0",
                          "success": [r[2] for r in rows], "error": [r[3] for r in rows],
                          "outcome": "goal"})
    return frame, pd.Series([r[1] for r in rows], dtype=object)


def test_unpaired_episodes_are_left_out_and_counted() -> None:
    """The agent on P1, P2, P3 (P3 never driven by the reference) and one episode without a
    pair; the reference twice on P1 (one repetition without a partner), once on P2 (an error
    row) and once on P4 with an unjudged success. One couple is left: P1's first."""
    frame, pairs = _frame([
        ("a", "P1", 1.0, ""), ("a", "P2", 1.0, ""), ("a", "P3", 0.0, ""), ("a", None, 1.0, ""),
        ("ref", "P1", 0.0, ""), ("ref", "P1", 1.0, ""), ("ref", "P2", math.nan, "BagError"),
        ("ref", "P4", math.nan, ""),
    ])
    d = paired_diff(frame, pairs, "a", "ref")
    assert (d.couples, d.pairs, d.b, d.c) == (1, 1, 1, 0)
    assert (d.unpaired_agent, d.unpaired_reference) == (3, 2)
    assert d.difference == 1.0 and d.p_value == 1.0 and d.verdict == NOT_DISTINGUISHABLE


def test_a_clear_difference_is_called() -> None:
    rows = [(agent, f"P{k}", s, "") for k in range(30)
            for agent, s in (("a", 1.0), ("ref", 0.0 if k % 5 else 1.0))]
    d = paired_diff(*_frame(rows), "a", "ref")
    assert (d.b, d.c, d.couples) == (24, 0, 30)
    assert d.p_value == pytest.approx(2 / 2**24)
    assert d.ci_low > 0 and d.verdict == "a better"


def test_references_default_to_every_pair_and_an_unknown_one_is_refused() -> None:
    frame, pairs = _frame([(a, "P1", 1.0, "") for a in ("x", "y", "z")])
    assert [(d.agent, d.reference) for d in paired_table(frame, pairs)] == [
        ("x", "y"), ("x", "z"), ("y", "z")]
    with pytest.raises(Exception, match="'w': no episode of that agent; the agents are x, y, z"):
        paired_table(frame, pairs, ["w"])


def test_seed_spread_is_the_success_rate_per_run() -> None:
    frame = pd.DataFrame({"agent": ["a"] * 4 + ["b"] * 2, "run": ["r0", "r0", "r1", "r1",
                                                                   "r0", "r0"],
                          "success": [1.0, 1.0, 1.0, 0.0, 1.0, 0.0], "error": ""})
    spread = seed_spread(frame)
    assert spread["agent"].tolist() == ["a"]  # b ran once: no spread
    row = spread.iloc[0]
    assert row["rates"] == [1.0, 0.5] and row["std"] == pytest.approx(math.sqrt(0.125))


def _cli(capsys: pytest.CaptureFixture[str], *args: object) -> tuple[int, str, str]:
    code = cli.main([str(a) for a in args])
    captured = capsys.readouterr()
    return code, captured.out, captured.err


def test_compare_paired_prints_the_differences(capsys, bench_bags: Path) -> None:
    code, out, _ = _cli(capsys, "compare", "--paired", "dwa", "--format", "json", bench_bags)
    assert code == 0
    records = json.loads(out)
    assert [(r["agent"], r["reference"]) for r in records] == [("planner", "dwa"), ("td3", "dwa")]
    frame = pd.read_csv(io.StringIO(_cli(capsys, "compute", "--format", "csv", bench_bags)[1]))
    for r in records:
        mine, ref = (frame[frame["agent"] == n].sort_values("bag") for n in (r["agent"], "dwa"))
        diff = mine["success"].to_numpy() - ref["success"].to_numpy()  # same pairs, same order
        assert r["couples"] == len(diff) and r["difference"] == pytest.approx(diff.mean())
        assert r["b"] == int((diff > 0).sum()) and r["c"] == int((diff < 0).sum())
        assert r["p_value"] == pytest.approx(mcnemar_exact(r["b"], r["c"]))
        assert r["ci_low"] <= r["difference"] <= r["ci_high"]
    code, out, _ = _cli(capsys, "compare", "--paired", "dwa", "--format", "markdown", bench_bags)
    assert code == 0 and out.startswith("| agent | reference | pairs | couples |")
    assert "McNemar p: exact" in out


@pytest.mark.bad_input
def test_compare_paired_with_an_unknown_reference_is_one_line_exit_2(capsys,
                                                                     bench_bags: Path) -> None:
    code, out, err = _cli(capsys, "compare", "--paired", "dwaa", bench_bags)
    assert code == 2 and out == ""
    assert err.strip().splitlines() == [
        "pic4rl-metrics: --paired/--reference 'dwaa': no episode of that agent; the agents "
        "are dwa, planner, td3"]
