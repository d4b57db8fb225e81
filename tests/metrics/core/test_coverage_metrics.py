"""Exploration metrics against analytic answers, at the grid's 0.05 m cells (``tasks.seen``).

Worlds: a 4 m square room centred on the origin (free floor 16 m², walls on cell edges, so a
LiDAR seeing all of it counts exactly 6400 cells) and a 2 m wide corridor open at both ends.
The synthetic LiDAR has 720 beams and a 10 m range."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from metrics_helpers import row

from pic4rl_base.seen_area import SeenGrid
from pic4rl_metrics.bags.reader import read_episode
from pic4rl_metrics.core import scan_summary
from pic4rl_metrics.core.derived import Derived
from pic4rl_metrics.synthetic.synthetic import cast_scan, straight_line, write_episode_bag
from pic4rl_metrics.synthetic.synthetic_tracks import (
    corridor,
    front_sector,
    square_room,
    turn_in_place,
)

EXPLORE = {"task": "explore/lidar", "free_area_m2": 16.0}
ROOM = square_room(4.0)
BEAMS = 720
RATE = 0.5  # rad/s
COLUMNS = ("area_seen_m2", "coverage_pct", "time_to_50pct_s", "time_to_90pct_s",
           "path_per_area_seen_mpm2")


def _sector_bag(path: Path, **facts: object) -> Path:
    """Turning in place at 0.5 rad/s for 14 s (a full turn and more) in the room, seeing
    through a 90 degree sector ahead."""
    track = turn_in_place(RATE, 14.0)
    scans = [front_sector(cast_scan(0.0, 0.0, yaw, ROOM, n_beams=BEAMS), math.pi / 2)
             for yaw in track.yaw]
    return write_episode_bag(path, track, scans=scans, facts={**EXPLORE, **facts})


def _sector_area(turned: np.ndarray) -> np.ndarray:
    """The room's floor (half-side h = 2 m) within the sector [-45°, 45° + turned] seen from
    the centre: a wall seen from bearing a to b (from its normal) is a triangle of area
    h²/2 (tan b - tan a), so the first wall gives h², each later one up to h² more."""
    h2 = 4.0
    full, part = np.divmod(np.minimum(turned, 1.5 * math.pi), math.pi / 2)
    return h2 * (1 + full) + 0.5 * h2 * (np.tan(part - math.pi / 4) + 1)


def test_turning_in_place_with_a_full_circle_lidar_sees_the_room_at_once(tmp_path: Path) -> None:
    """The first scan sees every cell of the room: 16 m² exactly, 100 %, both times 0, and
    no path."""
    track = turn_in_place(RATE, 5.0)
    m = row(write_episode_bag(tmp_path / "room", track, obstacles=ROOM, n_beams=BEAMS,
                              facts=EXPLORE))
    assert m["area_seen_m2"] == pytest.approx(16.0, abs=1e-9)
    assert m["coverage_pct"] == pytest.approx(100.0, abs=1e-7)
    assert m["time_to_50pct_s"] == m["time_to_90pct_s"] == 0.0
    assert m["path_per_area_seen_mpm2"] == 0.0


def test_turning_in_place_with_a_sector_sweeps_the_room_wall_by_wall(tmp_path: Path) -> None:
    """90° ahead, turning at 0.5 rad/s: a quarter at once, half after a quarter turn
    (t50 = (π/2) / 0.5 = 3.142 s), 90 % (14.4 m²) after π + π/4 + atan(0.2) turned (8.249 s),
    all after 1.5 π. Scans are integrated every 10° or more of turn (four 2.86° steps), so a
    time is late by at most one 0.4 s interval."""
    bag = _sector_bag(tmp_path / "sector")
    m = row(bag)
    assert m["area_seen_m2"] == pytest.approx(16.0, abs=1e-9)
    assert m["coverage_pct"] == pytest.approx(100.0, abs=1e-7)
    assert 0.5 * math.pi / RATE <= m["time_to_50pct_s"] <= 0.5 * math.pi / RATE + 0.4
    t90 = (1.25 * math.pi + math.atan(0.2)) / RATE
    assert t90 - 0.1 <= m["time_to_90pct_s"] <= t90 + 0.4
    curve = Derived(read_episode(bag)).seen
    assert curve is not None and curve.resolution_m == 0.05
    turned = RATE * (curve.t_ns - curve.t_ns[0]) * 1e-9
    step = 4 * RATE * 0.1  # the turn between scans integrated
    assert (curve.area_m2 >= _sector_area(np.maximum(turned - step, 0)) - 0.15).all()
    assert (curve.area_m2 <= _sector_area(turned) + 0.15).all()


def test_a_straight_corridor_is_seen_at_width_times_speed(tmp_path: Path) -> None:
    """Down a 2 m corridor at 0.5 m/s for 20 s, the LiDAR reaching 10 m both ways: at each
    pose the floor within 10 m, A0 = 2 (h √(R² − h²) + R² asin(h/R)) = 39.933 m² (h = 1,
    R = 10), then growing at width × speed = 1 m²/s to 59.933 m². Without a free-area fact
    the times are of that final area: 50 % at once, 90 % at (0.9 · 59.933 − A0) / 1 = 14.01 s.
    Path per area seen 10 / 59.933 m/m²; no coverage percentage."""
    a0 = 2 * (math.sqrt(99.0) + 100.0 * math.asin(0.1))
    bag = write_episode_bag(tmp_path / "corridor", straight_line(0.5, 20.0),
                            obstacles=corridor(-15.0, 40.0, 2.0), n_beams=BEAMS,
                            facts={"task": "explore"})
    m = row(bag)
    assert m["area_seen_m2"] == pytest.approx(a0 + 20.0, rel=2e-3)
    assert math.isnan(m["coverage_pct"])
    assert m["time_to_50pct_s"] == 0.0
    assert m["time_to_90pct_s"] == pytest.approx((0.9 * (a0 + 20.0) - a0) / 1.0, abs=0.45)
    assert m["path_per_area_seen_mpm2"] == pytest.approx(10.0 / (a0 + 20.0), rel=2e-3)
    curve = Derived(read_episode(bag)).seen
    assert curve is not None
    t_s = (curve.t_ns - curve.t_ns[0]) * 1e-9
    slope, start = np.polyfit(t_s, curve.area_m2, 1)
    assert slope == pytest.approx(1.0, rel=1e-2)
    assert a0 - 0.45 <= start <= a0 + 0.05  # a staircase: a scan integrated every 0.2 m


def test_the_reader_s_stream_and_the_whole_scans_agree(tmp_path: Path,
                                                       monkeypatch: pytest.MonkeyPatch) -> None:
    """Integrated while read in chunks of 16 scans (memory: the grid and a count a scan)
    or from every beam kept: the same columns, to the bit."""
    bag = _sector_bag(tmp_path / "sector")
    whole = row(bag, full_scans=True)
    monkeypatch.setattr(scan_summary, "CHUNK", 16)
    streamed = row(bag)
    assert [streamed[c] for c in COLUMNS] == [whole[c] for c in COLUMNS]


def test_other_tasks_get_no_area_columns(tmp_path: Path) -> None:
    """A navigation episode's scans are not integrated: every area column is NaN (so tables
    leave them out), even with a free-area fact."""
    m = row(_sector_bag(tmp_path / "nav", task="goToPose/lidar"))
    assert all(math.isnan(m[c]) for c in COLUMNS)


def test_the_grid_grows_in_every_direction_and_counts_each_cell_once() -> None:
    """A 10 m disk seen from (-20, -20) then (20, 20): two disks of π·100 m², each within
    half a cell's ring of the exact area; seeing one again adds nothing."""
    grid = SeenGrid(0.05)
    bearing = np.linspace(-math.pi, math.pi, 720, endpoint=False)
    first = grid.add(-20.0, -20.0, 0.3, bearing, np.full(720, 10.0))
    second = grid.add(20.0, 20.0, -1.0, bearing, np.full(720, 10.0))
    assert first * 0.0025 == pytest.approx(100 * math.pi, abs=2 * math.pi * 10 * 0.025)
    assert second == first
    assert grid.add(-20.0, -20.0, 2.0, bearing, np.full(720, 10.0)) == 0
    assert grid.area_m2 == pytest.approx(2 * first * 0.0025)


