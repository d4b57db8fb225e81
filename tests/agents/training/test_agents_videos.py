"""Videos of evaluations and of tests: ``eval.video_episodes`` writes each evaluation's first
episode as an MP4 in ``<run>/videos/`` (as long as the evaluation's episode) and a GIF in
TensorBoard, and nothing when off (the default); ``pic4rl-test --video`` writes one MP4 per
episode beside its bag, with one frame per control period of the episode."""

from __future__ import annotations

import contextlib
import io
from pathlib import Path

import imageio.v3 as iio
import pandas as pd
from agents_helpers import LIDAR_TD3, SHORT_EPISODES, TINY, TrainedRun
from tensorboard.backend.event_processing.event_accumulator import EventAccumulator

from pic4rl_agents.testing import tester

from pic4rl_agents.training import train
from pic4rl_agents.runs.config import EvalConfig
from pic4rl_metrics import read_episode


def test_evaluation_videos_are_off_by_default(trained_run: TrainedRun) -> None:
    assert EvalConfig().video_episodes == 0
    assert trained_run.code == 0 and (trained_run.run_dir / "eval").is_dir()  # it evaluated
    assert not (trained_run.run_dir / "videos").exists()


def test_each_evaluation_writes_its_first_episode_as_mp4_and_tensorboard_gif(
        tmp_path: Path) -> None:
    err = io.StringIO()
    with contextlib.redirect_stderr(err):
        code = train.main([
            "--hyperparams", *TINY, "tensorboard:true", "eval.interval_steps:100",
            "eval.video_episodes:1", "checkpoint.interval_steps:0",
            "--env-kwargs", *SHORT_EPISODES, "-n", "200", "--run", "v", "--no-progress",
            "--ros-args", "--params-file", str(LIDAR_TD3), "-p", f"runs_dir:={tmp_path}"])
    assert code == 0, err.getvalue()
    run = tmp_path / "v"
    evaluations = pd.read_csv(run / "eval" / "0" / "evaluations.csv")
    assert list(evaluations["steps"]) == [100, 200]
    videos = sorted((run / "videos").iterdir())
    assert [p.name for p in videos] == [f"eval_{s}_steps_episode_0.mp4" for s in (100, 200)]
    for steps, length in zip(evaluations["steps"], evaluations["mean_length"]):
        frames = iio.imread(run / "videos" / f"eval_{steps}_steps_episode_0.mp4")
        assert len(frames) == int(length) + 1  # the same episode: its reset, then each step
    events = EventAccumulator(str(run / "logs" / "0"), size_guidance={"images": 0})
    events.Reload()
    gifs = events.Images("eval/video_0")
    assert [g.step for g in gifs] == [100, 200]
    assert all(g.encoded_image_string.startswith(b"GIF89a") for g in gifs)


def test_pic4rl_test_video_writes_one_mp4_per_episode_beside_its_bag(tmp_path: Path) -> None:
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = tester.main(["--baseline", "proportional", "--episodes", "2", "--bags",
                            str(tmp_path), "--run", "r", "--video", "--env-kwargs",
                            "episode_max_steps:40", "--no-progress",
                            "--ros-args", "--params-file", str(LIDAR_TD3)])
    assert code == 0, err.getvalue()
    agent = tmp_path / "r" / "proportional"
    assert sorted(p.name for p in agent.iterdir() if p.suffix == ".mp4") == [
        "episode_0000.mp4", "episode_0001.mp4"]
    for name in ("episode_0000", "episode_0001"):
        episode = read_episode(agent / name)
        seconds = (episode.pose.t_ns[-1] - episode.pose.t_ns[0]) / 1e9
        assert len(iio.imread(agent / f"{name}.mp4")) == max(1, round(seconds * 10))
    assert f"videos: 2 in {tmp_path / 'r'}" in err.getvalue()
