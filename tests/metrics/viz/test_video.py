"""Episode videos from bags (``pic4rl-metrics video``): the robot drawn at its pose, as many
frames as the playing time times fps, MP4s that imageio opens with that many frames, a
real-robot bag rendered, side-by-side pairs, and bad bags as error rows with exit 1."""

from __future__ import annotations

import contextlib
import io
import math
from pathlib import Path

import imageio.v3 as iio
import numpy as np
import pytest

from pic4rl_metrics.cli.commands import main
from pic4rl_metrics.viz.raster import COLORS
from pic4rl_metrics.bags.reader import read_episode
from pic4rl_metrics.synthetic.synthetic import Obstacles, straight_line, write_episode_bag
from pic4rl_metrics.viz.video import EpisodeScene, VideoOptions, frame_count
from pic4rl_metrics.viz.video_batch import render_videos, video_names

REAL_BAGS = Path(__file__).resolve().parents[4] / "shared" / "real_bags"
WALLS = Obstacles(segments=((-1, -2, 8, -2), (8, -2, 8, 2), (8, 2, -1, 2), (-1, 2, -1, -2)))
FOOTPRINT = {"length_m": 0.5, "width_m": 0.4}


def bag(path: Path, *, agent: str = "td3", speed: float = 0.5, duration_s: float = 12.0,
        goal: tuple[float, float] = (6.0, 0.0), outcome: str = "goal") -> Path:
    """A straight run along +x from the origin at ``speed`` in a walled corridor."""
    track = straight_line(speed, duration_s, 0.1)
    facts = {"agent": agent, "footprint": FOOTPRINT, "start": [0.0, 0.0, 0.0],
             "goal": list(goal)}
    return write_episode_bag(path, track, obstacles=WALLS, n_beams=90, goal=goal,
                             facts=facts, outcome=outcome)


def run_cli(argv: list[str]) -> tuple[int, str, str]:
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = main(argv)
    return code, out.getvalue(), err.getvalue()


def test_the_robot_is_drawn_at_its_pose(tmp_path: Path) -> None:
    episode = read_episode(bag(tmp_path / "ep"), full_scans=True)
    scene = EpisodeScene(episode, VideoOptions(fps=10))
    frames = list(scene.frames())
    rr, cc = scene.map_box
    for k in (29, 59, 99):  # t = 3, 6, 10 s: x = 1.5, 3.0, 5.0 m
        x = 0.5 * scene.t_s[k]
        assert x == pytest.approx(0.5 * (k + 1) / 10)
        sub = frames[k][rr, cc]
        behind = scene.map_view.pixels(x - 0.15, 0.1)  # inside the footprint, off the heading
        col, row = (int(round(float(v))) for v in behind)
        assert tuple(sub[row, col]) == COLORS["robot"], k
        ahead = scene.map_view.pixels(x + 0.6, 0.1)  # beyond its front: not the robot
        col, row = (int(round(float(v))) for v in ahead)
        assert tuple(sub[row, col]) != COLORS["robot"], k


@pytest.mark.parametrize(("duration_s", "fps", "speed", "expected"),
                         [(12.0, 10, 1.0, 120), (12.0, 10, 2.0, 60), (12.0, 5, 1.0, 60),
                          (12.0, 30, 0.5, 720), (0.05, 10, 1.0, 1)])
def test_the_frame_count_is_the_playing_time_times_fps(
        tmp_path: Path, duration_s: float, fps: float, speed: float, expected: int) -> None:
    assert frame_count(duration_s, VideoOptions(fps=fps, speed=speed)) == expected
    if expected <= 120:
        episode = read_episode(bag(tmp_path / "ep", duration_s=max(duration_s, 0.1)),
                               full_scans=True)
        scene = EpisodeScene(episode, VideoOptions(fps=fps, speed=speed))
        assert sum(1 for _ in scene.frames()) == scene.n_frames
        assert scene.n_frames == max(1, round(scene.duration_s / speed * fps))
        assert scene.t_s[-1] == pytest.approx(scene.duration_s)  # the last frame: the end


def test_the_video_opens_with_imageio_and_has_that_many_frames(tmp_path: Path) -> None:
    source = bag(tmp_path / "ep")
    code, out, err = run_cli(["video", str(source), "--out", str(tmp_path / "v"), "--gif",
                              "--speed", "2", "--fps", "8"])
    assert code == 0, err
    frames = iio.imread(tmp_path / "v" / "ep.mp4")
    assert frames.shape == (round(12 / 2 * 8), 576, 960, 3)
    gif = iio.imread(tmp_path / "v" / "ep.gif")
    assert gif.shape[1:3] == (288, 480) and 1 < len(gif) <= len(frames)
    assert "ep.mp4" in out and "48" in out and f"wrote {tmp_path / 'v' / 'ep.mp4'}" in err


