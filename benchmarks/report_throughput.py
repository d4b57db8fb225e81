"""How long ``pic4rl-metrics report`` takes on a 1,000-episode benchmark, and how long its page
takes to open in a browser.

The bags are a synthetic benchmark (``pic4rl_metrics.synthetic.synthetic_bench``: 5 agents × 100
start–goal pairs × 2 runs in a walled arena), shaped like sim episodes: ``/ground_truth`` and
``/odom`` at 20 Hz, ``/cmd_vel`` at 20 Hz, a 360-beam ``/scan`` at 10 Hz, facts and outcome.
Writing them is not timed. Side by side in this one process: ``compute`` alone (reading and
judging every bag), the page alone from that result (the statistics, the maps, the HTML:
the report's own cost) and the whole ``report`` command end to end, each its best of
``--repeat`` runs.
With Chromium and Selenium installed (``.ci/run`` installs them), the page is opened headless
``--repeat`` times and the best time to its ``load`` event is kept.

    .venv/bin/python benchmarks/report_throughput.py              # 1,000 episodes
    .venv/bin/python benchmarks/report_throughput.py --episodes 200 --jobs 1

The last lines are ``RESULT <name> <value>``, one per figure, for ``docs/performance.md``.
Targets (issue 30): the report in at most 60 s, the page loaded in at most 2 s.
"""

from __future__ import annotations

import argparse
import os
import shutil
import sys
import tempfile
import time
from pathlib import Path

from pic4rl_metrics import compute

from pic4rl_metrics.cli import commands as cli
from pic4rl_metrics.viz.html_report import write_report
from pic4rl_metrics.viz.report_maps import SKETCH_SCANS
from pic4rl_metrics.synthetic.synthetic_bench import write_benchmark

AGENTS = {"td3": 0.8, "sac": 0.7, "dwa": 0.5, "proportional": 0.4, "planner": 0.95}
RUNS = 2


def page_load_s(page: Path, repeat: int) -> float | None:
    """Best time (s) from navigation start to the page's load event in headless Chromium;
    None when Chromium, its driver or Selenium is missing."""
    try:
        from selenium import webdriver
        from selenium.webdriver.chrome.service import Service
    except ImportError:
        return None
    if not (shutil.which("chromium") and shutil.which("chromedriver")):
        return None
    best = float("inf")
    for _ in range(repeat):
        profile = tempfile.mkdtemp(prefix="report-browser-")
        options = webdriver.ChromeOptions()
        options.binary_location = shutil.which("chromium") or ""
        for flag in ("--headless", "--no-sandbox", "--disable-gpu", "--disable-quic",
                     "--no-first-run", "--disable-background-networking",
                     "--disable-component-update", "--disable-sync",
                     f"--user-data-dir={profile}"):
            options.add_argument(flag)
        driver = webdriver.Chrome(service=Service(shutil.which("chromedriver") or ""),
                                  options=options)
        try:
            driver.get(page.as_uri())
            ms = driver.execute_script(
                "return performance.getEntriesByType('navigation')[0].loadEventEnd")
            best = min(best, float(ms) / 1000)
        finally:
            driver.quit()
            shutil.rmtree(profile, ignore_errors=True)
    return best


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--episodes", type=int, default=1000, help="episodes (default 1000)")
    parser.add_argument("--jobs", type=int, default=os.cpu_count() or 1,
                        help="bags judged at once, both sides (default: the cores)")
    parser.add_argument("--repeat", type=int, default=2, help="runs of each side (default 2)")
    parser.add_argument("--keep", type=Path, help="write the bags and the page here, and keep "
                                                  "them (default: a temporary directory)")
    args = parser.parse_args(argv)
    pairs = max(1, args.episodes // (len(AGENTS) * RUNS))
    root = args.keep or Path(tempfile.mkdtemp(prefix="report-bench-"))
    try:
        start = time.perf_counter()
        bags = root / "bags"
        if not bags.exists():
            write_benchmark(bags, AGENTS, pairs=pairs, runs=RUNS, n_beams=360, dt_s=0.05,
                            scan_every=2)
        n = len(list(bags.rglob("metadata.yaml")))
        print(f"{n} bags in {bags} ({time.perf_counter() - start:.0f} s to write)",
              file=sys.stderr)
        page = root / "report.html"
        compute_s, page_s, report_s = float("inf"), float("inf"), float("inf")
        for _ in range(args.repeat):
            start = time.perf_counter()
            result = compute([bags], jobs=args.jobs, scan_sample=SKETCH_SCANS)
            compute_s = min(compute_s, time.perf_counter() - start)
            start = time.perf_counter()
            write_report(result, page, overwrite=True, references=["dwa"])
            page_s = min(page_s, time.perf_counter() - start)
            start = time.perf_counter()
            code = cli.main(["report", str(bags), "--out", str(page), "--force",
                             "--jobs", str(args.jobs), "--reference", "dwa",
                             "--no-progress"])
            report_s = min(report_s, time.perf_counter() - start)
            if code != 0:
                print(f"report exited {code}", file=sys.stderr)
                return 1
        load_s = page_load_s(page, args.repeat)
        print(f"\n| step | best of {args.repeat} [s] |\n|---|---:|\n"
              f"| compute ({n} bags, jobs={args.jobs}) | {compute_s:.2f} |\n"
              f"| the page alone, from compute's result (statistics, maps, HTML) | "
              f"{page_s:.2f} |\n"
              f"| report, end to end (compute + page) | {report_s:.2f} |\n"
              f"| page load in headless Chromium | "
              f"{'–' if load_s is None else f'{load_s:.3f}'} |\n")
        print(f"RESULT report_episodes {n}")
        print(f"RESULT report_compute_s {compute_s:.2f}")
        print(f"RESULT report_page_s {page_s:.2f}")
        print(f"RESULT report_build_s {report_s:.2f}")
        print(f"RESULT report_page_over_compute_ratio {page_s / compute_s:.3f}")
        print(f"RESULT report_html_mb {page.stat().st_size / 1e6:.2f}")
        if load_s is not None:
            print(f"RESULT report_page_load_s {load_s:.3f}")
    finally:
        if args.keep is None:
            shutil.rmtree(root, ignore_errors=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
