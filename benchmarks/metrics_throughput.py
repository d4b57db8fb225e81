"""Messages per second of ``pic4rl_metrics.compute`` against a plain ``rosbags`` read loop.

Both sides run in this one process on the same bags, interleaved (metrics, rosbags, metrics,
...), and each keeps its best (shortest) time of ``--repeat`` runs. The numerator of both
rates is the same: every message in the bags, of every topic. The metrics read only the
topics they need, so they may beat a loop that decodes every message; the target is a ratio
of at least 1.0.

    .venv/bin/python benchmarks/metrics_throughput.py            # sim-shaped bags (+ real ones)
    .venv/bin/python benchmarks/metrics_throughput.py --bags bags/example

The last lines are ``RESULT <name> <value>``, one per figure, for ``docs/performance.md``.
"""

from __future__ import annotations

import argparse
import math
import sys
import tempfile
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path

from rosbags.highlevel import AnyReader, AnyReaderError
from rosbags.rosbag2 import ReaderError
from rosbags.typesys import Stores, get_typestore

from pic4rl_metrics import compute
from pic4rl_metrics.bags.inputs import discover
from pic4rl_metrics.synthetic.synthetic import DEFAULT_T0_NS, Obstacles, circle, write_episode_bag

REPO = Path(__file__).resolve().parents[1]
#: Real-robot bags shared beside the repository (see their README); used when present.
REAL_BAGS = REPO.parent / "shared" / "real_bags"

#: A 12 m x 12 m walled arena with four cylinders clear of the circular tracks.
ARENA = Obstacles(
    circles=((6.0, 6.0, 0.5), (1.5, 1.5, 0.3), (10.5, 1.5, 0.3), (1.5, 10.5, 0.3)),
    segments=((0, 0, 12, 0), (12, 0, 12, 12), (12, 12, 0, 12), (0, 12, 0, 0)),
)
FOOTPRINT = {"length_m": 0.508, "width_m": 0.430}  # Clearpath Jackal, as in pic4rl_sim.engine.robot_specs


class BenchmarkError(Exception):
    """A bag the benchmark cannot use: one side fails on it."""


@dataclass(frozen=True)
class Throughput:
    """One run of the benchmark: the bags, and each side's best wall time (s)."""

    bags: int
    source: str
    messages: int  # in the bags, every topic: the numerator of both rates
    decoded: int  # by the rosbags loop
    skipped: int  # by the rosbags loop: types the typestore does not know
    repeat: int
    metrics_s: float
    rosbags_s: float

    @property
    def metrics_msgs_per_s(self) -> float:
        return self.messages / self.metrics_s

    @property
    def rosbags_msgs_per_s(self) -> float:
        return self.messages / self.rosbags_s

    @property
    def ratio(self) -> float:
        """Metrics messages/s over rosbags messages/s (> 1: the metrics are faster)."""
        return self.rosbags_s / self.metrics_s

    def report(self) -> str:
        """A small table, then one ``RESULT <name> <value>`` line per figure."""
        rows = (
            ("pic4rl_metrics.compute (jobs=1)", self.metrics_s, self.metrics_msgs_per_s),
            ("rosbags read + deserialize", self.rosbags_s, self.rosbags_msgs_per_s),
        )
        return "\n".join([
            f"bags: {self.bags} ({self.source})",
            f"messages: {self.messages} (the rosbags loop decodes {self.decoded} and skips "
            f"{self.skipped} of unknown type)",
            f"best of {self.repeat} run(s) per side, interleaved",
            "",
            f"{'side':34s} {'best s':>9s} {'messages/s':>12s}",
            *(f"{name:34s} {best:9.3f} {rate:12.0f}" for name, best, rate in rows),
            f"{'ratio (metrics / rosbags)':34s} {'':9s} {self.ratio:12.2f}",
            "",
            f"RESULT bags {self.bags}",
            f"RESULT messages {self.messages}",
            f"RESULT metrics_msgs_per_s {self.metrics_msgs_per_s:.0f}",
            f"RESULT rosbags_read_msgs_per_s {self.rosbags_msgs_per_s:.0f}",
            f"RESULT metrics_vs_rosbags_ratio {self.ratio:.2f}",
        ])  # fmt: skip


