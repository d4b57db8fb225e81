"""Peak memory and time of judging one long bag, and of its HTML report, against the bag's
length (issue 27, item 8; issue 37, item 5).

Each length is a real-robot-shaped log (``pic4rl_metrics.synthetic.synthetic.write_long_bag``: 50 Hz
odometry, 40 Hz scans of 720 beams), judged by ``pic4rl_metrics.compute``, and then made into a
page by ``pic4rl-metrics report``, each in a fresh subprocess that reports its own peak
resident memory (``VmHWM``: ``ru_maxrss`` would carry a large parent's across exec) and wall
time, so one run's memory never counts against the next. The baseline is the same subprocess
judging nothing (Python, numpy, pandas and rosbags imported).

    .venv/bin/python benchmarks/metrics_memory.py               # 1, 5, 15 min
    .venv/bin/python benchmarks/metrics_memory.py --long        # also 30 and 120 min
    .venv/bin/python benchmarks/metrics_memory.py --minutes 2 4

The last lines are ``RESULT <name> <value>``, one per figure, for ``docs/performance.md``.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
from pathlib import Path

from pic4rl_metrics.synthetic.synthetic import write_long_bag

#: Judges the bag given as argv[2] (none: only imports) with ``compute`` (argv[1] ``compute``)
#: or writes its report beside it (``report``), and prints its figures as JSON.
CHILD = """
import json, os, sys, time
from pic4rl_metrics import compute
start = time.perf_counter()
row = {}
if sys.argv[2:] and sys.argv[1] == "compute":
    row = compute(sys.argv[2:]).frame.iloc[0].to_dict()
elif sys.argv[2:]:
    from pic4rl_metrics.cli.commands import main
    out = sys.argv[2] + ".html"
    code = main(["report", sys.argv[2], "--out", out, "--force", "--no-progress"])
    row = {"error": "" if code == 0 else f"report exited {code}"}
    os.unlink(out)
hwm = next(int(line.split()[1]) for line in open("/proc/self/status") if line.startswith("VmHWM:"))
print(json.dumps({"peak_mb": hwm / 1024,
                  "s": time.perf_counter() - start, "error": row.get("error", ""),
                  "path_m": row.get("path_length_m")}))
"""


def judge(bag: Path | None, what: str = "compute") -> dict[str, float | str]:
    """The child's figures for ``bag`` (``None``: the baseline), ``what``: ``compute`` or
    ``report``."""
    args = [sys.executable, "-c", CHILD, what, *([str(bag)] if bag else [])]
    done = subprocess.run(args, check=True, capture_output=True, text=True)
    return json.loads(done.stdout.strip().splitlines()[-1])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--minutes", type=float, nargs="+", default=[1.0, 5.0, 15.0])
    parser.add_argument("--long", action="store_true", help="also 30 and 120 minutes")
    args = parser.parse_args()
    minutes = sorted(set(args.minutes) | ({30.0, 120.0} if args.long else set()))
    base = judge(None)
    print(f"baseline (imports only): {base['peak_mb']:.0f} MB")
    print(f"{'minutes':>8} {'bag MB':>8} {'peak MB':>8} {'s':>7} {'path m':>9} "
          f"{'report MB':>10} {'report s':>9}")
    results = []
    with tempfile.TemporaryDirectory(prefix="pic4rl-memory-") as tmp:
        for length in minutes:
            bag = write_long_bag(Path(tmp) / f"log_{length:g}min", length)
            size_mb = sum(f.stat().st_size for f in bag.iterdir()) / 2**20
            got, page = judge(bag), judge(bag, "report")
            if got["error"] or page["error"]:
                raise SystemExit(f"{length:g} min: {got['error'] or page['error']}")
            print(f"{length:>8g} {size_mb:>8.0f} {got['peak_mb']:>8.0f} {got['s']:>7.1f} "
                  f"{got['path_m']:>9.1f} {page['peak_mb']:>10.0f} {page['s']:>9.1f}",
                  flush=True)
            results.append((length, got, page))
            for part in bag.iterdir():
                part.unlink()
            bag.rmdir()
    print(f"RESULT metrics_memory_baseline_mb {base['peak_mb']:.0f}")
    for length, got, page in results:
        print(f"RESULT metrics_peak_mb_{length:g}min {got['peak_mb']:.0f}")
        print(f"RESULT metrics_s_{length:g}min {got['s']:.1f}")
        print(f"RESULT report_peak_mb_{length:g}min {page['peak_mb']:.0f}")
        print(f"RESULT report_s_{length:g}min {page['s']:.1f}")
    if len(results) > 1:
        (m0, first, page0), (m1, last, page1) = results[0], results[-1]
        growth = (last["peak_mb"] - first["peak_mb"]) / (m1 - m0)
        print(f"RESULT metrics_peak_mb_per_min {growth:.1f}")
        growth = (page1["peak_mb"] - page0["peak_mb"]) / (m1 - m0)
        print(f"RESULT report_peak_mb_per_min {growth:.1f}")


if __name__ == "__main__":
    main()
