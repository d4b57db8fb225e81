"""``benchmarks/crowd_throughput.py`` (30 people at >= 10 x real time: issue 41 item 1) ends
with its figures."""

from __future__ import annotations

from bench_helpers import read_results, run_benchmark


def test_the_crowd_benchmark_ends_with_its_figures() -> None:
    """A short run with 4 people: its figures, never a bound (the numbers belong to
    docs/performance.md)."""
    done = run_benchmark("crowd_throughput.py", "--people", "4", "--steps", "20",
                         "--repeat", "1")
    figures = read_results(done.stdout, ("crowd_empty_rtf", "crowd_ratio", "crowd_rtf_4"))
    assert figures["crowd_rtf_4"] > 0 and figures["crowd_empty_rtf"] > 0
