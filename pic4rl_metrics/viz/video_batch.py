"""Episode videos of many bags: an MP4 (and a GIF) per bag, or per start–goal pair side by side.

The library behind ``pic4rl-metrics video`` and ``pic4rl-test --video``. It runs as
``compute`` does: ``jobs`` bags at a time, a bad bag becomes an error row and the rest are
rendered. A video is written to a temporary file and renamed into place, so it is whole or
absent; an existing one is kept unless ``overwrite``. imageio-ffmpeg brings its own ffmpeg.
"""

from __future__ import annotations

import logging
import os
from collections.abc import Iterable, Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from pic4rl_base import atomic
from pic4rl_base.errors import ConfigError, OutputError, Pic4rlError

from ..bags.inputs import discover
from ..bags.topics import TopicMap
from ..contract import EpisodeFacts
from ..tables.batch import BagResult, judge_bag, resolve_jobs, run_parallel
from ..tables.paired import pair_key
from .video import EpisodeScene, VideoOptions, extent, union

log = logging.getLogger(__name__)

#: The columns of the result table.
VIDEO_COLUMNS = ("bag", "video", "frames", "duration_s", "error")


@dataclass(frozen=True)
class VideoResult:
    """What became of one bag: the video showing it (``kept``: it existed and was left
    alone), its frame count and episode duration (s), or the error that stopped it."""

    bag: str
    video: str = ""
    frames: int = 0
    duration_s: float = float("nan")
    error: str = ""
    kept: bool = False


def ffmpeg_writer() -> Any:
    """imageio-ffmpeg's ``write_frames``; ``ConfigError`` saying how to install it."""
    try:
        import imageio_ffmpeg
    except ImportError as err:
        raise ConfigError("videos need imageio and imageio-ffmpeg: pip install "
                          "'pic4rl[video]' (or pip install imageio imageio-ffmpeg)") from err
    return imageio_ffmpeg.write_frames


def _publish(tmp: Path, target: Path, overwrite: bool) -> None:
    """Move the finished ``tmp`` to ``target``: replacing it only when ``overwrite``."""
    if overwrite:
        os.replace(tmp, target)
        return
    try:
        os.link(tmp, target)  # fails, leaving target alone, when it appeared meanwhile
    finally:
        tmp.unlink(missing_ok=True)


def write_video(frames: Iterable[np.ndarray], target: Path, *, fps: float,
                gif: Path | None = None, overwrite: bool = False, threads: int = 0) -> int:
    """Encode ``frames`` (equal ``uint8`` height × width × 3) as H.264 MP4 at ``target``, and
    at half size as a GIF at ``gif``; the number of frames. ``threads``: ffmpeg's (0: its
    choice). Raises ``OutputError`` naming the file that cannot be written."""
    write_frames = ffmpeg_writer()
    target.parent.mkdir(parents=True, exist_ok=True)
    small: list[np.ndarray] = []
    count = 0
    try:
        with atomic.temporary(target) as tmp:
            writer = None
            for frame in frames:
                if writer is None:
                    writer = write_frames(
                        str(tmp), (frame.shape[1], frame.shape[0]), fps=fps, codec="libx264",
                        macro_block_size=16, ffmpeg_log_level="error",
                        output_params=["-preset", "veryfast", "-threads", str(threads)])
                    writer.send(None)
                writer.send(np.ascontiguousarray(frame))
                if gif is not None:
                    small.append(frame[::2, ::2].copy())
                count += 1
            if writer is not None:
                writer.close()
            _publish(tmp, target, overwrite)
        if gif is not None:
            _write_gif(small, gif, fps=fps, overwrite=overwrite)
    except OSError as err:
        raise OutputError(f"{str(target)!r}: cannot write the video: "
                          f"{err.strerror or err}") from err
    except RuntimeError as err:  # imageio-ffmpeg: ffmpeg failed
        raise OutputError(f"{str(target)!r}: ffmpeg failed: {err}") from err
    return count


def _write_gif(frames: Sequence[np.ndarray], target: Path, *, fps: float,
               overwrite: bool) -> None:
    import imageio.v3 as iio

    with atomic.temporary(target) as tmp:
        iio.imwrite(tmp, np.stack(frames), extension=".gif", duration=1000 / fps, loop=0)
        _publish(tmp, target, overwrite)


def video_names(bags: Sequence[Path]) -> dict[Path, str]:
    """A file stem per bag: its name, or, where names repeat (``<agent>/episode_0000``), its
    path below the bags' common folder joined with ``_``."""
    stems = {bag: bag.name.removesuffix(".db3").removesuffix(".mcap") for bag in bags}
    if len(set(stems.values())) == len(stems):
        return stems
    absolute = {bag: bag.resolve() for bag in bags}
    common = Path(os.path.commonpath([str(p.parent) for p in absolute.values()]))
    return {bag: "_".join(absolute[bag].relative_to(common).with_suffix("").parts)
            for bag in bags}


@dataclass(frozen=True)
class _Reading:
    """How bags are read: the topic map and the facts given on the command line."""

    topic_map: TopicMap | None = None
    facts: EpisodeFacts | None = None
    given: frozenset[str] = frozenset()

    def judge(self, bag: Path) -> BagResult:
        """The bag's episode and outcome (no other metric), or its error."""
        return judge_bag(bag, self.topic_map, self.facts, self.given, metrics=("outcome",),
                         full_scans=True)


