"""Plots drawn from episodes built in memory: geometry of scan points, artists, files."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from matplotlib.figure import Figure

from pic4rl_base.errors import ConfigError
from pic4rl_base.geometry import Footprint
from pic4rl_metrics.contract import EpisodeFacts, Outcome
from pic4rl_metrics.core.series import CmdSeries, Episode, PoseSeries, ScanSeries
from pic4rl_metrics.tables.results import METRIC_COLUMNS, EpisodeMetrics
from pic4rl_metrics.viz.plots import (episode_figure, plot_acceleration_profile, plot_trajectory,
                                      plot_velocity_profile, save_figure, scan_points_world,
                                      trajectories_figure)

T0 = 1_700_000_000_000_000_000  # an epoch-like stamp (ns), where float64 would lose ns
PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


def make_scan(t_ns, ranges, angles, range_max=10.0) -> ScanSeries:
    ranges = np.atleast_2d(np.asarray(ranges, float))
    angles = np.broadcast_to(np.asarray(angles, float), ranges.shape).copy()
    n = len(ranges)
    return ScanSeries(np.asarray(t_ns, np.int64), ranges, angles,
                      np.full(n, 0.1), np.full(n, range_max))


def wall_episode(*, agent: str | None = "dwa", outcome=Outcome.GOAL, bag="run_0",
                 speed=0.5, cmd=True) -> Episode:
    """Robot driving along x at y=0 for 8 s; a wall at y=2 seen by a 181-beam scan."""
    t = T0 + np.arange(81, dtype=np.int64) * 100_000_000
    x = speed * np.arange(81) * 0.1
    pose = PoseSeries(t, x, np.zeros(81), np.zeros(81))
    bearings = np.linspace(0.2, math.pi - 0.2, 181)
    ranges = 2.0 / np.sin(bearings)  # distance to the line y = 2 from a point on y = 0
    ranges[ranges > 10.0] = np.inf
    ts = t[::5]
    scan = make_scan(ts, np.tile(ranges, (len(ts), 1)), bearings)
    cmds = CmdSeries(t[::10], np.full(9, speed), np.zeros(9), np.zeros(9)) if cmd else None
    facts = EpisodeFacts(agent=agent, start=(0.0, 0.0, 0.0), goal=(4.0, 0.0),
                         footprint=Footprint(radius_m=0.2), outcome=outcome)
    return Episode(Path(f"/bags/{bag}"), facts, pose, "/odom", scan=scan, cmd=cmds)


def metrics_for(outcome: str = "goal") -> EpisodeMetrics:
    values = {name: 1.0 for name in METRIC_COLUMNS}
    values.update(outcome=outcome, n_poses=81, n_scans=17, obstacle_dist_min_m=float("nan"))
    return EpisodeMetrics(**values)


def test_single_beam_placed_at_rotated_pose():
    pose = PoseSeries(np.array([T0, T0 + 10]), np.array([1.0, 1.0]), np.array([2.0, 2.0]),
                      np.array([math.pi / 2, math.pi / 2]))
    scan = make_scan([T0 + 5], [[3.0]], [0.0])
    ep = Episode(Path("b"), EpisodeFacts(), pose, "/odom", scan=scan)
    np.testing.assert_allclose(scan_points_world(ep), [[1.0, 5.0]], atol=1e-12)


def test_pose_interpolated_at_scan_stamp_with_unwrapped_yaw():
    # Yaw crosses +-pi between the poses: halfway is pi, not 0.
    pose = PoseSeries(np.array([T0, T0 + 2]), np.array([0.0, 2.0]), np.array([0.0, 0.0]),
                      np.array([math.pi - 0.1, -math.pi + 0.1]))
    scan = make_scan([T0 + 1], [[1.0]], [0.0])
    ep = Episode(Path("b"), EpisodeFacts(), pose, "/odom", scan=scan)
    np.testing.assert_allclose(scan_points_world(ep), [[0.0, 0.0]], atol=1e-9)


def test_wall_points_lie_on_wall_and_non_returns_are_dropped():
    ep = wall_episode()
    pts = scan_points_world(ep)
    finite_per_scan = np.isfinite(ep.scan.valid_ranges()[0]).sum()
    assert finite_per_scan < 181  # some beams see nothing (inf) ...
    assert len(pts) == finite_per_scan * len(ep.scan)  # ... and give no point
    np.testing.assert_allclose(pts[:, 1], 2.0, atol=1e-9)
    assert pts[:, 0].min() < 0 < 4 < pts[:, 0].max()


def test_scans_outside_pose_time_range_are_dropped():
    pose = PoseSeries(np.array([T0, T0 + 100]), np.zeros(2), np.zeros(2), np.zeros(2))
    scan = make_scan([T0 - 1, T0 + 50, T0 + 101], [[1.0], [2.0], [3.0]], [0.0])
    ep = Episode(Path("b"), EpisodeFacts(), pose, "/odom", scan=scan)
    np.testing.assert_allclose(scan_points_world(ep), [[2.0, 0.0]])


def test_every_and_max_points_subsample():
    ep = wall_episode()
    full = scan_points_world(ep)
    assert len(scan_points_world(ep, every=2)) == len(full) // len(ep.scan) * 9
    few = scan_points_world(ep, max_points=100)
    assert len(few) == 100
    assert {tuple(p) for p in few} <= {tuple(p) for p in full}
    with pytest.raises(ValueError, match="every=0"):
        scan_points_world(ep, every=0)


def test_no_scan_gives_no_points():
    ep = wall_episode()
    assert scan_points_world(Episode(ep.bag, ep.facts, ep.pose, "/odom")).shape == (0, 2)


def test_plot_trajectory_draws_path_markers_and_obstacles():
    ep = wall_episode(outcome=Outcome.COLLISION)
    ax = Figure().subplots()
    plot_trajectory(ax, ep, label="dwa", color="tab:purple")
    by_gid = {a.get_gid(): a for a in [*ax.lines, *ax.collections, *ax.patches]}
    path = by_gid["path"]
    np.testing.assert_array_equal(path.get_xdata(), ep.pose.x)
    np.testing.assert_array_equal(path.get_ydata(), ep.pose.y)
    assert path.get_label() == "dwa"
    assert by_gid["end"].get_marker() == "X"  # collision
    np.testing.assert_allclose(by_gid["goal"].get_xydata(), [[4.0, 0.0]])
    assert by_gid["goal_region"].get_radius() == pytest.approx(0.4)  # facts without: the default
    assert len(by_gid["obstacles"].get_offsets()) == len(scan_points_world(ep))
    assert ax.get_xlabel() == "x [m]" and ax.get_ylabel() == "y [m]"
    assert ax.get_aspect() == 1.0


def test_plot_trajectory_without_goal_or_scan():
    ep = wall_episode()
    bare = Episode(ep.bag, EpisodeFacts(), ep.pose, "/odom")
    ax = Figure().subplots()
    plot_trajectory(ax, bare)
    gids = {a.get_gid() for a in [*ax.lines, *ax.collections, *ax.patches]}
    assert gids == {"path", "start", "end"}
    assert ax.lines[0].get_xydata()[0].tolist() == [0.0, 0.0]


def test_velocity_profile_speed_and_commands():
    ep = wall_episode(speed=0.5)
    ax_v, ax_w = Figure().subplots(2)
    plot_velocity_profile(ax_v, ax_w, ep, label="a")
    measured, commanded = ax_v.lines
    np.testing.assert_allclose(measured.get_ydata(), 0.5)
    assert measured.get_xdata()[0] == pytest.approx(0.05)  # midpoint of the first interval
    assert commanded.get_linestyle() == "--" and commanded.get_label() == "a cmd"
    np.testing.assert_allclose(ax_w.lines[0].get_ydata(), 0.0, atol=1e-12)


@pytest.mark.parametrize("yaw, vx", [(0.0, -0.5), (math.pi, 0.5)])
def test_speed_is_drawn_signed_as_the_command(yaw, vx):
    """Backing along -x facing +x is -0.5 m/s, like its command; driving along -x facing -x
    is +0.5 (the body frame's forward component, not the world's)."""
    t = T0 + np.arange(21, dtype=np.int64) * 100_000_000
    pose = PoseSeries(t, -0.05 * np.arange(21), np.zeros(21), np.full(21, yaw))
    cmds = CmdSeries(t[::5], np.full(5, vx), np.zeros(5), np.zeros(5))
    ep = Episode(Path("b"), EpisodeFacts(), pose, "/odom", cmd=cmds)
    ax_v, ax_w = Figure().subplots(2)
    plot_velocity_profile(ax_v, ax_w, ep)
    measured, commanded = ax_v.lines
    np.testing.assert_allclose(measured.get_ydata(), vx, atol=1e-12)
    np.testing.assert_allclose(commanded.get_ydata(), vx)
    assert "forward" in ax_v.get_ylabel()
    (speed,) = trajectories_figure([ep]).axes[1].lines
    np.testing.assert_allclose(speed.get_ydata(), vx, atol=1e-12)


def test_acceleration_profile_of_a_speed_ramp():
    t = T0 + np.arange(11, dtype=np.int64) * 100_000_000
    ts = np.arange(11) * 0.1
    pose = PoseSeries(t, 0.5 * ts**2, np.zeros(11), 0.3 * ts, vx=ts, vy=np.zeros(11),
                      wz=0.3 * ts)  # v = t, w = 0.3 t: a = 1, alpha = 0.3
    ep = Episode(Path("b"), EpisodeFacts(), pose, "/odom")
    ax_a, ax_alpha = Figure().subplots(2)
    plot_acceleration_profile(ax_a, ax_alpha, ep)
    np.testing.assert_allclose(ax_a.lines[0].get_ydata(), 1.0)
    np.testing.assert_allclose(ax_alpha.lines[0].get_ydata(), 0.3)
    assert ax_a.get_ylabel().startswith("a [m/s")


def test_episode_figure_has_five_axes_and_saves_png(tmp_path):
    fig = episode_figure(wall_episode(), metrics_for("goal"))
    assert isinstance(fig, Figure) and len(fig.axes) == 5
    assert "run_0" in fig.get_suptitle() and "dwa" in fig.get_suptitle()
    assert any("n/a" in t.get_text() for t in fig.axes[0].texts)  # NaN min distance
    out = save_figure(fig, tmp_path / "sub" / "ep.png")
    data = out.read_bytes()
    assert out == tmp_path / "sub" / "ep.png" and data.startswith(PNG_MAGIC)


def test_episode_figure_uses_inferred_outcome_for_end_marker():
    fig = episode_figure(wall_episode(outcome=None), metrics_for("timeout"))
    end = next(a for a in fig.axes[0].lines if a.get_gid() == "end")
    assert end.get_marker() == "s" and "timeout" in fig.get_suptitle()


def test_comparison_figure_one_legend_entry_per_group():
    eps = [wall_episode(agent="dwa", bag="a"), wall_episode(agent="dwa", bag="b"),
           wall_episode(agent="td3", bag="c", speed=0.3), wall_episode(agent=None, bag="d")]
    fig = trajectories_figure(eps)
    ax_traj, ax_speed = fig.axes
    texts = [t.get_text() for t in ax_traj.get_legend().get_texts()]
    assert texts == ["dwa", "td3", "d"]
    paths = [a for a in ax_traj.lines if a.get_gid() == "path"]
    assert len(paths) == 4 and paths[0].get_color() == paths[1].get_color()
    assert paths[0].get_color() != paths[2].get_color()
    assert len(ax_speed.lines) == 4


def test_comparison_figure_rejects_unknown_group():
    with pytest.raises(ConfigError, match="did you mean 'agent'"):
        trajectories_figure([wall_episode()], group_by="agnet")
    with pytest.raises(ConfigError, match="no episodes"):
        trajectories_figure([])


def test_save_figure_refuses_to_overwrite(tmp_path):
    target = tmp_path / "fig.png"
    target.write_bytes(b"user data")
    fig = Figure()
    fig.subplots().plot([0, 1])
    with pytest.raises(FileExistsError, match="overwrite=True"):
        save_figure(fig, target)
    assert target.read_bytes() == b"user data"
    assert save_figure(fig, target, overwrite=True).read_bytes().startswith(PNG_MAGIC)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["fig.png"]  # no temp file left
