"""Figures of episodes: trajectory with scan obstacles, velocity and acceleration profiles.

Plot functions take their axes and only draw, so callers compose them freely; the figure
builders make ``matplotlib.figure.Figure`` objects directly (never ``pyplot``), which needs no
display and no global state, so plots can be made headless and in parallel.
"""

from __future__ import annotations

import difflib
from collections.abc import Sequence
from dataclasses import fields, replace
from pathlib import Path

import matplotlib as mpl
import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure
from matplotlib.patches import Circle

from pic4rl_base import atomic
from pic4rl_base.errors import ConfigError
from pic4rl_base.geometry import Pose2D
from ..contract import EpisodeFacts, Outcome
from ..core.kinematics import differentiate, seconds, velocity_series
from ..core.registry import METRICS
from ..core.scan_summary import ScanSummary
from ..core.series import Episode, ScanSeries
from ..tables.results import EpisodeMetrics
from .people import plot_tracks

#: End marker (marker, colour, legend text) per outcome; ``None`` reads as unknown.
END_STYLE: dict[Outcome, tuple[str, str, str]] = {
    Outcome.GOAL: ("*", "tab:green", "end: goal"),
    Outcome.COLLISION: ("X", "tab:red", "end: collision"),
    Outcome.TIMEOUT: ("s", "tab:orange", "end: timeout"),
    Outcome.DIVERGED: ("P", "tab:purple", "end: diverged"),
    Outcome.ABORTED: ("v", "0.6", "end: aborted"),
    Outcome.UNKNOWN: ("D", "0.4", "end: unknown"),
}
OBSTACLE_COLOR = "0.6"
FORWARD_SPEED_LABEL = "forward v [m/s]"  # the body-frame vx, signed as the command is


def drawn_scans(episode: Episode) -> ScanSeries | None:
    """The whole scans a map of ``episode`` can draw: every scan (``full_scans``), else the
    sample kept beside the summary (``scan_sample``); None without a scan topic."""
    scan = episode.scan
    if isinstance(scan, ScanSummary):
        if scan.sample is None:
            raise ValueError(f"{str(episode.bag)!r}: its scans were kept as per-scan figures "
                             "only; read it with full_scans=True or scan_sample=N to draw them")
        return scan.sample
    return scan


def scan_hits_world(episode: Episode, *, every: int = 1) -> tuple[np.ndarray, np.ndarray,
                                                                     np.ndarray]:
    """Returns of every ``every``-th scan in the pose frame (m): the scans' rows, and x and y
    (rows × beams, NaN where a beam has no return).

    Each scan is placed at the pose interpolated linearly at its stamp (yaw on the unwrapped
    angle), its beams by the LiDAR's mount (``facts.scan_mount``, the base origin when
    unknown); scans outside the pose time range are dropped rather than extrapolated. The
    still plots and the episode videos build their map from these. The episode needs its
    whole scans or a sample of them (``drawn_scans``: rows index those), else ``ValueError``.
    """
    if every < 1:
        raise ValueError(f"every={every!r} must be >= 1")
    scan, pose = drawn_scans(episode), episode.pose
    none = (np.zeros(0, dtype=np.intp), np.zeros((0, 0)), np.zeros((0, 0)))
    if scan is None or len(scan) == 0 or len(pose) == 0:
        return none
    t_pose = np.asarray(pose.t_ns, dtype=np.int64)
    t_scan = np.asarray(scan.t_ns, dtype=np.int64)
    rows = np.arange(0, len(scan), every)
    rows = rows[(t_scan[rows] >= t_pose[0]) & (t_scan[rows] <= t_pose[-1])]
    if rows.size == 0:
        return none
    # Offsets from the first pose keep ns precision that float64 epoch stamps would lose.
    tp = (t_pose - t_pose[0]).astype(float)
    ts = (t_scan[rows] - t_pose[0]).astype(float)
    x = np.interp(ts, tp, np.asarray(pose.x, float))[:, None]
    y = np.interp(ts, tp, np.asarray(pose.y, float))[:, None]
    yaw = np.interp(ts, tp, np.unwrap(np.asarray(pose.yaw, float)))[:, None]
    some = ScanSeries(t_scan[rows], scan.ranges[rows], scan.angles[rows],
                      scan.range_min[rows], scan.range_max[rows])
    bx, by = some.points(episode.facts.scan_mount or Pose2D(0.0, 0.0))
    return rows, x + np.cos(yaw) * bx - np.sin(yaw) * by, y + np.sin(yaw) * bx + np.cos(yaw) * by


