"""Row metrics against analytic answers: from the recorded centre line, from a line fitted to
the recorded scan (a bag of a real field without one), and NaN with its reason when neither
is there. The lane fit itself on exact points."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from metrics_helpers import row

from pic4rl_metrics.tables.results import ROW_COLUMNS, TABLE1_COLUMNS, table_columns
from pic4rl_metrics.core.crop_rows import LaneWindow, fit_lane, lane_deviations
from pic4rl_metrics.synthetic.synthetic import Obstacles, straight_line, write_episode_bag

HALF_M = 1.25  # half the lane's width: trunk centres at y = +-1.25
TRUNK_M = 0.05
#: Trunks every metre along both rows, from x = -3 to 16.
ROWS = Obstacles(circles=tuple((float(x), s * HALF_M, TRUNK_M)
                               for x in range(-3, 17) for s in (1, -1)))


def rows_points(offset_m: float, yaw: float, n: int = 20) -> tuple[np.ndarray, np.ndarray]:
    """Points of two straight rows at world y = +-1.25 (every 0.5 m from x = -1 to 4), seen
    from a robot at (0, offset_m) with heading ``yaw``, in its base frame."""
    wx = np.tile(np.linspace(-1.0, 4.0, n // 2 + 1), 2)
    wy = np.repeat([HALF_M, -HALF_M], n // 2 + 1)
    dx, dy = wx, wy - offset_m
    c, s = math.cos(yaw), math.sin(yaw)
    return c * dx + s * dy, -s * dx + c * dy


@pytest.mark.parametrize(("offset_m", "yaw"), [(0.0, 0.0), (0.3, 0.0), (-0.2, 0.15),
                                               (0.4, -0.2)])
def test_the_lane_fit_of_two_straight_rows(offset_m: float, yaw: float) -> None:
    x, y = rows_points(offset_m, yaw)
    fit = fit_lane(x, y)
    assert fit is not None
    assert fit.deviation_m == pytest.approx(offset_m, abs=1e-9)
    assert fit.heading_rad == pytest.approx(-yaw, abs=1e-9)
    assert fit.width_m == pytest.approx(2 * HALF_M / math.cos(yaw), abs=1e-9)  # along y


def test_one_row_seen_takes_the_last_width_and_none_gives_nothing() -> None:
    x, y = rows_points(0.3, 0.0)
    left = y > 0
    assert fit_lane(x[left], y[left]) is None  # no width known yet
    fit = fit_lane(x[left], y[left], width_m=2.5)
    assert fit is not None and fit.deviation_m == pytest.approx(0.3, abs=1e-9)
    assert fit_lane(np.zeros(0), np.zeros(0), width_m=2.5) is None
    # A nearest point beyond max_half_width_m is the next row out, seen through a gap.
    far = fit_lane(x[left], y[left] + 1.0, width_m=2.5, window=LaneWindow(max_half_width_m=1.8))
    assert far is None
    deviations = lane_deviations(np.vstack([x[left], x[left]]), np.vstack([y[left], y[left]]))
    assert np.isnan(deviations).all()  # never both rows: no width, no deviation


@pytest.mark.parametrize("offset_m", [0.2, -0.35])
def test_row_metrics_from_the_scan_of_a_parallel_drive(tmp_path: Path, offset_m: float) -> None:
    track = straight_line(0.5, 20.0, start=(0.0, offset_m, 0.0))
    bag = write_episode_bag(tmp_path / "row", track, obstacles=ROWS, n_beams=720,
                            facts={"task": "vineyard"})
    m = row(bag)
    assert m["row_reference"] == "scan"
    assert m["row_path_mae_m"] == pytest.approx(abs(offset_m), abs=2e-3)
    assert m["row_path_mse_m2"] == pytest.approx(offset_m**2, abs=2e-3)
    assert m["warnings"] == ""


def test_row_metrics_from_the_scan_of_a_slanted_drive(tmp_path: Path) -> None:
    # From y = -0.3 to y = 0.2 at a constant speed: |y| is linear in time, so its time mean is
    # (0.3^2 + 0.2^2) / (2 * 0.5) = 0.13 m and the mean of y^2 is (0.3^3 + 0.2^3) / (3 * 0.5).
    yaw = math.atan2(0.5, 10.0)
    track = straight_line(math.hypot(10.0, 0.5) / 20.0, 20.0, start=(0.0, -0.3, yaw))
    bag = write_episode_bag(tmp_path / "row", track, obstacles=ROWS, n_beams=720,
                            facts={"task": "vineyard"})
    m = row(bag)
    assert m["row_path_mae_m"] == pytest.approx(0.13, abs=3e-3)
    assert m["row_path_mse_m2"] == pytest.approx((0.027 + 0.008) / 1.5, abs=3e-3)


def test_the_recorded_centre_line_comes_first(tmp_path: Path) -> None:
    track = straight_line(0.5, 20.0, start=(0.0, 0.2, 0.0))
    facts = {"task": "vineyard", "row_centerline": [[0.0, 0.5], [12.0, 0.5]]}
    m = row(write_episode_bag(tmp_path / "row", track, obstacles=ROWS, facts=facts))
    assert m["row_reference"] == "centerline"
    assert m["row_path_mae_m"] == pytest.approx(0.3, abs=1e-9)  # from the line, not the rows


def test_no_centre_line_and_no_scan_is_a_nan_with_its_reason(tmp_path: Path) -> None:
    track = straight_line(0.5, 10.0)
    m = row(write_episode_bag(tmp_path / "row", track, facts={"task": "vineyard"}))
    assert math.isnan(m["row_path_mae_m"]) and math.isnan(m["row_path_mse_m2"])
    assert m["row_reference"] is None
    assert "row: no row_centerline fact and no scan: row_path_mae_m and row_path_mse_m2 NaN" \
        in m["warnings"]


def test_a_bag_of_another_task_gets_no_row_metrics_from_its_scan(tmp_path: Path) -> None:
    track = straight_line(0.5, 10.0, start=(0.0, 0.2, 0.0))
    m = row(write_episode_bag(tmp_path / "row", track, obstacles=ROWS,
                              facts={"task": "goToPose"}))
    assert math.isnan(m["row_path_mae_m"]) and "row:" not in m["warnings"]


def test_tables_show_the_row_metrics_when_an_episode_has_them() -> None:
    goto = pd.DataFrame({"success": [1.0], "row_path_mae_m": [math.nan]})
    assert table_columns(goto) == TABLE1_COLUMNS
    vineyard = pd.DataFrame({"success": [1.0, 0.0], "row_path_mae_m_mean": [0.1, math.nan],
                             "row_path_mse_m2_mean": [0.02, math.nan]})
    assert table_columns(vineyard) == TABLE1_COLUMNS + ROW_COLUMNS
