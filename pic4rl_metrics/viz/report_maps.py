"""The HTML report's maps: per start–goal pair the agents' paths, per agent where it failed,
drawn on the map its episodes' scans build, as inline PNG images.

A report of a thousand episodes holds a few hundred small maps, so they are drawn with numpy
(``raster``, the drawing the episode videos use) on arrays and encoded by Pillow, not with a
matplotlib figure each. Each episode is first reduced to a ``Sketch``: its path, a subsample
of its scans' returns in the pose frame (``plots.scan_hits_world``, the videos' map), its end
and its people's tracks (``people``), so an episode's arrays are walked once however many maps
show it.
"""

from __future__ import annotations

import base64
import io
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field

import numpy as np
from PIL import Image

from ..core.series import Episode
from . import people as crowd
from . import raster
from .plots import drawn_scans, scan_hits_world
from .raster import COLORS, View

#: One colour per agent, in order (matplotlib's tab10).
PALETTE: tuple[tuple[int, int, int], ...] = (
    (31, 119, 180), (255, 127, 14), (44, 160, 44), (148, 103, 189), (140, 86, 75),
    (227, 119, 194), (127, 127, 127), (188, 189, 34), (23, 190, 207), (214, 39, 40),
)
#: The colour of an episode's end, by outcome (the failures' map and the pairs' maps).
END_COLORS: dict[str, tuple[int, int, int]] = {
    "goal": (44, 160, 44), "collision": (214, 39, 40), "timeout": (255, 127, 14),
    "diverged": (148, 103, 189), "aborted": (150, 150, 150), "unknown": (90, 90, 90),
}
MAP_SIZE = (280, 280)
#: At most this many scans of one episode are drawn (evenly spread): the report reads no more
#: (``compute(..., scan_sample=SKETCH_SCANS)``), so its memory is bounded in a log's length.
SKETCH_SCANS = 60
#: At most this many scan returns of one episode enter its sketch (evenly subsampled).
SKETCH_POINTS = 1500
SKETCH_POSES = 400


@dataclass(frozen=True)
class Sketch:
    """What the maps draw of one episode (world metres, the pose frame)."""

    path: np.ndarray  # (n, 2)
    returns: np.ndarray  # (m, 2) scan returns
    outcome: str
    start: tuple[float, float]
    goal: tuple[float, float] | None
    goal_tolerance_m: float
    people: np.ndarray = field(default_factory=lambda: np.zeros((0, 0, 2)))  # crowd.tracks

    @property
    def end(self) -> tuple[float, float]:
        return float(self.path[-1, 0]), float(self.path[-1, 1])


def _even(points: np.ndarray, most: int) -> np.ndarray:
    if len(points) <= most:
        return points
    return points[np.linspace(0, len(points) - 1, most).astype(int)]


def sketch(episode: Episode, outcome: str) -> Sketch:
    """``episode`` reduced to what the maps draw; ``outcome``: its judged outcome."""
    pose = episode.pose
    path = _even(np.column_stack([np.asarray(pose.x, float), np.asarray(pose.y, float)]),
                 SKETCH_POSES)
    scans = drawn_scans(episode)
    every = max(1, len(scans) // SKETCH_SCANS) if scans is not None else 1
    _, px, py = scan_hits_world(episode, every=every)
    keep = np.isfinite(px) & np.isfinite(py)
    returns = _even(np.column_stack([px[keep], py[keep]]), SKETCH_POINTS)
    facts = episode.facts.with_defaults()
    start = (facts.start[0], facts.start[1]) if facts.start is not None else tuple(path[0])
    return Sketch(path, returns, outcome, (float(start[0]), float(start[1])), facts.goal,
                  float(facts.goal_tolerance_m), crowd.tracks(episode))


def _bounds(sketches: Sequence[Sketch], with_returns: bool) -> tuple[float, float, float, float]:
    parts = [s.path for s in sketches]
    parts += [np.array([s.goal]) for s in sketches if s.goal is not None]
    if with_returns:
        parts += [s.returns for s in sketches if len(s.returns)]
    xy = np.concatenate(parts)
    xy = xy[np.isfinite(xy).all(axis=1)]
    margin = 0.5
    return (float(xy[:, 0].min()) - margin, float(xy[:, 1].min()) - margin,
            float(xy[:, 0].max()) + margin, float(xy[:, 1].max()) + margin)


def _canvas(sketches: Sequence[Sketch], size: tuple[int, int]) -> tuple[np.ndarray, View]:
    """A white image with every sketch's scan returns (grey) and its view."""
    width, height = size
    img = np.full((height, width, 3), 255, np.uint8)
    view = View.fit(_bounds(sketches, with_returns=True), width, height, margin_px=6)
    for s in sketches:
        if len(s.returns):
            raster.points(img, view, s.returns[:, 0], s.returns[:, 1], COLORS["map"])
    return img, view


def _marker(img: np.ndarray, view: View, xy: tuple[float, float], color: object,
            px: float = 3.5, ring: bool = False) -> None:
    raster.disc(img, view, xy[0], xy[1], px * view.metres_per_pixel, color,
                ring_px=1.5 if ring else None)


def pair_map(sketches: Sequence[tuple[Sketch, tuple[int, int, int]]],
             size: tuple[int, int] = MAP_SIZE) -> np.ndarray:
    """One start–goal pair: the map of its episodes' scans, the people's tracks of its
    episodes (pink, a ring where each was last seen), each episode's path in its agent's
    colour, the start (ring), the goal (green ring: its tolerance) and each end in its
    outcome's colour."""
    only = [s for s, _ in sketches]
    img, view = _canvas(only, size)
    for s in only:
        crowd.draw_tracks(img, view, s.people)
    for s, color in sketches:
        raster.polyline(img, view, s.path, color, width=2)
    first = only[0]
    if first.goal is not None:
        raster.disc(img, view, first.goal[0], first.goal[1], first.goal_tolerance_m,
                    COLORS["goal"], ring_px=2)
    _marker(img, view, first.start, COLORS["cursor"], ring=True)
    for s, _ in sketches:
        _marker(img, view, s.end, END_COLORS.get(s.outcome, END_COLORS["unknown"]), px=3)
    return img


def failure_map(world: Sequence[Sketch], failures: Iterable[Sketch],
                size: tuple[int, int] = MAP_SIZE) -> np.ndarray:
    """Where an agent's episodes ended without success, on the map every episode of the
    world builds: a dot per end in its outcome's colour (red: collision)."""
    img, view = _canvas(world, size)
    for s in failures:
        _marker(img, view, s.end, END_COLORS.get(s.outcome, END_COLORS["unknown"]))
    return img


def png_uri(img: np.ndarray) -> str:
    """``img`` (uint8, height × width × 3) as a ``data:image/png;base64,...`` URI."""
    buf = io.BytesIO()
    Image.fromarray(img).save(buf, format="PNG", compress_level=6)
    return "data:image/png;base64," + base64.b64encode(buf.getvalue()).decode("ascii")
