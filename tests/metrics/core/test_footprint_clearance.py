"""With a footprint, the clearance from it (issue 37, item 11): ``obstacle_dist_*`` stay the raw
ranges (the paper's), ``footprint_clearance_min_m`` / ``_mean_m`` are measured from the
footprint's boundary — the range less the radius for a circle, less the half-length ahead and
the half-width to the side for a rectangle. Analytic answers on one beam per scan."""

from __future__ import annotations

import csv
import io
import math
from pathlib import Path

import numpy as np
import pytest

from pic4rl_metrics import compute
from pic4rl_metrics.cli.commands import main
from pic4rl_metrics.synthetic.synthetic import straight_line, write_episode_bag

from metrics_helpers import F32, JACKAL

N_BEAMS = 8  # from -pi by pi/4: beam 4 looks ahead (0 rad), beam 6 to the left (pi/2)


def _bag(tmp_path: Path, beam: int, footprint: dict | None) -> Path:
    """10 s at 10 Hz; one return per scan on ``beam``, from 2.0 m down to 1.0 m (0.01 m a
    scan), every other beam no return."""
    scans = []
    for i in range(101):
        ranges = np.full(N_BEAMS, np.inf, dtype=np.float32)
        ranges[beam] = 2.0 - 0.01 * i
        scans.append(ranges)
    facts = None if footprint is None else {"footprint": footprint}
    return write_episode_bag(tmp_path / f"bag{beam}", straight_line(0.0, 10.0), scans=scans,
                             n_beams=N_BEAMS, facts=facts)


@pytest.mark.parametrize(("beam", "footprint", "extent_m"), [
    (4, {"radius_m": 0.2}, 0.2),
    (6, {"radius_m": 0.2}, 0.2),
    (4, JACKAL, JACKAL["length_m"] / 2),  # ahead: the half-length, 0.254
    (6, JACKAL, JACKAL["width_m"] / 2),  # to the left: the half-width, 0.215
])
def test_clearance_is_the_range_less_the_footprint_along_the_beam(
        tmp_path: Path, beam: int, footprint: dict, extent_m: float) -> None:
    row = compute([_bag(tmp_path, beam, footprint)]).frame.iloc[0]
    assert row["error"] == ""
    assert row["obstacle_dist_min_m"] == pytest.approx(1.0, abs=F32)  # the raw range
    assert row["obstacle_dist_mean_m"] == pytest.approx(1.5, abs=F32)  # linear: the mid-value
    assert row["footprint_clearance_min_m"] == pytest.approx(1.0 - extent_m, abs=F32)
    assert row["footprint_clearance_mean_m"] == pytest.approx(1.5 - extent_m, abs=F32)


def test_without_a_footprint_there_is_no_clearance(tmp_path: Path) -> None:
    row = compute([_bag(tmp_path, 4, None)]).frame.iloc[0]
    assert row["obstacle_dist_min_m"] == pytest.approx(1.0, abs=F32)
    assert math.isnan(row["footprint_clearance_min_m"])
    assert math.isnan(row["footprint_clearance_mean_m"])


def test_the_footprint_option_gives_the_clearance_of_a_real_log(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    bag = _bag(tmp_path, 4, None)  # a log without facts: the footprint from the command line
    assert main(["compute", str(bag), "--footprint", "rect:0.5x0.4", "--format", "csv"]) == 0
    row = next(csv.DictReader(io.StringIO(capsys.readouterr().out)))
    assert float(row["footprint_clearance_min_m"]) == pytest.approx(0.75, abs=F32)
    assert float(row["obstacle_dist_min_m"]) == pytest.approx(1.0, abs=F32)
