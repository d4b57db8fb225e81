"""The frames of an episode video, from its ``Episode`` alone (a simulated or a real bag).

The still parts are drawn once with matplotlib (axes, start, goal and its tolerance, the row's
centre line, the v and ω profiles, a title with the outcome); each frame is a copy of that
picture with the moving parts drawn on it with numpy (``raster``): the map built up from the
scans so far, the path so far, the current scan, the footprint at its heading, the walking
person, the crowd's people with short track tails (``people``) and a time cursor across v and
ω; an exploration's floor seen so far is tinted (``coverage_plot``). Frame ``k`` (of
``duration / speed × fps``) shows the episode at ``(k + 1) × speed / fps``
seconds after its first pose, so the last one shows its end.
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from dataclasses import dataclass, replace

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.colors import to_rgb
from matplotlib.figure import Figure
from matplotlib.lines import Line2D

from pic4rl_base.errors import ConfigError

from ..contract import Outcome
from ..core.series import Episode
from . import people as crowd
from . import raster
from .coverage_plot import seen_shade
from .plots import END_STYLE, plot_trajectory, plot_velocity_profile, scan_hits_world
from .raster import COLORS, View

#: Frame size (pixels): multiples of 16, as H.264 encoders want them.
FRAME_SIZE = (960, 576)


@dataclass(frozen=True)
class VideoOptions:
    """How an episode plays: ``fps`` frames per second of video, ``speed`` seconds of episode
    per second of video; ``gif`` also writes a GIF (half size)."""

    fps: float = 10.0
    speed: float = 1.0
    gif: bool = False

    def __post_init__(self) -> None:
        for name in ("fps", "speed"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0):
                raise ConfigError(f"--{name}: {value!r} is invalid; expected a number > 0")


def frame_count(duration_s: float, options: VideoOptions) -> int:
    """Frames of a video of an episode ``duration_s`` long: its playing time times fps."""
    return max(1, round(duration_s / options.speed * options.fps))


def extent(episode: Episode) -> tuple[float, float, float, float]:
    """The world box (m) an episode's video shows: its poses, start, goal and tolerance,
    person and every scan return, with a margin for the footprint."""
    facts = episode.facts.with_defaults()
    xs = [np.asarray(episode.pose.x, float)]
    ys = [np.asarray(episode.pose.y, float)]
    _, px, py = scan_hits_world(episode)
    xs.append(px[np.isfinite(px)])
    ys.append(py[np.isfinite(py)])
    if facts.goal is not None:
        tol = facts.goal_tolerance_m
        xs.append(np.array([facts.goal[0] - tol, facts.goal[0] + tol]))
        ys.append(np.array([facts.goal[1] - tol, facts.goal[1] + tol]))
    if facts.start is not None:
        xs.append(np.array([facts.start[0]]))
        ys.append(np.array([facts.start[1]]))
    if episode.person is not None and len(episode.person):
        xs.append(np.asarray(episode.person.x, float))
        ys.append(np.asarray(episode.person.y, float))
    x, y = np.concatenate(xs), np.concatenate(ys)
    fp = facts.footprint
    margin = 0.5 + (max(fp.length_m or 0, fp.width_m or 0, 2 * (fp.radius_m or 0))
                    if fp is not None else 0.4)
    return (float(x.min()) - margin, float(y.min()) - margin,
            float(x.max()) + margin, float(y.max()) + margin)


def union(boxes: list[tuple[float, float, float, float]]) -> tuple[float, float, float, float]:
    """The smallest box holding every box (xmin, ymin, xmax, ymax)."""
    b = np.asarray(boxes, float)
    return (float(b[:, 0].min()), float(b[:, 1].min()), float(b[:, 2].max()),
            float(b[:, 3].max()))


def _legend_handles(person: bool) -> list[Line2D]:
    def mark(name: str, label: str, marker: str = "s") -> Line2D:
        rgb = tuple(c / 255 for c in COLORS[name])
        return Line2D([], [], ls="none", marker=marker, mfc=rgb, mec=rgb, label=label)

    handles = [mark("robot", "robot"), mark("path", "path", "_"), mark("scan", "scan", "."),
               mark("map", "map (scans so far)", ".")]
    return [*handles, mark("person", "person", "o")] if person else handles


class EpisodeScene:
    """The still picture of one episode and the frames drawn on it (see the module).

    ``outcome``: the word the title shows (default: the bag's, else unknown); ``bounds``: the
    world box to show (default: ``extent``), the same for episodes shown side by side."""

    def __init__(self, episode: Episode, options: VideoOptions = VideoOptions(), *,
                 outcome: str | None = None,
                 bounds: tuple[float, float, float, float] | None = None,
                 size: tuple[int, int] = FRAME_SIZE) -> None:
        self.episode, self.options = episode, options
        pose = episode.pose
        self.t0_ns = int(pose.t_ns[0])
        self.duration_s = (int(pose.t_ns[-1]) - self.t0_ns) / 1e9
        self.n_frames = frame_count(self.duration_s, options)
        step_s = options.speed / options.fps
        offsets = np.minimum((np.arange(self.n_frames) + 1) * step_s, self.duration_s)
        self.t_s = offsets
        self.outcome = outcome or (episode.facts.outcome or Outcome.UNKNOWN).value
        self._background(bounds or extent(episode), size)

    def _background(self, bounds: tuple[float, float, float, float],
                    size: tuple[int, int]) -> None:
        """Draw the still picture and keep the pixel views of its axes."""
        width, height = size
        fig = Figure(figsize=(width / 100, height / 100), dpi=100, layout="constrained")
        canvas = FigureCanvasAgg(fig)
        grid = fig.add_gridspec(2, 2, width_ratios=[1.6, 1])
        ax_map = fig.add_subplot(grid[:, 0])
        ax_v = fig.add_subplot(grid[0, 1])
        ax_w = fig.add_subplot(grid[1, 1], sharex=ax_v)
        ep = self.episode
        plot_trajectory(ax_map, ep, obstacles=False, color="black")
        for artist in ax_map.lines:
            if artist.get_gid() in ("path", "end"):
                artist.set_visible(False)  # they are drawn as the episode plays
        centerline = ep.facts.row_centerline
        if centerline is not None and len(centerline):
            line = np.asarray(centerline, float)
            ax_map.plot(line[:, 0], line[:, 1], "--", lw=1,
                        color=tuple(c / 255 for c in COLORS["centerline"]))
        ax_map.update_datalim([bounds[:2], bounds[2:]])
        ax_map.autoscale_view()
        person = self._person_track() is not None or ep.people is not None
        ax_map.legend(handles=_legend_handles(person),
                      loc="upper right", fontsize="x-small", framealpha=0.8)
        plot_velocity_profile(ax_v, ax_w, ep)
        ax_v.tick_params(labelbottom=False)
        ax_v.set_xlabel("")
        ax_v.set_xlim(0, max(self.duration_s, 1e-3))
        name = ep.bag.name.removesuffix(".db3").removesuffix(".mcap")
        fig.suptitle(f"{name} | agent: {ep.facts.agent or 'unknown'} | outcome: {self.outcome}",
                     fontsize="medium")
        canvas.draw()
        self.background = np.asarray(canvas.buffer_rgba())[..., :3].copy()
        self.map_view, self.map_box = self._axes_view(ax_map, height)
        self.cursor = [self._axes_view(ax, height) for ax in (ax_v, ax_w)]

    @staticmethod
    def _axes_view(ax: object, height: int) -> tuple[View, tuple[slice, slice]]:
        """The view of ``ax`` on the sub-image its axes box covers, and that box."""
        x0, y0, x1, y1 = (int(round(v)) for v in ax.bbox.extents)  # type: ignore[attr-defined]
        rows, cols = slice(height - y1, height - y0), slice(x0, x1)
        full = View.of_axes(ax, height)
        return replace(full, col0=full.col0 - x0, row0=full.row0 - (height - y1),
                       width=x1 - x0, height=y1 - y0), (rows, cols)

    def frames(self) -> Iterator[np.ndarray]:
        """Every frame, in order (each a new array)."""
        ep, facts = self.episode, self.episode.facts
        pose = ep.pose
        tp = (np.asarray(pose.t_ns, np.int64) - self.t0_ns) / 1e9
        x = np.interp(self.t_s, tp, np.asarray(pose.x, float))
        y = np.interp(self.t_s, tp, np.asarray(pose.y, float))
        yaw = np.interp(self.t_s, tp, np.unwrap(np.asarray(pose.yaw, float)))
        upto = np.searchsorted(tp, self.t_s, side="right")
        rows, sx, sy = scan_hits_world(ep)
        ts = ((np.asarray(ep.scan.t_ns, np.int64)[rows] - self.t0_ns) / 1e9
              if ep.scan is not None and len(rows) else np.zeros(0))
        seen = np.searchsorted(ts, self.t_s, side="right")
        person = self._person_track()
        people = crowd.positions(ep, self.t_s, self.t0_ns)
        base = self.background.copy()
        rr, cc = self.map_box
        view = self.map_view
        shade = seen_shade(ep, view, base[rr, cc].shape[:2], self.t0_ns)  # explore: area seen
        last_pose, last_scan = 0, 0
        path_end = (float(pose.x[0]), float(pose.y[0]))
        for k in range(self.n_frames):
            map_img = base[rr, cc]
            if shade is not None:
                shade.draw(map_img, self.t_s[k])
            raster.points(map_img, view, sx[last_scan:seen[k]], sy[last_scan:seen[k]],
                          COLORS["map"], size=2)
            path = [path_end, *zip(pose.x[last_pose:upto[k]], pose.y[last_pose:upto[k]]),
                    (x[k], y[k])]
            raster.polyline(map_img, view, path, COLORS["path"], width=2)
            last_pose, last_scan, path_end = upto[k], seen[k], (float(x[k]), float(y[k]))
            frame = base.copy()
            sub = frame[rr, cc]
            if seen[k] > 0:
                raster.points(sub, view, sx[seen[k] - 1], sy[seen[k] - 1], COLORS["scan"],
                              size=3)
            if person is not None:
                raster.disc(sub, view, person[0][k], person[1][k], 0.25, COLORS["person"])
            if people is not None:
                crowd.draw_frame(sub, view, people, k, self.options.fps / self.options.speed)
            color = self._robot_color(k)
            raster.footprint(sub, view, float(x[k]), float(y[k]), float(yaw[k]),
                             facts.footprint, color)
            self._cursor(frame, self.t_s[k])
            yield frame

    def _person_track(self) -> tuple[np.ndarray, np.ndarray] | None:
        person = self.episode.person
        if person is None or len(person) == 0:
            return None
        tq = (np.asarray(person.t_ns, np.int64) - self.t0_ns) / 1e9
        return (np.interp(self.t_s, tq, np.asarray(person.x, float)),
                np.interp(self.t_s, tq, np.asarray(person.y, float)))

    def _robot_color(self, k: int) -> tuple[int, int, int]:
        """The robot's colour; on the last frame, its outcome's (green goal, red collision)."""
        if k < self.n_frames - 1:
            return COLORS["robot"]
        try:
            name = END_STYLE[Outcome.parse(self.outcome)][1]
        except ConfigError:
            return COLORS["robot"]
        return tuple(int(round(255 * c)) for c in to_rgb(name))  # type: ignore[return-value]

    def _cursor(self, frame: np.ndarray, t_s: float) -> None:
        for view, (rr, cc) in self.cursor:
            col = view.col0 + view.sx * t_s
            sub = frame[rr, cc]
            c = int(round(col))
            sub[:, max(c - 1, 0):min(c + 1, sub.shape[1])] = COLORS["cursor"]
