"""Person-monitoring metrics against analytic answers: the robot drives 0.5 m/s along +x for
10 s at 10 Hz (``LINE``), the person walks a known line, the desired distance and the
camera's field of view come from the facts."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from metrics_helpers import EXACT, LINE
from metrics_helpers import row as _row

from pic4rl_metrics import compute
from pic4rl_metrics.synthetic.synthetic import Track, straight_line, write_episode_bag

FACTS = {"person_distance_m": 2.0, "camera_fov_rad": math.pi / 2}


def _person(x: np.ndarray, y: np.ndarray) -> Track:
    zeros = np.zeros_like(LINE.t_s)
    return Track(LINE.t_s, x, y, zeros, zeros, zeros, zeros)


def test_a_person_walking_away_ahead(tmp_path: Path) -> None:
    """Ahead at 1 + 0.2 t m: bearing 0, in view throughout, distance 1 -> 3 m (mean 2), and
    |d - 2| = |0.2 t - 1| is two triangles of area 2.5 over 10 s: MAE 0.5 m."""
    person = straight_line(0.7, 10.0, start=(1.0, 0.0, 0.0))
    m = _row(write_episode_bag(tmp_path / "away", LINE, person=person, facts=FACTS))
    assert m["follow_heading_mae_rad"] == pytest.approx(0.0, abs=EXACT)
    assert m["person_in_view_fraction"] == 1.0
    assert m["person_dist_mean_m"] == pytest.approx(2.0, abs=1e-9)
    assert m["person_dist_error_mae_m"] == pytest.approx(0.5, abs=1e-9)


def test_a_person_drifting_out_of_view(tmp_path: Path) -> None:
    """1 m ahead and 0.2 t + 0.01 m to the left: the bearing atan(0.2 t + 0.01) passes the
    90 degree field's edge (45 degrees) at t = 4.95 s, so the samples at 0.0 ... 4.9 s, each
    holding 0.1 s, are in view: 5.0 s of 10 s. The bearing's max is atan(2.01) at 10 s."""
    y = 0.2 * LINE.t_s + 0.01
    m = _row(write_episode_bag(tmp_path / "drift", LINE, person=_person(LINE.x + 1.0, y),
                               facts=FACTS))
    assert m["person_in_view_fraction"] == pytest.approx(0.5, abs=EXACT)
    assert m["follow_heading_max_rad"] == pytest.approx(math.atan(2.01), abs=1e-12)
    bearing = np.arctan(y)
    assert m["follow_heading_rmse_rad"] == pytest.approx(
        math.sqrt(np.trapezoid(bearing**2, LINE.t_s) / 10.0), abs=1e-12)
    wide = _row(write_episode_bag(tmp_path / "wide", LINE, person=_person(LINE.x + 1.0, y),
                                  facts={**FACTS, "camera_fov_rad": math.pi}))
    assert wide["person_in_view_fraction"] == 1.0  # atan(2.01) < 90 degrees


def test_without_the_facts_the_judged_columns_are_nan_with_a_reason(tmp_path: Path) -> None:
    person = straight_line(0.5, 10.0, start=(2.0, 0.0, 0.0))
    bag = write_episode_bag(tmp_path / "bare", LINE, person=person)
    result = compute([bag], metrics=["person_in_view_fraction", "person_dist_error_mae_m",
                                     "person_dist_mean_m"])
    row = result.frame.iloc[0]
    assert math.isnan(row["person_in_view_fraction"])
    assert math.isnan(row["person_dist_error_mae_m"])
    assert row["person_dist_mean_m"] == pytest.approx(2.0, abs=1e-9)
    assert "camera_fov" in row["warnings"] and "person_distance" in row["warnings"]
