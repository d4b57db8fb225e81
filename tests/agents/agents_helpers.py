"""Constants and small helpers of the agents' tests (imported as ``agents_helpers``; the
fixtures are in this folder's conftest.py)."""

from __future__ import annotations

import contextlib
import os
import shutil
import signal
import subprocess
import sys
import time
import uuid
from dataclasses import dataclass
from typing import Any
from pathlib import Path

import pytest
from ros_helpers import sim_env

ROOT = Path(__file__).resolve().parents[2]
CONFIG = ROOT / "config"
#: The previous shipped recipes (one env, ε-greedy, replay buffers in checkpoints, the pairs
#: file): the fixtures of the trainer and tester tests, which the shipped files no longer are.
LIDAR_TD3 = ROOT / "tests" / "agents" / "data" / "train_goto_lidar_td3_basic.yaml"
DEPTH_TD3 = ROOT / "tests" / "agents" / "data" / "train_goto_depth_td3_basic.yaml"

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

#: ``pic4rl-run``, as ``python -m`` (the console script runs the same ``main``).
LAUNCHER = [sys.executable, "-m", "pic4rl_agents.launch.run"]
#: Generous ROS waits: sims and trainers start slowly on a loaded machine.
ROS_TIMEOUT_S = 60.0
ROS_ARGS = ["-p", f"ros.timeout_s:={ROS_TIMEOUT_S}"]
SIM, TRAINER = "pic4rl_sim.node", "pic4rl_agents.training.train"


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


@dataclass
class Launcher:
    """One ``pic4rl-run`` process in a session of its own, its output in ``log``."""

    proc: subprocess.Popen[bytes]
    log: Path
    tag: str  # NAME=value in the environment of the launcher and of everything it starts

    @classmethod
    def start(cls, args: list[str], log: Path, domain: int) -> Launcher:
        """``pic4rl-run ARGS`` on ``domain``, tagged, its output to ``log``."""
        tag = f"PIC4RL_TEST_TAG={uuid.uuid4().hex}"
        # faulthandler on: a launcher that outlives its wait has every process's stacks dumped
        env = sim_env(domain, {**dict([tag.split("=", 1)]), "PYTHONFAULTHANDLER": "1"})
        with log.open("wb") as out:
            proc = subprocess.Popen([*LAUNCHER, *args], cwd=ROOT, env=env, stdout=out,
                                    stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL,
                                    start_new_session=True)
        return cls(proc, log, tag)

    @property
    def output(self) -> str:
        return self.log.read_text(errors="replace")

    def wait(self, timeout_s: float) -> int:
        try:
            return self.proc.wait(timeout=timeout_s)
        except subprocess.TimeoutExpired:
            self._dump_stacks()
            pytest.fail(f"pic4rl-run still running after {timeout_s} s (each process's "
                        f"Python stacks follow its output):\n{self.output}")

    def _dump_stacks(self) -> None:
        """Every process it started writes its threads' Python stacks to the log (their
        faulthandler, on SIGABRT): where a hung run waits. All are frozen first (SIGSTOP), then
        each is let go with its SIGABRT pending, one at a time, so no process sees another die
        before it has dumped, and no two dumps mix; the launcher last (its sims die with it)."""
        pids = sorted(processes_with(self.tag, "python"), key=lambda pid: pid == self.proc.pid)
        for sig in (signal.SIGSTOP, signal.SIGABRT):
            for pid in pids:
                with contextlib.suppress(ProcessLookupError):
                    os.kill(pid, sig)
        for pid in pids:
            with contextlib.suppress(ProcessLookupError):
                os.kill(pid, signal.SIGCONT)
            time.sleep(0.5)

    def left(self, needle: str = SIM) -> list[int]:
        """Pids of processes it started that are still alive (``needle`` in the command)."""
        deadline = time.monotonic() + 2.0  # a sim killed just now may take a moment to go
        while (pids := processes_with(self.tag, needle)) and time.monotonic() < deadline:
            time.sleep(0.1)
        return pids

    def stop(self, *, interrupt: bool = True) -> None:
        """The launcher stopped (Ctrl-C first when ``interrupt``, SIGKILL if it lingers) and
        anything it left behind (found by the tag) killed."""
        if self.proc.poll() is None:
            if interrupt:
                os.kill(self.proc.pid, signal.SIGINT)
            try:
                self.proc.wait(timeout=60 if interrupt else 0)
            except subprocess.TimeoutExpired:
                os.killpg(self.proc.pid, signal.SIGKILL)
                self.proc.wait()
        for pid in processes_with(self.tag, "python"):
            with contextlib.suppress(ProcessLookupError):  # gone meanwhile
                os.killpg(os.getpgid(pid), signal.SIGKILL)


def label_error(model: Any, obs: Any, labels: Any) -> float:
    """Mean squared error of ``model``'s deterministic actions against imitation's labels."""
    acted, _ = model.predict(obs, deterministic=True)
    return float(((acted - labels) ** 2).mean())


def imitation_on(run: Any, env: Any, config: Any, *, batch_size: int = 16, **kwargs: Any) -> Any:
    """An ``Imitation`` of ``config`` (an ``ImitationConfig``) on the vec env ``env`` with a new
    model of ``run``'s trainer section, no logger output and no callbacks."""
    from stable_baselines3.common.callbacks import CallbackList
    from stable_baselines3.common.logger import configure

    from pic4rl_agents.models.algorithms import new_model
    from pic4rl_agents.training.imitation import Imitation

    model = new_model(run.train, env)
    model.set_logger(configure(None, []))
    callback = CallbackList([])
    callback.init_callback(model)
    return Imitation(config, env, run.env, model, callback, batch_size=batch_size, **kwargs)
