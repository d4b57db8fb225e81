"""Sim nodes as child processes, and the ROS domains they run in: what ``pic4rl-run`` and a
``transport: ros`` benchmark cell share.

A sim is started in its own session (Ctrl-C at a terminal reaches the trainer or tester
first; ``stop_group`` stops the sim after it) and dies with the process that started it
(Linux's parent-death signal): a worker SIGKILLed mid-cell leaves no sim publishing into a
domain that its retry, or another suite, takes next.

``domain_lease`` gives a cell a ROS domain that no other holder on this machine has, for as
long as the cell runs: one lock file per domain under ``/tmp/pic4rl-ros-domains/`` (a fixed
place, whatever ``TMPDIR`` says: DDS domains are the machine's), held with
``flock`` (the kernel drops it when its holder dies, SIGKILL included). The domains tried are
those after the user's ``ROS_DOMAIN_ID`` (0 if unset), wrapping within 1-101 (DDS's usable
ids with the default port mapping), the user's own never.
"""

from __future__ import annotations

import contextlib
import ctypes
import fcntl
import os
import signal
import subprocess
import sys
from collections.abc import Callable, Iterator, Mapping, Sequence
from pathlib import Path

from pic4rl_bridge.errors import ConfigError

#: The ROS domain ids a lease chooses from.
DOMAIN_IDS = range(1, 102)
LOCKS = Path("/tmp/pic4rl-ros-domains")
_PR_SET_PDEATHSIG = 1


def _die_with(parent: int) -> Callable[[], None]:
    """A ``preexec_fn``: the child gets SIGKILL when ``parent`` dies (exits at once if it has
    already, between the fork and this call). Resolved before the fork."""
    prctl = ctypes.CDLL(None, use_errno=True).prctl

    def set_death_signal() -> None:
        prctl(_PR_SET_PDEATHSIG, signal.SIGKILL)
        if os.getppid() != parent:
            os._exit(1)

    return set_death_signal


def start_child(argv: Sequence[str], env: Mapping[str, str]) -> subprocess.Popen[bytes]:
    """``argv`` in its own session (``stop_group`` stops its whole group), killed when this
    process dies: a sim node, or a user's ROS 2 stack (``pic4rl_agents.stack``)."""
    return subprocess.Popen(list(argv), env=dict(env), start_new_session=True,
                            preexec_fn=_die_with(os.getpid()))


def start_sim(ros_args: Sequence[str], env: Mapping[str, str]) -> subprocess.Popen[bytes]:
    """``python -m pic4rl_sim.node --ros-args *ros_args`` in its own session, killed when
    this process dies."""
    return start_child([sys.executable, "-m", "pic4rl_sim.node", "--ros-args", *ros_args], env)


def stop_group(proc: subprocess.Popen[bytes], timeout_s: float) -> int:
    """SIGINT to ``proc``'s group, then SIGKILL if it lingers; its exit code."""
    if proc.poll() is None:
        try:
            os.killpg(proc.pid, signal.SIGINT)
            proc.wait(timeout=timeout_s)
        except subprocess.TimeoutExpired:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()
        except ProcessLookupError:
            proc.wait()
    return proc.returncode


def user_domain() -> int:
    """The user's ``ROS_DOMAIN_ID`` (0 when unset)."""
    text = os.environ.get("ROS_DOMAIN_ID", "").strip() or "0"
    if not text.isdigit():
        raise ConfigError(f"ROS_DOMAIN_ID={text!r}: expected an integer from 0 to 232")
    return int(text)


def _lock_dir() -> Path:
    """The lock files' folder, shared by every user of this machine (DDS domains are)."""
    if not LOCKS.is_dir():
        with contextlib.suppress(FileExistsError):
            LOCKS.mkdir()
        with contextlib.suppress(PermissionError):
            LOCKS.chmod(0o1777)
    return LOCKS


@contextlib.contextmanager
def domain_lease(base: int | None = None) -> Iterator[int]:
    """The first ROS domain after ``base`` (default ``user_domain()``) that no other lease on
    this machine holds, held until the block ends; ``ConfigError`` when all are held."""
    base = user_domain() if base is None else base
    folder = _lock_dir()
    n = len(DOMAIN_IDS)
    order = [DOMAIN_IDS[(base - DOMAIN_IDS[0] + 1 + k) % n] for k in range(n)]
    for domain in (d for d in order if d != base):
        fd = os.open(folder / f"domain_{domain}.lock", os.O_RDONLY | os.O_CREAT, 0o644)
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            os.close(fd)
            continue
        try:
            yield domain
        finally:
            os.close(fd)  # releases the lock
        return
    raise ConfigError(f"no free ROS domain: all of {DOMAIN_IDS[0]}-{DOMAIN_IDS[-1]} are held "
                      f"by other runs (lock files in {folder})")
