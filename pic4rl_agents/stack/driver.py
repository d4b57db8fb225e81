"""Driving episodes with a ROS 2 stack as the agent: ``drive_stack``.

The env is ``NavEnv`` over the ROS transport, with ``StackTransport`` relaying the stack's
commands in place of its own: the sim node listens on ``sim/cmd_vel``; a lockstep step waits
for the stack's answer to the last frame on ``cmd_vel`` and forwards it (so the env sees and
judges every step, as for any agent), a realtime step forwards the latest command each
control period of wall time; the bag records the stack's commands as ``/cmd_vel``.
A stack that sends nothing for ``silence_s``, exits, or sends a non-finite command ends the
episode ``aborted`` with that reason (``StaleSensor``, which the env turns into ``aborted``);
one that does not start within ``start_timeout_s`` raises ``StackError`` (the cell fails).
"""

from __future__ import annotations

import contextlib
import math
import os
import signal
import subprocess
import sys
import time
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

import numpy as np
from geometry_msgs.msg import Twist
from rclpy.qos import qos_profile_sensor_data
from std_srvs.srv import Empty

from pic4rl_bridge.config import StepMode
from pic4rl_bridge.env import NavEnv
from pic4rl_bridge.errors import BridgeError, StaleSensor, TransportError
from pic4rl_bridge.transports.ros_transport import RosTransport
from pic4rl_sim.engine.geometry import Twist2D

from pic4rl_agents.launch.simproc import start_child, stop_group
from .spec import StackSpec

#: The stack's topic, and the sim's (remapped) command topic that the env forwards it to.
STACK_CMD_VEL, SIM_CMD_VEL = "cmd_vel", "sim/cmd_vel"
#: Seconds the first step of an episode waits before it steps the sim with a stop.
_NUDGE_S = 1.0


class StackError(BridgeError):
    """The stack did not start (one line: the command and what was missing)."""


