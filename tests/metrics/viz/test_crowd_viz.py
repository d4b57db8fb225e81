"""The crowd on the pictures (issue 41 item 6), from synthetic bags with people: the report's
leaderboard has the social columns and its pair map draws the people's tracks, a video frame
has the person colour where a person stands, the episode plot draws each track, and pictures of
a bag without people have none."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from pic4rl_metrics import compute
from pic4rl_metrics.bags.reader import read_episode
from pic4rl_metrics.synthetic.synthetic import Obstacles, Track, straight_line, write_episode_bag
from pic4rl_metrics.synthetic.synthetic_crowd import standing
from pic4rl_metrics.viz.html_report import write_report
from pic4rl_metrics.viz.people import PERSON_RADIUS_M
from pic4rl_metrics.viz.plots import episode_figure
from pic4rl_metrics.viz.raster import COLORS, View
from pic4rl_metrics.viz.report_maps import SKETCH_SCANS, _bounds, pair_map, sketch
from pic4rl_metrics.viz.video import EpisodeScene, VideoOptions

WALLS = Obstacles(segments=((-1, -3, 8, -3), (8, -3, 8, 3), (8, 3, -1, 3), (-1, 3, -1, -3)))
FACTS = {"footprint": {"radius_m": 0.2}, "start": [0.0, 0.0, 0.0], "goal": [6.0, 0.0]}
PERSON = (3.0, 1.5)


def _walker(duration_s: float) -> Track:
    """A person walking +y from (5, -2) at 0.3 m/s."""
    return straight_line(0.3, duration_s, 0.1, start=(5.0, -2.0, np.pi / 2))


def _bag(path: Path, agent: str, people: bool = True) -> Path:
    robot = straight_line(0.5, 12.0, 0.1)
    crowd = [standing(*PERSON, 12.0), _walker(12.0)] if people else []
    return write_episode_bag(path, robot, obstacles=WALLS, n_beams=90, goal=(6.0, 0.0),
                             people=crowd, facts={**FACTS, "agent": agent}, outcome="goal")


def _pixel(view: View, x: float, y: float) -> tuple[int, int]:
    col, row = (round(float(v)) for v in view.pixels(x, y))
    return row, col


def test_the_report_has_the_social_columns_and_draws_the_people(tmp_path: Path) -> None:
    bags = [_bag(tmp_path / "bags" / a / "episode_0000", a) for a in ("dwa", "orca")]
    result = compute(bags, scan_sample=SKETCH_SCANS)
    out = tmp_path / "report.html"
    write_report(result, out)
    text = out.read_text()
    board = re.search(r'<table id="leaderboard".*?</table>', text, re.DOTALL)
    assert board is not None
    for label in ("personal zone time [s]", "min person distance [m]", "people collisions"):
        assert label in board.group(0), label
    assert "each person's track" in text
    # the pair map: the standing person's ring and the walker's track in the person colour
    drawn = [(sketch(read_episode(b, full_scans=True), "goal"), (31, 119, 180)) for b in bags]
    img = pair_map(drawn)
    view = View.fit(_bounds([s for s, _ in drawn], True), img.shape[1], img.shape[0],
                    margin_px=6)  # the map's own view
    person = np.all(img == COLORS["person"], axis=-1)
    for x, y in ((5.0, -1.0), (5.0, 0.5), (PERSON[0] + PERSON_RADIUS_M, PERSON[1])):
        r, c = _pixel(view, x, y)
        assert person[r - 1:r + 2, c - 1:c + 2].any(), (x, y)
    r, c = _pixel(view, 2.0, -2.0)  # nobody walked there
    assert not person[r - 1:r + 2, c - 1:c + 2].any()
    bare = pair_map([(sketch(read_episode(_bag(tmp_path / "bare", "dwa", people=False),
                                           full_scans=True),
                              "goal"), (31, 119, 180))])
    assert not np.all(bare == COLORS["person"], axis=-1).any()


def test_a_video_frame_draws_a_person_where_it_stands(tmp_path: Path) -> None:
    scene = EpisodeScene(read_episode(_bag(tmp_path / "ep", "orca"), full_scans=True),
                         VideoOptions(fps=10))
    frames = list(scene.frames())
    rr, cc = scene.map_box
    for k in (20, 80):
        sub = frames[k][rr, cc]
        row, col = _pixel(scene.map_view, *PERSON)
        assert tuple(sub[row, col]) == COLORS["person"], k
        off = _pixel(scene.map_view, PERSON[0], PERSON[1] + 2.5 * PERSON_RADIUS_M)
        assert tuple(sub[off]) != COLORS["person"], k
        # the walker: its disc where it is now, a tail where it was 1 s before
        t = scene.t_s[k]
        now = _pixel(scene.map_view, 5.0, -2.0 + 0.3 * t)
        assert tuple(sub[now]) == COLORS["person"], k
    plain = EpisodeScene(read_episode(_bag(tmp_path / "plain", "dwa", people=False),
                                      full_scans=True), VideoOptions(fps=10))
    last = list(plain.frames())[-1][plain.map_box]
    assert not np.all(last == COLORS["person"], axis=-1).any()


def test_the_episode_plot_draws_each_persons_track(tmp_path: Path) -> None:
    fig = episode_figure(read_episode(_bag(tmp_path / "ep", "orca"), full_scans=True))
    ax = fig.axes[0]
    tracks = [line for line in ax.lines if line.get_gid() == "people"]
    assert len(tracks) == 2
    ends = sorted(tuple(np.round(p.center, 2)) for p in ax.patches if p.get_gid() == "person")
    assert ends == [PERSON, (5.0, round(-2.0 + 0.3 * 12.0, 2))]
    bare = episode_figure(read_episode(_bag(tmp_path / "bare", "dwa", people=False),
                                       full_scans=True))
    assert not [line for line in bare.axes[0].lines if line.get_gid() == "people"]