def scan_points_world(episode: Episode, *, every: int = 1, max_points: int = 20000) -> np.ndarray:
    """Obstacle points (N, 2) in the pose frame (m) from every ``every``-th scan
    (``scan_hits_world``), at most ``max_points`` of them, evenly subsampled."""
    if every < 1 or max_points < 0:
        msg = f"every={every!r} must be >= 1 and max_points={max_points!r} >= 0"
        raise ValueError(msg)
    _, px, py = scan_hits_world(episode, every=every)
    keep = np.isfinite(px) & np.isfinite(py)
    points = np.column_stack([px[keep], py[keep]])
    if len(points) > max_points:
        points = points[np.linspace(0, len(points) - 1, max_points).astype(int)]
    return points


def _outcome(facts: EpisodeFacts) -> Outcome:
    return facts.outcome if facts.outcome is not None else Outcome.UNKNOWN


def plot_trajectory(
    ax: Axes,
    episode: Episode,
    *,
    label: str | None = None,
    color: str | None = None,
    obstacles: bool = True,
) -> None:
    """Path, start, goal (with its tolerance circle), outcome-styled end and scan obstacles.

    Artists carry a ``gid`` (``path``, ``start``, ``goal``, ``goal_region``, ``end``,
    ``obstacles``) so a caller can find them, e.g. to build a legend; only the path is
    labelled, so several episodes on one axes give one legend entry each.
    """
    pose, facts = episode.pose, episode.facts
    if obstacles:
        pts = scan_points_world(episode)
        if len(pts):
            ax.scatter(pts[:, 0], pts[:, 1], s=1.5, c=OBSTACLE_COLOR, linewidths=0,
                       zorder=1, rasterized=True, gid="obstacles")
    (path,) = ax.plot(pose.x, pose.y, color=color, label=label, lw=1.5, zorder=2, gid="path")
    color = path.get_color()
    start = facts.start[:2] if facts.start is not None else None
    if start is None and len(pose):
        start = (pose.x[0], pose.y[0])
    if start is not None:
        ax.plot([start[0]], [start[1]], "o", mfc="white", mec=color, mew=1.5, ms=7, zorder=3,
                gid="start")
    if facts.goal is not None:
        gx, gy = facts.goal
        radius = facts.with_defaults().goal_tolerance_m
        ax.add_patch(Circle((gx, gy), radius, fill=False, ls="--", lw=1, ec="tab:green",
                            zorder=2, gid="goal_region"))
        ax.plot([gx], [gy], "P", color="tab:green", mec="black", mew=0.5, ms=9, zorder=3,
                gid="goal")
    if len(pose):
        marker, end_color, _ = END_STYLE[_outcome(facts)]
        ax.plot([pose.x[-1]], [pose.y[-1]], marker, color=end_color, mec="black", mew=0.5,
                ms=10, zorder=4, gid="end")
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")


def _t0(episode: Episode) -> int | None:
    return int(episode.pose.t_ns[0]) if len(episode.pose) else None


def plot_velocity_profile(
    ax_lin: Axes, ax_ang: Axes, episode: Episode, *, label: str | None = None
) -> None:
    """Signed forward speed (the body-frame ``vx``: negative when reversing) and yaw rate
    against time since the first pose; the commands (``cmd_vel``'s ``linear.x``, signed too)
    dashed."""
    vel = velocity_series(episode.pose)
    t0 = _t0(episode)
    t = seconds(vel.t_ns, t0)
    (line,) = ax_lin.plot(t, vel.vx, label=label, lw=1.2)
    color = line.get_color()
    ax_ang.plot(t, vel.wz, label=label, color=color, lw=1.2)
    cmd = episode.cmd
    if cmd is not None and len(cmd):
        tc = seconds(cmd.t_ns, t0)
        cmd_label = "cmd" if label is None else f"{label} cmd"
        style = dict(where="post", ls="--", lw=1, color=color, alpha=0.7, label=cmd_label)
        ax_lin.step(tc, cmd.vx, **style)
        ax_ang.step(tc, cmd.wz, **style)
    ax_lin.set_ylabel(FORWARD_SPEED_LABEL)
    ax_ang.set_ylabel(r"$\omega$ [rad/s]")
    for ax in (ax_lin, ax_ang):
        ax.set_xlabel("t [s]")
        ax.grid(True, alpha=0.3)