class StackTransport(RosTransport):
    """The ROS transport relaying a stack's commands: the sim listens on ``sim/cmd_vel``
    (``SIM_CMD_VEL``), the stack publishes ``cmd_vel``; each step forwards the stack's latest
    command to the sim (the env's own action is ignored), so the env sees, judges and records
    every step, and a non-finite command never reaches the sim."""

    def __init__(self, *args: Any, stack: StackSpec, failure: Callable[[], str | None],
                 **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self._stack, self._failure = stack, failure
        self._commands, self._bad = 0, None  # commands heard; the first non-finite one
        self._mark = 0  # commands heard when the last frame was asked for
        self._first = True  # no answer from the stack yet this episode
        self._since = time.monotonic()
        self._latest = Twist2D()
        self._last_command_s = time.monotonic()
        sub = self.node.create_subscription(Twist, STACK_CMD_VEL, self._on_command,
                                            qos_profile_sensor_data)
        self.stack_topic = sub.topic_name
        self._cmd_name = self.stack_topic  # bags record the stack's commands as cmd_vel
        if self._mode is StepMode.RATE:
            self._dt_s /= stack.real_time_factor  # a control period of wall time

    def _on_command(self, msg: Twist) -> None:
        values = (msg.linear.x, msg.linear.y, msg.angular.z)
        if self._bad is None and not all(math.isfinite(v) for v in values):
            self._bad = f"stack {self._stack.name} sent a non-finite cmd_vel {values!r}"
        self._latest = Twist2D(*values)
        self._commands += 1
        self._last_command_s = time.monotonic()

    def _bag_time(self, stamp_ns: int) -> int:
        """Sim time in both clocks: the sim stamps every message, so bags are in sim time."""
        return stamp_ns

    def problem(self) -> str | None:
        """Why the stack cannot go on (exited, non-finite command), or ``None``."""
        return self._bad or self._failure()

    def reset(self, request: Any) -> Any:
        self._mark = self._commands  # the stack may answer the reset's frame before it returns
        frame = super().reset(request)
        self._bad, self._first, self._since = None, True, time.monotonic()
        self._last_command_s = time.monotonic()
        return frame

    def step(self, command: Twist2D) -> Any:
        if self._mode is StepMode.RATE:  # the sim steps on its timer with the latest command
            if self.problem() is not None:
                raise StaleSensor(str(self.problem()))
            if time.monotonic() - self._last_command_s > self._stack.silence_s:
                raise StaleSensor(f"stack {self._stack.name} sent no cmd_vel within "
                                  f"{self._stack.silence_s:g} s")
            return super().step(self._latest)
        answered = lambda: self._commands > self._mark or self.problem() is not None  # noqa: E731
        if self._first and time.monotonic() - self._since < self._stack.silence_s:
            # a stack started just now may have missed the reset's frame: a stop step
            with contextlib.suppress(TransportError):  # brings it another one
                self._spin_until(answered, _NUDGE_S, "cmd_vel")
            if not answered():
                return super().step(Twist2D())
        self._first = False
        try:  # the stack's answer to the last frame
            self._spin_until(answered, self._stack.silence_s, "cmd_vel")
        except TransportError as err:
            raise StaleSensor(f"stack {self._stack.name} sent no cmd_vel within "
                              f"{self._stack.silence_s:g} s") from err
        if self._bad is not None or self._commands == self._mark:
            raise StaleSensor(str(self.problem()))
        self._mark = self._commands  # later ones answer the frame this step brings
        return super().step(self._latest)


class StackEnv(NavEnv):
    """``NavEnv`` whose transport is a ``StackTransport``."""

    def __init__(self, *args: Any, stack: StackSpec, failure: Callable[[], str | None],
                 **kwargs: Any) -> None:
        self._stack_args = {"stack": stack, "failure": failure}
        super().__init__(*args, **kwargs)

    def _make_transport(self, sensors: frozenset[str], node: Any) -> StackTransport:
        return StackTransport(self.config, self.scenario, sensors, node=node,
                              **self._stack_args)


class StackProcess:
    """The user's command: started in its own process group (killed with this process),
    stopped with its whole group."""

    def __init__(self, stack: StackSpec, env: Mapping[str, str], cwd: Path) -> None:
        self.stack, self._env, self._cwd = stack, dict(env), cwd
        self.proc: subprocess.Popen[bytes] | None = None

    def start(self) -> None:
        here = Path.cwd()
        os.chdir(self._cwd)  # start_child has no cwd: the command runs from the suite's folder
        try:
            self.proc = start_child(self.stack.command, self._env)
        except OSError as err:
            raise StackError(f"stack {self.stack.name}: cannot start "
                             f"{' '.join(self.stack.command)!r}: {err}") from err
        finally:
            os.chdir(here)

    def failure(self) -> str | None:
        if self.proc is not None and self.proc.poll() is not None:
            return f"stack {self.stack.name} exited with code {self.proc.returncode}"
        return None

    def stop(self) -> None:
        if self.proc is not None:  # its group, even when its leader has exited already
            stop_group(self.proc, 5.0)
            with contextlib.suppress(ProcessLookupError):
                os.killpg(self.proc.pid, signal.SIGKILL)
            self.proc = None


def _wait_ready(env: StackEnv, stack: StackProcess) -> None:
    """Until the stack publishes ``cmd_vel`` and subscribes to the sync topic (scan)."""
    transport: StackTransport = env.transport  # type: ignore[assignment]
    node, spec = transport.node, stack.stack
    cmd, sync = transport.stack_topic, transport._topics[transport._sync_topic].name
    deadline = time.monotonic() + spec.start_timeout_s
    while time.monotonic() < deadline:
        if stack.failure() is not None:
            raise StackError(f"{stack.failure()} before it started")
        if node.count_publishers(cmd) > 0 and node.count_subscribers(sync) > 1:
            settle = time.monotonic() + 0.3  # the sim matches the stack's subscription too
            while time.monotonic() < settle:
                transport._executor.spin_once(timeout_sec=0.05)
            return
        transport._executor.spin_once(timeout_sec=0.1)
    raise StackError(f"stack {spec.name}: {' '.join(spec.command)!r} did not start within "
                     f"{spec.start_timeout_s:g} s (no publisher on {cmd} and subscriber on "
                     f"{sync} besides the sim's and the env's)")


def _wait_gone(env: StackEnv, timeout_s: float = 5.0) -> None:
    """Until the graph forgets the stopped stack's ``cmd_vel`` publisher (else the next
    process would look started before it is)."""
    transport: StackTransport = env.transport  # type: ignore[assignment]
    deadline = time.monotonic() + timeout_s
    while (transport.node.count_publishers(transport.stack_topic) > 0
           and time.monotonic() < deadline):
        transport._executor.spin_once(timeout_sec=0.05)


def _call(env: StackEnv, service: str, what: str) -> None:
    """Call the ``std_srvs/Empty`` service ``service`` (relative: in the env's namespace)."""
    transport: StackTransport = env.transport  # type: ignore[assignment]
    client = transport.node.create_client(Empty, service)
    try:
        transport._call(client, Empty.Request(), what)
    finally:
        transport.node.destroy_client(client)


def drive_stack(stack: StackSpec, config: Any, *, overrides: Mapping[str, Any],
                episodes: int, seed: int, domain: int, cwd: Path,
                sim_file: Path) -> list[str]:
    """Drive ``episodes`` episodes of ``stack`` in the env of ``config`` (a ``Scenario``, an
    ``EnvConfig`` or a params file; + ``overrides``): the sim node (its resolved params written
    to ``sim_file``) and the stack in ROS domain ``domain``, both stopped at the end; the
    episodes' outcomes in order. The config is resolved once (a ``Scenario`` is used as it is)."""
    from pic4rl_base import params_file
    from pic4rl_bridge.config import EnvConfig, load_env_config
    from pic4rl_bridge.recording import record_from_config
    from pic4rl_bridge.scenario import Scenario

    ros_env = {**os.environ, "ROS_DOMAIN_ID": str(domain), "ROS_AUTOMATIC_DISCOVERY_RANGE":
               os.environ.get("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")}
    realtime = stack.clock == "realtime"
    given = config if isinstance(config, Scenario) else None
    base = given.config if given else (
        config if isinstance(config, EnvConfig) else load_env_config(config))
    env_config = base.replace(**{**overrides, "agent": stack.name, "transport": "ros",
                                 "ros.domain_id": domain, "topics.cmd_vel": SIM_CMD_VEL,
                                 "ros.step_mode": "rate" if realtime else "lockstep"})
    clock = ({"clock_mode": "realtime", "real_time_factor": stack.real_time_factor}
             if realtime else {"clock_mode": "lockstep"})
    scenario = given.for_env(env_config) if given else Scenario(env_config)
    sim_file.write_text(params_file.dump({"/**": {**scenario.node_values, **clock}}))
    # The sim and the stack start before the env is built: their start-up (seconds of DDS
    # discovery, the longest part of a short run) goes on while it is.
    sim = start_child([sys.executable, "-m", "pic4rl_sim.node", "--ros-args",
                       "--params-file", str(sim_file), "-r", f"cmd_vel:={SIM_CMD_VEL}"],
                      ros_env)
    process = StackProcess(stack, ros_env, cwd)
    env: StackEnv | None = None
    recorded: Any = None  # the env, in RecordEpisodes when record.enabled
    outcomes: list[str] = []
    try:
        process.start()
        env = StackEnv(scenario, stack=stack, failure=process.failure)
        recorded = record_from_config(env) if env_config.record.enabled else env
        action = np.zeros(env.action_space.shape, dtype=np.float32)
        fresh = True  # a stack started and not yet seen ready
        for episode in range(episodes):
            if process.proc is None:
                process.start()
                fresh = True
            if fresh:
                _wait_ready(env, process)
                fresh = False
            elif stack.reset_service:
                _call(env, stack.reset_service, "the stack's reset")
            recorded.reset(seed=seed if episode == 0 else None)
            done, info = False, {}
            while not done:
                _, _, terminated, truncated, info = recorded.step(action)
                done = terminated or truncated
            outcomes.append(str(info.get("outcome")))
            if stack.restart == "episode" or process.failure() is not None:
                process.stop()
                _wait_gone(env)
    finally:
        process.stop()
        if recorded is not None:  # (a recorder that failed to start closed the env)
            recorded.close()
        stop_group(sim, 10.0)
    return outcomes
