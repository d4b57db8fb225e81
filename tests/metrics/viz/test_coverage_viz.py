"""Exploration drawn (``viz.coverage_plot``): synthetic exploration bags (turning in place in a
4 m square room, seeing through a 90° sector ahead) give the report's coverage curves, per
agent the mean of its episodes with a band, and the videos' tint of the floor seen, inside the
seen sector and nowhere else; ``pic4rl-metrics plot`` draws the curves as a PNG."""

from __future__ import annotations

import math
import re
from pathlib import Path

import numpy as np
import pytest

from pic4rl_metrics.bags.reader import read_episode
from pic4rl_metrics.cli.commands import main
from pic4rl_metrics.synthetic.synthetic import cast_scan, write_episode_bag
from pic4rl_metrics.synthetic.synthetic_tracks import front_sector, square_room, turn_in_place
from pic4rl_metrics.viz.coverage_plot import ALPHA, SHADE, coverage_figure
from pic4rl_metrics.viz.video import EpisodeScene, VideoOptions

ROOM = square_room(4.0)  # free floor 16 m²


def _explore_bag(path: Path, agent: str, rate: float, duration_s: float = 14.0) -> Path:
    track = turn_in_place(rate, duration_s)
    scans = [front_sector(cast_scan(0.0, 0.0, yaw, ROOM, n_beams=720), math.pi / 2)
             for yaw in track.yaw]
    facts = {"task": "explore/lidar", "free_area_m2": 16.0, "agent": agent,
             "footprint": {"length_m": 0.5, "width_m": 0.4}}
    return write_episode_bag(path, track, scans=scans, facts=facts)


def _sector_pct(turned: float) -> float:
    """Coverage % of the room seen from its centre by a 90° sector turned ``turned`` rad
    (``test_coverage_metrics``'s closed form)."""
    full, part = divmod(min(turned, 1.5 * math.pi), math.pi / 2)
    return 100.0 * 4.0 * (1 + full + 0.5 * (math.tan(part - math.pi / 4) + 1)) / 16.0


def test_the_report_draws_each_agents_mean_coverage_and_spread(tmp_path: Path,
                                                               capsys) -> None:
    """fast turns a full circle in both episodes (100 % each, no spread); slow turns 3.5 and
    4.2 rad in 14 s (81.8 % and 92.3 %): its line ends at their mean, its band is wide."""
    bags = tmp_path / "bags"
    _explore_bag(bags / "fast_0", "fast", 0.5)
    _explore_bag(bags / "fast_1", "fast", 0.5)
    _explore_bag(bags / "slow_0", "slow", 0.25)
    _explore_bag(bags / "slow_1", "slow", 0.3)
    out = tmp_path / "report.html"
    assert main(["report", str(bags), "--out", str(out)]) == 0, capsys.readouterr().err
    text = out.read_text()
    section = re.search(r'<section id="sec-coverage">(.*?)</section>', text, re.DOTALL)
    assert section is not None, "no coverage section"
    svg = section.group(1)
    assert "coverage [%]" in svg and "fast (n = 2)" in svg and "slow (n = 2)" in svg
    finals = dict(re.findall(r'class="mean" data-agent="(\w+)" data-final="([\d.]+)"', svg))
    assert float(finals["fast"]) == pytest.approx(100.0, abs=0.01)
    slow = 0.5 * (_sector_pct(0.25 * 14.0) + _sector_pct(0.3 * 14.0))
    assert float(finals["slow"]) == pytest.approx(slow, abs=1.0)
    bands = dict(re.findall(r'class="spread" data-agent="(\w+)" points="([^"]+)"', svg))
    assert set(bands) == {"fast", "slow"}

    def width(points: str) -> float:  # the band's widest vertical extent (px)
        xy = np.array([p.split(",") for p in points.split()], float)
        half = len(xy) // 2
        return float(np.max(np.abs(xy[:half, 1] - xy[half:][::-1, 1])))

    assert width(bands["fast"]) < 0.5
    assert width(bands["slow"]) > 10.0


def test_a_navigation_report_has_no_coverage_section(tmp_path: Path, capsys) -> None:
    from pic4rl_metrics.synthetic.synthetic import straight_line
    bag = write_episode_bag(tmp_path / "bags" / "nav", straight_line(0.5, 4.0, 0.1),
                            obstacles=ROOM, n_beams=90, goal=(1.5, 0.0), outcome="goal",
                            facts={"agent": "td3", "start": [0.0, 0.0, 0.0], "goal": [1.5, 0.0]})
    out = tmp_path / "report.html"
    assert main(["report", str(bag.parent), "--out", str(out)]) == 0, capsys.readouterr().err
    assert 'id="sec-coverage"' not in out.read_text()