def write_sim_bags(
    out_dir: Path,
    episodes: int,
    duration_s: float,
    *,
    pose_hz: float = 20.0,
    scan_every: int = 2,
    n_beams: int = 360,
) -> list[Path]:
    """Sim-shaped episode bags in ``out_dir``: ``/ground_truth`` and ``/odom`` (Odometry) and
    ``/cmd_vel`` at ``pose_hz``, a ``n_beams``-beam ``/scan`` every ``scan_every``-th pose,
    plus goal, facts and outcome. Each episode drives a circle of its own radius and speed."""
    bags = []
    for k in range(episodes):
        radius_m, speed_mps = 2.5 + 0.1 * (k % 10), 0.3 + 0.02 * (k % 7)
        track = circle(radius_m, speed_mps, duration_s, 1.0 / pose_hz, center=(6.0, 6.0))
        goal = (round(float(track.x[-1]), 4), round(float(track.y[-1]), 4))
        facts = {
            "agent": "bench", "task": "goToPose", "world": "bench_arena", "robot": "jackal",
            "run": "metrics_throughput", "episode": str(k), "seed": k, "footprint": FOOTPRINT,
            "start": [float(track.x[0]), float(track.y[0]), float(track.yaw[0])],
            "goal": list(goal), "max_speed_mps": 1.0,
        }  # fmt: skip
        bags.append(write_episode_bag(
            out_dir / f"episode_{k:03d}", track, obstacles=ARENA, scan_every=scan_every,
            n_beams=n_beams, goal=goal, facts=facts, outcome="goal",
            t0_ns=DEFAULT_T0_NS + k * 3_600_000_000_000,
        ))  # fmt: skip
    return bags


def real_bags() -> list[Path]:
    """The shared real-robot bags, or none when they are not beside the repository."""
    return list(discover([REAL_BAGS]).bags) if REAL_BAGS.is_dir() else []


def message_count(bags: Sequence[Path]) -> int:
    """Messages in the bags, of every topic (the numerator of both rates)."""
    typestore = get_typestore(Stores.ROS2_JAZZY)
    total = 0
    for bag in bags:
        try:
            with AnyReader([bag], default_typestore=typestore) as reader:
                total += sum(c.msgcount for c in reader.connections)
        except (AnyReaderError, ReaderError, OSError) as err:
            msg = f"{str(bag)!r}: cannot open bag: {err}"
            raise BenchmarkError(msg) from err
    return total


def rosbags_read(bags: Sequence[Path]) -> tuple[int, int]:
    """The baseline: read and deserialize every message whose type the typestore knows.

    Returns (messages decoded, messages skipped for an unknown type).
    """
    typestore = get_typestore(Stores.ROS2_JAZZY)
    decoded = skipped = 0
    for bag in bags:
        try:
            with AnyReader([bag], default_typestore=typestore) as reader:
                fielddefs = reader.typestore.fielddefs
                known = [c for c in reader.connections if c.msgtype in fielddefs]
                skipped += sum(c.msgcount for c in reader.connections if c not in known)
                for conn, _, raw in reader.messages(connections=known):
                    reader.deserialize(raw, conn.msgtype)
                    decoded += 1
        except (AnyReaderError, ReaderError, OSError) as err:
            msg = f"{str(bag)!r}: rosbags cannot read it: {err}"
            raise BenchmarkError(msg) from err
    return decoded, skipped