def plot_acceleration_profile(
    ax_lin: Axes, ax_ang: Axes, episode: Episode, *, label: str | None = None
) -> None:
    """|d(vx, vy)/dt| and signed d(wz)/dt over real time steps, against time since first pose."""
    vel = velocity_series(episode.pose)
    t0 = _t0(episode)
    lin = differentiate(vel.t_ns, np.column_stack([vel.vx, vel.vy]))
    yaw = differentiate(vel.t_ns, vel.wz)
    (line,) = ax_lin.plot(seconds(lin.t_ns, t0), np.linalg.norm(lin.value, axis=1),
                          label=label, lw=1.2)
    ax_ang.plot(seconds(yaw.t_ns, t0), yaw.value, label=label, color=line.get_color(), lw=1.2)
    ax_lin.set_ylabel(f"a [{METRICS['lin_acc_max_mps2'].unit}]")
    ax_ang.set_ylabel(rf"$\alpha$ [{METRICS['yaw_acc_max_radps2'].unit}]")
    for ax in (ax_lin, ax_ang):
        ax.set_xlabel("t [s]")
        ax.grid(True, alpha=0.3)


def _metrics_text(metrics: EpisodeMetrics) -> str:
    def fmt(name: str) -> str:
        info, value = METRICS[name], getattr(metrics, name)
        return f"{info.label}: " + ("n/a" if np.isnan(value) else f"{value:.2f} {info.unit}")

    success = "n/a" if np.isnan(metrics.success) else ("yes" if metrics.success > 0 else "no")
    names = ("clearance_time_s", "path_length_m", "obstacle_dist_min_m")
    return "\n".join([f"success: {success}", *(fmt(name) for name in names)])


def episode_figure(episode: Episode, metrics: EpisodeMetrics | None = None) -> Figure:
    """One episode: trajectory (left) and v, omega, a, alpha stacked on the right."""
    facts = episode.facts
    if metrics is not None and facts.outcome is None:
        # The metrics may have inferred the outcome; show it on the end marker too.
        try:
            facts = replace(facts, outcome=Outcome.parse(metrics.outcome))
        except ConfigError:
            pass
        episode = replace(episode, facts=facts)
    fig = Figure(figsize=(13, 7), layout="constrained")
    grid = fig.add_gridspec(4, 2, width_ratios=[1.5, 1])
    ax_traj = fig.add_subplot(grid[:, 0])
    ax_v = fig.add_subplot(grid[0, 1])
    right = [ax_v] + [fig.add_subplot(grid[i, 1], sharex=ax_v) for i in (1, 2, 3)]

    plot_trajectory(ax_traj, episode)
    plot_tracks(ax_traj, episode)
    names = {"path": "path", "start": "start", "goal": "goal", "end": END_STYLE[_outcome(facts)][2]}
    handles = [a for a in ax_traj.lines if a.get_gid() in names]
    ax_traj.legend(handles, [names[h.get_gid()] for h in handles], loc="lower right",
                   fontsize="small")
    plot_velocity_profile(right[0], right[1], episode)
    plot_acceleration_profile(right[2], right[3], episode)
    if episode.cmd is not None and len(episode.cmd):
        ax_v.legend(ax_v.lines[:2], ["measured", "commanded"], fontsize="small")
    for ax in right[:-1]:
        ax.tick_params(labelbottom=False)
        ax.set_xlabel("")
    if metrics is not None:
        ax_traj.text(0.02, 0.98, _metrics_text(metrics), transform=ax_traj.transAxes,
                     va="top", ha="left", fontsize="small", zorder=5,
                     bbox=dict(boxstyle="round", fc="white", ec="0.7", alpha=0.9))
    outcome = metrics.outcome if metrics is not None else _outcome(facts).value
    fig.suptitle(f"{episode.bag.name} | agent: {facts.agent or 'unknown'} | outcome: {outcome}")
    return fig


def _group(episode: Episode, group_by: str) -> str:
    value = getattr(episode.facts, group_by)
    return episode.bag.name if value is None else str(value)


