"""``benchmarks/metrics_memory.py`` (a long log judged, and reported, in bounded memory: issue 27
item 8, issue 37 item 5) ends with its figures."""

from __future__ import annotations

from bench_helpers import read_results, run_benchmark


def test_the_memory_benchmark_ends_with_its_figures() -> None:
    """``benchmarks/metrics_memory.py`` on two tiny lengths: its figures, never a bound (the
    numbers belong to docs/performance.md)."""
    done = run_benchmark("metrics_memory.py", "--minutes", "0.05", "0.1")
    figures = read_results(done.stdout, (
        "metrics_memory_baseline_mb", "metrics_peak_mb_0.05min", "metrics_s_0.05min",
        "report_peak_mb_0.05min", "report_s_0.05min", "metrics_peak_mb_0.1min",
        "metrics_s_0.1min", "report_peak_mb_0.1min", "report_s_0.1min",
        "metrics_peak_mb_per_min", "report_peak_mb_per_min"))
    assert figures["metrics_peak_mb_0.1min"] >= figures["metrics_memory_baseline_mb"] > 0
    assert figures["report_peak_mb_0.1min"] >= figures["metrics_memory_baseline_mb"]
    assert figures["report_s_0.1min"] > 0
