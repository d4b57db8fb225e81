"""Videos of training: after each evaluation, its first episodes driven again by the same
deterministic policy with rendering on (``render_mode="rgb_array"``, the top-down view),
each an MP4 in ``<run>/videos/`` and a GIF in TensorBoard (``eval/video_<i>``).

Off unless ``eval.video_episodes`` > 0. The episodes are the evaluation's own: its env's config
and seed, so the first video shows the evaluation's first episode.
"""

from __future__ import annotations

import logging
from pathlib import Path
from typing import Any

import numpy as np
from stable_baselines3.common.callbacks import BaseCallback, EvalCallback
from stable_baselines3.common.logger import TensorBoardOutputFormat

from pic4rl_base.errors import Pic4rlError
from pic4rl_bridge.config import EnvConfig
from pic4rl_metrics.viz.video_batch import write_video

log = logging.getLogger(__name__)


def record_episode(env: Any, obs: Any, policy: Any) -> list[np.ndarray]:
    """The frames of one episode of ``env`` (``render_mode="rgb_array"``), just reset to
    ``obs``: the first, then one per step; ``policy(obs)`` gives the action."""
    frames = [env.render()]
    done = False
    while not done:
        obs, _, terminated, truncated, _ = env.step(policy(obs))
        frames.append(env.render())
        done = terminated or truncated
    return frames


def gif_summary(tag: str, frames: list[np.ndarray], fps: float) -> Any:
    """A TensorBoard summary holding ``frames`` (half size) as an animated GIF, as
    ``SummaryWriter.add_video`` writes one, without moviepy."""
    import imageio.v3 as iio
    from tensorboard.compat.proto.summary_pb2 import Summary

    small = np.stack([f[::2, ::2] for f in frames])
    data = iio.imwrite("<bytes>", small, extension=".gif", duration=1000 / fps, loop=0)
    image = Summary.Image(height=small.shape[1], width=small.shape[2], colorspace=3,
                          encoded_image_string=data)
    return Summary(value=[Summary.Value(tag=tag, image=image)])


class EvalVideoCallback(BaseCallback):
    """After each evaluation of ``evaluation`` (put this callback after it), ``episodes``
    videos of the evaluation's episodes (``env_config``, ``seed``) into ``out_dir``."""

    def __init__(self, evaluation: EvalCallback, env_config: EnvConfig, *, episodes: int,
                 seed: int, out_dir: Path) -> None:
        super().__init__()
        self.evaluation, self.env_config = evaluation, env_config
        self.episodes, self.seed, self.out_dir = episodes, seed, out_dir
        self._seen = 0
        self._env: Any = None
        self.written: list[Path] = []

    def _on_step(self) -> bool:
        done = len(self.evaluation.evaluations_results)
        if done > self._seen:
            self._seen = done
            self.record()
        return True

    def record(self) -> None:
        """Drive and write this evaluation's videos."""
        from pic4rl_bridge.env import NavEnv

        if self._env is None:
            self._env = NavEnv(self.env_config, render_mode="rgb_array")
        env, steps = self._env, self.num_timesteps
        fps = float(env.metadata["render_fps"])

        def policy(obs: Any) -> Any:
            return self.model.predict(obs, deterministic=True)[0]

        for i in range(self.episodes):
            obs, _ = env.reset(seed=self.seed if i == 0 else None)
            frames = record_episode(env, obs, policy)
            target = self.out_dir / f"eval_{steps}_steps_episode_{i}.mp4"
            try:
                write_video(frames, target, fps=fps)
            except Pic4rlError as err:
                log.warning("evaluation video not written: %s", err)
                continue
            self.written.append(target)
            self._tensorboard(f"eval/video_{i}", frames, fps, steps)

    def _tensorboard(self, tag: str, frames: list[np.ndarray], fps: float, steps: int) -> None:
        for fmt in self.model.logger.output_formats:
            if isinstance(fmt, TensorBoardOutputFormat):
                fmt.writer.file_writer.add_summary(gif_summary(tag, frames, fps), steps)
                fmt.writer.flush()

    def _on_training_end(self) -> None:
        if self._env is not None:
            self._env.close()