def test_an_existing_video_is_kept_unless_forced(tmp_path: Path) -> None:
    source = bag(tmp_path / "ep")
    target = tmp_path / "v" / "ep.mp4"
    target.parent.mkdir()
    target.write_bytes(b"mine")
    code, _, err = run_cli(["video", str(source), "--out", str(target.parent), "--fps", "2"])
    assert code == 0 and target.read_bytes() == b"mine" and "kept existing" in err
    code, _, err = run_cli(["video", str(source), "--out", str(target.parent), "--fps", "2",
                            "--force"])
    assert code == 0, err
    assert len(iio.imread(target)) == 24
    assert sorted(p.name for p in target.parent.iterdir()) == ["ep.mp4"]  # no temporary left


def test_empty_and_corrupt_bags_are_error_rows_and_the_rest_is_rendered(tmp_path: Path) -> None:
    good = bag(tmp_path / "good")
    corrupt = tmp_path / "corrupt.db3"
    corrupt.write_bytes(b"not a bag at all" * 10)
    empty = tmp_path / "empty"
    empty.mkdir()
    truncated = bag(tmp_path / "truncated")
    db3 = next(truncated.glob("*.db3"))
    db3.write_bytes(db3.read_bytes()[:2048])
    out_dir = tmp_path / "v"
    code, out, err = run_cli(["video", str(corrupt), str(empty), str(truncated), str(good),
                              "--out", str(out_dir), "--fps", "2", "-j", "2"])
    assert code == 1
    assert "Traceback" not in err and "3 of 4 bag(s) failed" in err
    for name in ("corrupt.db3", "empty", "truncated"):
        assert any(line.startswith("error: ") and name in line for line in err.splitlines())
    assert sorted(p.name for p in out_dir.iterdir()) == ["good.mp4"]
    assert len(iio.imread(out_dir / "good.mp4")) == 24


def test_grid_puts_a_pairs_episodes_side_by_side(tmp_path: Path) -> None:
    first = bag(tmp_path / "td3" / "episode_0000", agent="td3")
    second = bag(tmp_path / "sac" / "episode_0000", agent="sac", speed=0.4,
                 outcome="timeout")
    other = bag(tmp_path / "sac" / "episode_0001", agent="sac", goal=(5.0, 1.0))
    third = bag(tmp_path / "td3" / "episode_0001", agent="td3", goal=(4.0, 0.0),
                duration_s=6.0)
    fourth = bag(tmp_path / "dwa" / "episode_0001", agent="dwa", goal=(4.0, 0.0))
    rows = render_videos([tmp_path], tmp_path / "v", options=VideoOptions(fps=2), grid=True)
    by_bag = {Path(r.bag): r for r in rows}
    assert not any(r.error for r in rows) and len(rows) == 5
    assert by_bag[first].video == by_bag[second].video == str(tmp_path / "v" / "pair_02.mp4")
    assert by_bag[third].video == by_bag[fourth].video == str(tmp_path / "v" / "pair_01.mp4")
    assert by_bag[other].video == str(tmp_path / "v" / "sac_episode_0001.mp4")
    frames = iio.imread(tmp_path / "v" / "pair_02.mp4")
    assert frames.shape[1:] == (576, 2 * 960, 3)
    assert len(frames) == 24  # the longer episode's: both last 12 s
    assert len(iio.imread(tmp_path / "v" / "pair_01.mp4")) == 24  # dwa's 12 s, td3 holds


def test_names_repeat_only_with_their_folders(tmp_path: Path) -> None:
    bags = [tmp_path / "run" / a / "episode_0000" for a in ("td3", "dwa")]
    assert video_names(bags) == {bags[0]: "td3_episode_0000", bags[1]: "dwa_episode_0000"}
    single = [tmp_path / "x" / "episode_0003.db3"]
    assert video_names(single) == {single[0]: "episode_0003"}


@pytest.mark.bad_input
def test_bad_speed_is_a_usage_error(tmp_path: Path) -> None:
    with pytest.raises(SystemExit) as exc, contextlib.redirect_stderr(io.StringIO()) as err:
        main(["video", str(tmp_path), "--out", str(tmp_path), "--speed", "0"])
    assert exc.value.code == 2 and "--speed" in err.getvalue()


def test_a_real_robot_bag_renders() -> None:
    source = REAL_BAGS / "neato_obstacle_avoider"
    if not source.is_dir():
        pytest.skip("../shared/real_bags not found: real-robot bag tests not run")
    episode = read_episode(source, full_scans=True)
    scene = EpisodeScene(episode, VideoOptions(fps=2))
    assert scene.n_frames == round(scene.duration_s * 2) and scene.duration_s > 30
    frames = list(scene.frames())
    rr, cc = scene.map_box
    scan_colour = np.all(frames[-1][rr, cc] == COLORS["scan"], axis=-1)
    assert scan_colour.sum() > 10  # its LiDAR's returns are drawn


def test_a_real_robot_bag_renders_through_the_cli(tmp_path: Path) -> None:
    source = REAL_BAGS / "neato_person_follower"
    if not source.is_dir():
        pytest.skip("../shared/real_bags not found: real-robot bag tests not run")
    code, _, err = run_cli(["video", str(source), "--out", str(tmp_path), "--speed", "4",
                            "--fps", "4"])
    assert code == 0, err
    frames = iio.imread(tmp_path / "neato_person_follower.mp4")
    assert len(frames) == round(36.37 / 4 * 4) and not math.isnan(frames.mean())
