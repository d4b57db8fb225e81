"""The report reads only the scans its maps draw (issue 37, item 5): a long log's scans are
summarized for the metrics and at most ``SKETCH_SCANS`` of them are kept whole, evenly spread,
so the report's memory stays bounded in the log's length (the figures: benchmarks/
metrics_memory.py, docs/performance.md)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from pic4rl_metrics.bags.reader import read_episode
from pic4rl_metrics.cli import commands as cli
from pic4rl_metrics.contract import EpisodeFacts
from pic4rl_metrics.core.scan_summary import ScanStream, ScanSummary
from pic4rl_metrics.synthetic.synthetic import write_long_bag
from pic4rl_metrics.viz.report_maps import SKETCH_POINTS, SKETCH_SCANS, sketch

MINUTES = 1.5  # 3,601 scans at 40 Hz, 4,501 poses at 50 Hz
N_SCANS = int(MINUTES * 60 * 40) + 1


@pytest.fixture(scope="module")
def long_bag(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return write_long_bag(tmp_path_factory.mktemp("long") / "log", MINUTES)


def test_the_report_keeps_at_most_60_scans_and_1500_points_of_a_long_log(
        long_bag: Path, tmp_path: Path) -> None:
    args = cli.build_parser().parse_args(["report", str(long_bag), "--out",
                                          str(tmp_path / "r.html")])
    result = cli._run(args)
    (row,) = result.results
    scan = row.episode.scan
    # the metrics still see every scan, as their summary; the map only a bounded sample
    assert isinstance(scan, ScanSummary) and len(scan) == N_SCANS
    assert scan.sample is not None and SKETCH_SCANS // 2 <= len(scan.sample) <= SKETCH_SCANS == 60
    # evenly spread over the whole log: scans 0, 64, 128, ... of 3,601 at 40 Hz (1.6 s apart)
    t = (scan.sample.t_ns - scan.t_ns[0]) / 1e9
    assert t[0] == 0.0 and len(t) == 57
    np.testing.assert_allclose(np.diff(t), 1.6, atol=1e-6)
    drawn = sketch(row.episode, row.metrics.outcome)
    assert 0 < len(drawn.returns) <= SKETCH_POINTS == 1500
    # every return lies within the wall's reach (2 + 0.5 sin t m) of the path along +x
    x, y = drawn.returns.T
    assert np.all(np.abs(y) <= 2.5 + 1e-4)
    assert x.min() >= -2.5 - 1e-4 and x.max() <= 0.5 * MINUTES * 60 + 2.5 + 1e-4


def test_the_sample_changes_no_metric(long_bag: Path) -> None:
    from pic4rl_metrics.core.metrics import compute_metrics

    plain, sampled = read_episode(long_bag), read_episode(long_bag, scan_sample=SKETCH_SCANS)
    assert plain.scan.sample is None
    a, b = compute_metrics(plain), compute_metrics(sampled)
    assert a.obstacle_dist_min_m == pytest.approx(1.5, abs=1e-3)
    for name in ("obstacle_dist_min_m", "obstacle_dist_mean_m", "path_length_m"):
        assert getattr(a, name) == getattr(b, name)


def test_the_stream_never_holds_more_than_twice_the_sample() -> None:
    stream = ScanStream(EpisodeFacts(), sample=60)
    row = (np.ones(4, np.float32), 0.0, 0.1, 0.05, 10.0)
    most = 0
    for _ in range(100_000):
        stream.append(row)
        most = max(most, len(stream._kept))
    assert most <= 120
    kept = [i for i, _ in stream._kept]
    # what is held is every stride-th scan since the first: even, and covering the stream
    stride = np.diff(kept)[0]
    assert len(set(np.diff(kept))) == 1 and kept[0] == 0 and kept[-1] > 100_000 - 2 * stride
    summary = stream.finish(np.arange(100_000, dtype=np.int64), np.arange(100_000))
    assert len(summary) == 100_000 and 30 <= len(summary.sample) <= 60
    np.testing.assert_array_equal(np.diff(summary.sample.t_ns), np.diff(summary.sample.t_ns)[0])
