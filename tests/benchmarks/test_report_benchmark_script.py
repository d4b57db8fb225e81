"""``benchmarks/report_throughput.py`` runs end to end on a tiny synthetic benchmark and ends with
its figures. Only the shape of the output is checked, never a speed."""

from __future__ import annotations

import math
import shutil

from bench_helpers import read_results, run_benchmark

FIGURES = ("report_episodes", "report_compute_s", "report_page_s", "report_build_s",
           "report_page_over_compute_ratio", "report_html_mb")


def test_a_small_run_ends_with_parseable_figures(tmp_path) -> None:
    done = run_benchmark("report_throughput.py", "--episodes", "10", "--repeat", "1",
                         "--jobs", "1", "--keep", str(tmp_path))
    try:
        import selenium  # noqa: F401
        browser = bool(shutil.which("chromium") and shutil.which("chromedriver"))
    except ImportError:
        browser = False
    expected = FIGURES + (("report_page_load_s",) if browser else ())
    figures = read_results(done.stdout, expected)
    assert figures["report_episodes"] == 10  # 5 agents × 1 pair × 2 runs
    assert all(math.isfinite(v) and v > 0 for v in figures.values()), figures
    assert (tmp_path / "report.html").read_text().startswith("<!DOCTYPE html>")