def metrics_compute(bags: Sequence[Path]) -> int:
    """``pic4rl_metrics.compute`` on the bags (one job); returns the number of rows.

    An error row would make the comparison meaningless: it raises ``BenchmarkError``.
    """
    result = compute(bags, jobs=1)
    if result.failed:
        failed = result.failed
        msg = f"pic4rl_metrics.compute failed on {len(failed)} bag(s): {failed[0].error}"
        raise BenchmarkError(msg)
    return len(result.results)


def measure(bags: Sequence[Path], repeat: int, source: str) -> Throughput:
    """Best times of ``compute`` and of the rosbags loop over ``repeat`` interleaved runs."""
    messages = message_count(bags)
    print(f"{len(bags)} bags, {messages} messages; {repeat} run(s) per side", file=sys.stderr)
    best = {"metrics": math.inf, "rosbags": math.inf}
    counts: list[tuple[int, int]] = []
    sides: dict[str, Callable[[], object]] = {
        "metrics": lambda: metrics_compute(bags),
        "rosbags": lambda: counts.append(rosbags_read(bags)),
    }
    for i in range(repeat):
        for name, run in sides.items():
            start = time.perf_counter()
            run()
            elapsed = time.perf_counter() - start
            best[name] = min(best[name], elapsed)
            print(f"run {i + 1}/{repeat}: {name:8s} {elapsed:7.3f} s", file=sys.stderr)
    decoded, skipped = counts[-1]
    return Throughput(
        len(bags), source, messages, decoded, skipped, repeat, best["metrics"], best["rosbags"]
    )


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="benchmarks/metrics_throughput.py",
        description="Messages/s of pic4rl_metrics.compute and of a plain rosbags "
        "read-and-deserialize loop on the same bags, and their ratio.",
    )
    parser.add_argument(
        "--bags", nargs="+", metavar="PATH",
        help="bags to use instead of the synthetic set (and the real bags)",
    )  # fmt: skip
    parser.add_argument("--episodes", type=int, default=20, help="synthetic bags (default 20)")
    parser.add_argument(
        "--duration", type=float, default=60.0, metavar="S",
        help="seconds per synthetic episode (default 60)",
    )  # fmt: skip
    parser.add_argument(
        "--no-real", action="store_true", help=f"leave out the real-robot bags in {REAL_BAGS}"
    )
    parser.add_argument(
        "--repeat", type=int, default=3, metavar="N",
        help="runs per side; the best time counts (default 3)",
    )  # fmt: skip
    return parser


def _bags(args: argparse.Namespace, tmp: Path) -> tuple[list[Path], str]:
    """The bags to measure and a line saying what they are."""
    if args.bags:
        found = discover(args.bags)
        if found.unmatched:
            item, why = found.unmatched[0]
            msg = f"{item}: {why}"
            raise BenchmarkError(msg)
        return list(found.bags), "given with --bags"
    start = time.perf_counter()
    print(f"writing {args.episodes} synthetic bags of {args.duration:g} s", file=sys.stderr)
    bags = write_sim_bags(tmp, args.episodes, args.duration)
    print(f"  written in {time.perf_counter() - start:.1f} s", file=sys.stderr)
    real = [] if args.no_real else real_bags()
    real_note = f" + {len(real)} real-robot bags" if real else " (real-robot bags: no)"
    return bags + real, f"{args.episodes} synthetic x {args.duration:g} s{real_note}"


def main(argv: Sequence[str] | None = None) -> int:
    parser = _parser()
    args = parser.parse_args(argv)
    if args.repeat < 1 or args.episodes < 0 or not args.duration > 0:
        parser.error("need --repeat >= 1, --episodes >= 0 and --duration > 0")
    try:
        with tempfile.TemporaryDirectory(prefix="pic4rl_bench_") as tmp:
            bags, source = _bags(args, Path(tmp))
            if not bags:
                raise BenchmarkError("no bags to measure")
            result = measure(bags, args.repeat, source)
    except (BenchmarkError, OSError) as err:
        print(f"error: {err}", file=sys.stderr)
        return 1
    print(result.report())
    return 0


if __name__ == "__main__":
    sys.exit(main())
