"""The ``sim`` node process the ROS 2 benchmarks time against: its own process group, stopped
with SIGINT as ``pic4rl-run`` stops it, killed if it has not stopped within 10 s."""

from __future__ import annotations

import os
import signal
import subprocess
import sys


def start_sim(domain: int, *ros_args: str) -> subprocess.Popen[bytes]:
    """``python -m pic4rl_sim.node --ros-args *ros_args`` on ROS domain ``domain``, discovery
    kept on localhost."""
    env = {**os.environ, "ROS_DOMAIN_ID": str(domain),
           "ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST"}
    return subprocess.Popen([sys.executable, "-m", "pic4rl_sim.node", "--ros-args", *ros_args],
                            env=env, start_new_session=True, stdout=subprocess.DEVNULL,
                            stderr=subprocess.PIPE)


def cpu_s(pid: int) -> float:
    """CPU time (s, user + system) the process ``pid`` has used so far, from ``/proc`` (10 ms
    ticks; 0 where there is no ``/proc``). Per-step CPU of both lockstep processes moves less
    with a shared machine's load than their wall time does."""
    try:
        with open(f"/proc/{pid}/stat") as f:
            fields = f.read().rsplit(")", 1)[1].split()
    except OSError:
        return 0.0
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def stop_sim(proc: subprocess.Popen[bytes]) -> None:
    if proc.poll() is None:
        try:
            os.killpg(proc.pid, signal.SIGINT)
            proc.wait(timeout=10)
        except subprocess.TimeoutExpired:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()
        except ProcessLookupError:
            proc.wait()
