"""Constants and small helpers of the agents' tests (imported as ``agents_helpers``; the
fixtures are in this folder's conftest.py)."""

from __future__ import annotations

import os
import shutil
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
CONFIG = ROOT / "config"
LIDAR_TD3 = CONFIG / "train_goto_lidar_td3.yaml"
DEPTH_TD3 = CONFIG / "train_goto_depth_td3.yaml"

#: Trainer overrides (``--hyperparams``) for runs that take seconds: tiny nets, a short warm-up,
#: a small buffer, one-episode evaluations, no TensorBoard.
TINY = ["policy.net_arch:[16]", "policy.critic_arch:[16]", "batch_size:32",
        "learning_starts:50", "buffer_size:5000", "eval.episodes:1", "tensorboard:false"]
#: Env overrides (``--env-kwargs``): short episodes, so a few hundred steps finish several.
SHORT_EPISODES = ["episode_max_steps:60"]

TRAINED_STEPS = 300
CHECKPOINT_STEPS = 100
EVAL_STEPS = 150
PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


@dataclass(frozen=True)
class TrainedRun:
    """The session's short training run: its directory and what ``train.main`` returned."""

    run_dir: Path
    code: int
    stderr: str

    def copy_to(self, parent: Path) -> Path:
        """A private copy (same run name) under ``parent``, for tests that change it."""
        target = parent / self.run_dir.name
        shutil.copytree(self.run_dir, target)
        return target


def processes_with(tag: str, needle: str) -> list[int]:
    """Pids of live processes whose environment holds ``tag`` (``NAME=value``) and whose
    command line contains ``needle``: how a test finds the sims its launcher started (they
    run in sessions of their own, so no process group reaches them)."""
    found = []
    for entry in os.scandir("/proc"):
        if not entry.name.isdigit():
            continue
        try:
            with open(f"/proc/{entry.name}/cmdline", "rb") as f:
                cmdline = f.read().replace(b"\0", b" ").decode(errors="replace")
            with open(f"/proc/{entry.name}/environ", "rb") as f:
                environ = f.read().split(b"\0")
            with open(f"/proc/{entry.name}/stat", "rb") as f:
                state = f.read().rsplit(b")", 1)[1].split()[0]
        except OSError:  # gone meanwhile, or not ours to read
            continue
        if state != b"Z" and needle in cmdline and tag.encode() in environ:
            found.append(int(entry.name))
    return found
