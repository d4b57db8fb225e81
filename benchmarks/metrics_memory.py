"""Peak memory and time of judging one long bag, against the bag's length (issue 27, item 8).

Each length is a real-robot-shaped log (``pic4rl_metrics.testing.synthetic.write_long_bag``: 50 Hz
odometry, 40 Hz scans of 720 beams), judged by ``pic4rl_metrics.compute`` in a fresh
subprocess that reports its own peak resident memory (``VmHWM``: ``ru_maxrss`` would carry a
large parent's across exec) and wall time, so one length's memory never counts against the
next. The baseline is the same subprocess judging nothing (Python, numpy, pandas and rosbags imported).

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

from pic4rl_metrics.testing.synthetic import write_long_bag

#: Judges the bag given as argv[1] (none: only imports) and prints its figures as JSON.
CHILD = """
import json, sys, time
from pic4rl_metrics import compute
start = time.perf_counter()
row = compute(sys.argv[1:]).frame.iloc[0].to_dict() if sys.argv[1:] else {}
hwm = next(int(line.split()[1]) for line in open("/proc/self/status") if line.startswith("VmHWM:"))
print(json.dumps({"peak_mb": hwm / 1024,
                  "s": time.perf_counter() - start, "error": row.get("error", ""),
                  "path_m": row.get("path_length_m"), "n_scans": row.get("n_scans")}))
"""


def judge(bag: Path | None) -> dict[str, float | str]:
    """The child's figures for ``bag`` (``None``: the baseline)."""
    args = [sys.executable, "-c", CHILD, *([str(bag)] if bag else [])]
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
    print(f"{'minutes':>8} {'bag MB':>8} {'peak MB':>8} {'s':>7} {'path m':>9} {'scans':>7}")
    results = []
    with tempfile.TemporaryDirectory(prefix="pic4rl-memory-") as tmp:
        for length in minutes:
            bag = write_long_bag(Path(tmp) / f"log_{length:g}min", length)
            size_mb = sum(f.stat().st_size for f in bag.iterdir()) / 2**20
            got = judge(bag)
            if got["error"]:
                raise SystemExit(f"{length:g} min: {got['error']}")
            print(f"{length:>8g} {size_mb:>8.0f} {got['peak_mb']:>8.0f} {got['s']:>7.1f} "
                  f"{got['path_m']:>9.1f} {got['n_scans']:>7.0f}")
            results.append((length, got))
            for part in bag.iterdir():
                part.unlink()
            bag.rmdir()
    print(f"RESULT metrics_memory_baseline_mb {base['peak_mb']:.0f}")
    for length, got in results:
        print(f"RESULT metrics_peak_mb_{length:g}min {got['peak_mb']:.0f}")
        print(f"RESULT metrics_s_{length:g}min {got['s']:.1f}")
    if len(results) > 1:
        (m0, first), (m1, last) = results[0], results[-1]
        growth = (last["peak_mb"] - first["peak_mb"]) / (m1 - m0)
        print(f"RESULT metrics_peak_mb_per_min {growth:.1f}")


if __name__ == "__main__":
    main()