def trajectories_figure(episodes: Sequence[Episode], *, group_by: str = "agent") -> Figure:
    """All trajectories on one axes and their signed forward speeds on another, by group.

    ``group_by`` names an ``EpisodeFacts`` field (agent, task, world, run, ...); an episode
    without that fact forms its own group named after its bag.
    """
    names = [f.name for f in fields(EpisodeFacts)]
    if group_by not in names:
        hint = difflib.get_close_matches(group_by, names, n=1)
        suggestion = f"; did you mean {hint[0]!r}?" if hint else f"; expected one of {names}"
        raise ConfigError(f"group_by={group_by!r} is not an episode fact{suggestion}")
    if not episodes:
        raise ConfigError("trajectories_figure: no episodes to plot")
    groups = list(dict.fromkeys(_group(ep, group_by) for ep in episodes))
    cycle = mpl.rcParams["axes.prop_cycle"].by_key().get("color", [])
    if len(groups) <= len(cycle):
        colors = dict(zip(groups, cycle))
    else:
        cmap = mpl.colormaps["turbo"]
        colors = {g: cmap(i / max(len(groups) - 1, 1)) for i, g in enumerate(groups)}

    fig = Figure(figsize=(14, 6), layout="constrained")
    ax_traj, ax_speed = fig.subplots(1, 2, width_ratios=[1.3, 1])
    labelled: set[str] = set()
    for ep in episodes:
        group = _group(ep, group_by)
        label = None if group in labelled else group
        labelled.add(group)
        plot_trajectory(ax_traj, ep, label=label, color=colors[group])
        vel = velocity_series(ep.pose)
        ax_speed.plot(seconds(vel.t_ns, _t0(ep)), vel.vx, color=colors[group], lw=1, alpha=0.8)
    ax_traj.legend(title=group_by, fontsize="small")
    ax_speed.set_xlabel("t [s]")
    ax_speed.set_ylabel(FORWARD_SPEED_LABEL)
    ax_speed.grid(True, alpha=0.3)
    fig.suptitle(f"{len(episodes)} episodes by {group_by}")
    return fig


def figure_names(bags: Sequence[str]) -> list[str]:
    """A file name (no suffix) per bag, unique among ``bags``: the bag's name, with as many of
    its parent folders in front as it takes to tell it from the others
    (``td3_lidar-episode_0000`` and ``sac_lidar-episode_0000``)."""
    split = [[p for p in Path(b).parts if p not in ("/", "\\")] for b in bags]
    for parts in split:
        parts[-1] = parts[-1].removesuffix(".db3").removesuffix(".mcap")
    depth = [1] * len(split)
    while True:
        names = ["-".join(parts[-d:]) for parts, d in zip(split, depth)]
        taken = {n for n in names if names.count(n) > 1}
        grow = [i for i, n in enumerate(names) if n in taken and depth[i] < len(split[i])]
        if not grow:
            return [n if n not in taken else f"{n}-{i}" for i, n in enumerate(names)]
        for i in grow:
            depth[i] += 1


def by_world(episodes: Sequence[Episode]) -> dict[str, list[Episode]]:
    """``episodes`` by their ``world`` fact (``""``: none recorded), in order: a comparison
    never overlays the scans of two worlds."""
    groups: dict[str, list[Episode]] = {}
    for episode in episodes:
        groups.setdefault(episode.facts.world or "", []).append(episode)
    return groups


def save_figure(fig: Figure, path: str | Path, *, overwrite: bool = False,
                dpi: float = 150) -> Path:
    """Write ``fig`` (format from the suffix, PNG when none) and return its path.

    Parent folders are created. An existing file is never touched unless ``overwrite``: the
    new file is opened exclusively, so one appearing meanwhile is not clobbered either; with
    ``overwrite`` the figure goes to a temporary file first and replaces the old one whole.
    """
    path = Path(path)
    fmt = path.suffix.lstrip(".").lower() or "png"
    if not overwrite and path.exists():
        msg = f"{str(path)!r} exists; pass overwrite=True to replace it"
        raise FileExistsError(msg)
    path.parent.mkdir(parents=True, exist_ok=True)
    if overwrite:
        with atomic.replacing(path) as tmp, tmp.open("wb") as handle:
            fig.savefig(handle, format=fmt, dpi=dpi)
        return path
    try:
        handle = path.open("xb")
    except FileExistsError as err:
        msg = f"{str(path)!r} exists; pass overwrite=True to replace it"
        raise FileExistsError(msg) from err
    try:
        with handle:
            fig.savefig(handle, format=fmt, dpi=dpi)
    except BaseException:
        path.unlink(missing_ok=True)  # only the file this call created
        raise
    return path
