"""The crowd on the pictures: people as discs with short track tails in the episode videos, their
whole tracks on the report's trajectory maps and on ``pic4rl-metrics plot``'s trajectory.

An episode with a ``people`` topic (``Episode.people``: one column per person, NaN where a
message lacks that person) is drawn where the robot met them, so a video or a map shows why a
path bent or a social metric is what it is. Videos and maps are drawn with numpy (``raster``),
as the rest of their moving parts; the episode figure with matplotlib, as the rest of it.
"""

from __future__ import annotations

import numpy as np
from matplotlib.axes import Axes
from matplotlib.patches import Circle

from ..core.series import Episode
from . import raster
from .raster import COLORS, View

#: A person's disc radius on the pictures (m): the social metrics' person radius is 0.3 m.
PERSON_RADIUS_M = 0.25
#: How far back a video's track tail reaches (s).
TAIL_S = 2.0
#: At most this many positions of each person enter a report map's track.
TRACK_POINTS = 200


def positions(episode: Episode, t_s: np.ndarray, t0_ns: int) -> np.ndarray | None:
    """Each person's position at the episode times ``t_s`` (s after ``t0_ns``): the latest
    message's, NaN before the first message or where that message lacks the person; an array
    (len(t_s), people, 2), ``None`` without people."""
    people = episode.people
    if people is None or len(people) == 0 or people.x.shape[1] == 0:
        return None
    tq = (np.asarray(people.t_ns, np.int64) - t0_ns) / 1e9
    at = np.searchsorted(tq, np.asarray(t_s, float), side="right") - 1
    xy = np.stack([np.asarray(people.x, float), np.asarray(people.y, float)], axis=-1)
    out = xy[np.maximum(at, 0)]
    out[at < 0] = np.nan
    return out


def draw_frame(img: np.ndarray, view: View, xy: np.ndarray, k: int, frames_per_s: float) -> None:
    """Frame ``k`` of ``xy`` (``positions`` at the frames' times): each person present a disc,
    behind it a tail over the last ``TAIL_S`` seconds of frames."""
    first = max(0, k - round(TAIL_S * frames_per_s))
    for person in range(xy.shape[1]):
        raster.polyline(img, view, xy[first:k + 1, person], COLORS["person"])
        x, y = xy[k, person]
        if np.isfinite(x) and np.isfinite(y):
            raster.disc(img, view, float(x), float(y), PERSON_RADIUS_M, COLORS["person"])


def tracks(episode: Episode) -> np.ndarray:
    """Each person's track for a map, evenly thinned to ``TRACK_POINTS``: (people, n, 2),
    NaN where a message lacks the person; (0, 0, 2) without people."""
    people = episode.people
    if people is None or len(people) == 0:
        return np.zeros((0, 0, 2))
    rows = np.unique(np.linspace(0, len(people) - 1, min(len(people), TRACK_POINTS)).astype(int))
    xy = np.stack([np.asarray(people.x, float)[rows], np.asarray(people.y, float)[rows]], -1)
    return xy.transpose(1, 0, 2)


def draw_tracks(img: np.ndarray, view: View, people: np.ndarray) -> None:
    """Every person's track (``tracks``) as a thin line, broken where the person was absent,
    and a ring where it was last seen."""
    for track in people:
        present = np.isfinite(track).all(axis=1)
        breaks = np.flatnonzero(np.diff(present.astype(int)) != 0) + 1
        for run in np.split(np.arange(len(track)), breaks):
            if len(run) and present[run[0]]:
                raster.polyline(img, view, track[run], COLORS["person"])
        if present.any():
            x, y = track[np.flatnonzero(present)[-1]]
            raster.disc(img, view, float(x), float(y), PERSON_RADIUS_M, COLORS["person"],
                        ring_px=1.5)


def plot_tracks(ax: Axes, episode: Episode) -> None:
    """Every person's track on the episode figure's trajectory axes: a thin line (gid
    ``people``), a disc where it was last seen."""
    rgb = tuple(c / 255 for c in COLORS["person"])
    for track in tracks(episode):
        present = np.flatnonzero(np.isfinite(track).all(axis=1))
        if len(present):
            ax.plot(track[:, 0], track[:, 1], color=rgb, lw=0.8, zorder=1.5, gid="people")
            ax.add_patch(Circle(tuple(track[present[-1]]), PERSON_RADIUS_M, color=rgb,
                                zorder=1.5, gid="person"))
