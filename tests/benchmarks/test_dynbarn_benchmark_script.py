"""``benchmarks/dynbarn_throughput.py`` (the dynamic BARN's real-time factor with the LiDAR:
issue 41 item 2) ends with its figures."""

from __future__ import annotations

from bench_helpers import read_results, run_benchmark


def test_the_dynbarn_benchmark_ends_with_its_figures() -> None:
    """A short run with 4 moving obstacles: its figures, never a bound (the numbers belong to
    docs/performance.md)."""
    done = run_benchmark("dynbarn_throughput.py", "--moving", "4", "--steps", "20",
                         "--repeat", "1")
    figures = read_results(done.stdout, ("dynbarn_still_rtf", "dynbarn_ratio", "dynbarn_rtf"))
    assert figures["dynbarn_rtf"] > 0 and figures["dynbarn_still_rtf"] > 0