@dataclass(frozen=True)
class _Job:
    """One video: its bags (one, or a start–goal pair's), read here or judged already, and
    where it goes."""

    sources: tuple[Path | BagResult, ...]
    reading: _Reading
    target: Path
    options: VideoOptions
    overwrite: bool
    threads: int


def _render(job: _Job) -> list[VideoResult]:
    """Write one video; one row per bag in it (every failure becomes the rows' error)."""
    if job.target.exists() and not job.overwrite:
        return [VideoResult(str(s if isinstance(s, Path) else s.bag), str(job.target),
                            kept=True) for s in job.sources]
    results = [s if isinstance(s, BagResult) else job.reading.judge(s) for s in job.sources]
    if any(r.error for r in results):
        return [VideoResult(r.bag, error=r.error) for r in results]
    gif = job.target.with_suffix(".gif") if job.options.gif else None
    episodes = [r.episode for r in results if r.episode is not None]
    outcomes = [r.metrics.outcome if r.metrics is not None else None for r in results]
    try:
        bounds = union([extent(ep) for ep in episodes]) if len(episodes) > 1 else None
        scenes = [EpisodeScene(ep, job.options, outcome=o, bounds=bounds)
                  for ep, o in zip(episodes, outcomes)]
        frames = scenes[0].frames() if len(scenes) == 1 else side_by_side(scenes)
        count = write_video(frames, job.target, fps=job.options.fps, gif=gif,
                            overwrite=job.overwrite, threads=job.threads)
    except Pic4rlError as err:
        return [VideoResult(r.bag, error=str(err)) for r in results]
    return [VideoResult(r.bag, str(job.target), count, s.duration_s)
            for r, s in zip(results, scenes)]


def side_by_side(scenes: Sequence[EpisodeScene], columns: int = 3) -> Iterator[np.ndarray]:
    """Frames of several scenes in a grid of at most ``columns`` columns, as long as the
    longest; a finished scene holds its last frame, an empty cell is white."""
    streams = [scene.frames() for scene in scenes]
    last: list[np.ndarray | None] = [None] * len(scenes)
    n_cols = min(columns, len(scenes))
    n_rows = -(-len(scenes) // n_cols)
    for _ in range(max(scene.n_frames for scene in scenes)):
        for i, stream in enumerate(streams):
            last[i] = next(stream, last[i])
        blank = np.full_like(last[0], 255)
        cells = [*last, *[blank] * (n_rows * n_cols - len(last))]
        yield np.vstack([np.hstack(cells[r * n_cols:(r + 1) * n_cols]) for r in range(n_rows)])


def _pairs(judged: Sequence[BagResult]) -> list[list[BagResult]]:
    """Judged bags grouped by start–goal pair, in bag order; a bag without one alone."""
    groups: dict[object, list[BagResult]] = {}
    for result in judged:
        key = pair_key(result)
        groups.setdefault(key if key is not None else result.bag, []).append(result)
    return list(groups.values())


def render_videos(inputs: Iterable[str | Path], out: Path | None = None, *,
                  options: VideoOptions = VideoOptions(), topic_map: TopicMap | None = None,
                  facts: EpisodeFacts | None = None, given: frozenset[str] = frozenset(),
                  jobs: int = 1, progress: bool = False, grid: bool = False,
                  overwrite: bool = False) -> tuple[VideoResult, ...]:
    """A video per bag named by ``inputs`` (``inputs.discover``) into ``out`` (``None``: each
    beside its bag, ``<bag>.mp4``), ``jobs`` at a time (0: one per core); with ``grid``, one
    per start–goal pair with its bags side by side (``pair_NN.mp4``). One row per bag, in
    bag order; inputs that name no bag and bags that cannot be read are error rows."""
    jobs = resolve_jobs(jobs)
    ffmpeg_writer()  # a missing encoder is said once, before any work
    found = discover(inputs)
    rows = [VideoResult(item, error=f"{item!r}: {why}") for item, why in found.unmatched]
    for note in found.skipped:
        log.warning(note)
    names = video_names(list(found.bags))
    reading = _Reading(topic_map, facts, given)
    threads = 1 if jobs > 1 else 0

    def target(bag: Path, stem: str | None = None) -> Path:
        folder = out if out is not None else bag.parent
        return folder / f"{stem or (names[bag] if out is not None else bag.name)}.mp4"

    if not grid:
        work = [_Job((bag,), reading, target(bag), options, overwrite, threads)
                for bag in found.bags]
    else:
        judged = run_parallel(reading.judge, list(found.bags), jobs=jobs, progress=progress,
                              what="bags")
        rows += [VideoResult(r.bag, error=r.error) for r in judged if r.error]
        work, pairs = [], 0
        for group in _pairs([r for r in judged if not r.error]):
            pairs += len(group) > 1
            stem = f"pair_{pairs:02d}" if len(group) > 1 else None
            work.append(_Job(tuple(group), reading, target(Path(group[0].bag), stem), options,
                             overwrite, threads))
    for made in run_parallel(_render, work, jobs=jobs, progress=progress, what="videos"):
        rows += made
    order = {str(bag): i for i, bag in enumerate(found.bags)}
    return tuple(sorted(rows, key=lambda r: order.get(r.bag, -1)))