def test_a_video_frame_shades_the_seen_sector_and_nothing_else(tmp_path: Path) -> None:
    """At t = 1 s the sector has turned 0.5 rad (scans integrated up to 0.8 s at least): the
    floor at bearings in [-45°, 45° + 22.9°] is seen. Every tinted pixel lies there (or in the
    sensor's own cell), pixels well inside it are tinted, behind the robot none are."""
    episode = read_episode(_explore_bag(tmp_path / "ep", "fast", 0.5, 4.0), full_scans=True)
    scene = EpisodeScene(episode, VideoOptions(fps=10))
    frames = list(scene.frames())
    rr, cc = scene.map_box
    view = scene.map_view
    background = scene.background[rr, cc].astype(float)
    tinted = np.round((1 - ALPHA) * background + ALPHA * SHADE)
    k = 9  # t = 1.0 s
    assert scene.t_s[k] == pytest.approx(1.0)
    sub = frames[k][rr, cc].astype(float)
    shaded = (sub == tinted).all(axis=2) & (background != tinted).any(axis=2)
    rows, cols = np.nonzero(shaded)
    x = (cols + 0.5 - view.col0) / view.sx
    y = (view.row0 - (rows + 0.5)) / view.sy
    bearing = np.arctan2(y, x)
    tol_m = 0.05 + 2 * view.metres_per_pixel  # a cell, and a pixel's rounding either way
    near = np.hypot(x, y) <= 0.1 + tol_m
    in_room = (np.abs(x) <= 2 + tol_m) & (np.abs(y) <= 2 + tol_m)
    outside = np.maximum.reduce([np.zeros_like(x), -math.pi / 4 - bearing,
                                 bearing - (math.pi / 4 + 0.5)])  # rad beyond the sector
    in_sector = np.hypot(x, y) * np.sin(np.minimum(outside, math.pi / 2)) <= tol_m
    assert len(rows) > 1000
    assert (near | (in_room & in_sector)).all(), np.c_[x, y][~(near | (in_room & in_sector))][:5]

    def shaded_at(px: float, py: float) -> bool:
        col, row = (int(v) for v in view.pixels(px, py))
        return bool(shaded[row, col])

    assert shaded_at(1.2, 0.3) and shaded_at(0.6, 1.0)  # bearings 14° and 59°: ahead
    assert not shaded_at(-1.2, 0.3) and not shaded_at(0.3, -1.2)  # behind, and right of -45°
    last = frames[-1][rr, cc].astype(float)  # 4 s: 2 rad turned, more seen, none outside
    assert ((last == tinted).all(axis=2) & (background != tinted).any(axis=2)).sum() > len(rows)


def test_plot_draws_the_coverage_curves_as_a_figure(tmp_path: Path, capsys) -> None:
    """``pic4rl-metrics plot`` beside its comparison figure writes the same curves as a PNG:
    one line per agent, ending at its mean coverage; a navigation bag gets none."""
    bags = tmp_path / "bags"
    _explore_bag(bags / "fast_0", "fast", 0.5)
    _explore_bag(bags / "slow_0", "slow", 0.25)
    out = tmp_path / "plots"
    assert main(["plot", str(bags), "--out", str(out)]) == 0, capsys.readouterr().err
    assert (out / "coverage.png").stat().st_size > 10_000 and (out / "comparison.png").exists()
    episodes = [read_episode(bags / name) for name in ("fast_0", "slow_0")]
    fig = coverage_figure(episodes)
    assert fig is not None
    ax = fig.axes[0]
    assert ax.get_ylabel() == "coverage [%]"
    finals = {line.get_label(): line.get_ydata()[-1] for line in ax.get_lines()}
    assert finals["fast (n = 1)"] == pytest.approx(100.0, abs=0.01)
    assert finals["slow (n = 1)"] == pytest.approx(_sector_pct(0.25 * 14.0), abs=1.0)
    nav = write_episode_bag(tmp_path / "nav", turn_in_place(0.5, 2.0), obstacles=ROOM,
                            facts={"task": "goToPose/lidar"})
    assert coverage_figure([read_episode(nav)]) is None