def test_tables_show_the_area_columns_only_where_an_episode_explores(tmp_path: Path) -> None:
    """Their comparison section (``explore``) and ``compute``'s view show them only when some
    episode has a value: a navigation table stays as it was."""
    from pic4rl_metrics import compute
    from pic4rl_metrics.tables.results import table_columns
    from pic4rl_metrics.tables.text import render_episodes
    nav = compute([_sector_bag(tmp_path / "nav", task="goToPose/lidar")]).frame
    both = compute([_sector_bag(tmp_path / "explore"), tmp_path / "nav"]).frame
    assert not set(COLUMNS) & set(table_columns(nav))
    assert set(COLUMNS) <= set(table_columns(both))
    assert "area seen" not in render_episodes(nav, "table")
    assert "area seen" in render_episodes(both, "table")


def test_scans_are_placed_through_the_lidar_s_mount(tmp_path: Path) -> None:
    """A robot standing in the 2 m corridor heading along it, its 90° sensor mounted 0.5 m
    ahead and turned to the left wall (``scan_mount`` yaw π/2): it sees the triangle up to
    that wall, h²/2 (tan 45° − tan −45°) = 1 m² with h = 1 m, plus the 40 cells whose centres
    lie on its 45° edges, half outside (0.05 m²); read without the mount it would look down
    the corridor (tens of m²)."""
    track = turn_in_place(0.0, 2.0)
    scans = [front_sector(cast_scan(0.5, 0.0, math.pi / 2, corridor(-15.0, 40.0, 2.0),
                                    n_beams=BEAMS), math.pi / 2) for _ in track.t_s]
    mount = {"x_m": 0.5, "y_m": 0.0, "yaw_rad": math.pi / 2}
    m = row(write_episode_bag(tmp_path / "mounted", track, scans=scans,
                              facts={"task": "explore", "scan_mount": mount}))
    assert m["area_seen_m2"] == pytest.approx(1.05, abs=0.01)
