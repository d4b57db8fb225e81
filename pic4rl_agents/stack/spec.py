"""``StackSpec``: what a ``stack:`` key says (``pic4rl-run stack``'s options make one).

    stack: {command: "python my_node.py", name: my_stack, clock: lockstep, restart: episode}

``command`` (required): the command line, split as a shell would (no shell features), run
from the current folder. ``name``: the agent's name in bags and tables (default
``stack``). ``clock``: ``lockstep`` (the sim steps on each ``cmd_vel``: stacks that answer
each scan) or ``realtime`` (the sim steps on a wall-clock timer at ``real_time_factor``
and publishes ``/clock``: timer-driven stacks with ``use_sim_time``). ``restart``:
``episode`` (a fresh process each episode) or ``never`` (one process for the cell; then
``reset_service``, a ``std_srvs/Empty`` the stack offers, is called before each episode
when given). ``start_timeout_s``: how long the command may take to publish ``cmd_vel`` and
subscribe ``scan``; ``silence_s``: wall seconds without a command before the episode ends
``aborted``.
"""

from __future__ import annotations

import shlex
from collections.abc import Mapping
from dataclasses import dataclass, fields
from typing import Any

from pic4rl_bridge.errors import ConfigError

CLOCKS = ("lockstep", "realtime")
RESTARTS = ("episode", "never")


@dataclass(frozen=True)
class StackSpec:
    """A ROS 2 stack to start as a cell's agent (see the module's docstring)."""

    command: tuple[str, ...]
    name: str = "stack"
    clock: str = "lockstep"
    restart: str = "episode"
    reset_service: str = ""
    real_time_factor: float = 10.0
    start_timeout_s: float = 30.0
    silence_s: float = 5.0


_KEYS = tuple(f.name for f in fields(StackSpec))


def stack_spec(raw: Any, where: str) -> StackSpec:
    """``raw`` (a ``stack:`` mapping) checked; ``ConfigError`` in one line naming ``where``
    (e.g. ``suite.yaml: tasks[0].stack``) and what was expected."""
    if not isinstance(raw, Mapping):
        raise ConfigError(f"{where}: expected a mapping with a 'command', got {raw!r}")
    unknown = sorted(set(raw) - set(_KEYS))
    if unknown:
        raise ConfigError(f"{where}: unknown key {unknown[0]!r}; expected one of "
                          f"{', '.join(_KEYS)}")
    command = raw.get("command")
    if not isinstance(command, str) or not command.strip():
        raise ConfigError(f"{where}.command: expected a command line, got {command!r}")
    try:
        argv = tuple(shlex.split(command))
    except ValueError as err:
        raise ConfigError(f"{where}.command: {command!r}: {err}") from err
    values: dict[str, Any] = {"command": argv}
    name = raw.get("name", "stack")
    if not isinstance(name, str) or not name or "/" in name or name.startswith("."):
        raise ConfigError(f"{where}.name: expected a name for the bags' folder, got {name!r}")
    values["name"] = name
    for key, choices in (("clock", CLOCKS), ("restart", RESTARTS)):
        value = raw.get(key, getattr(StackSpec, key))
        if value not in choices:
            raise ConfigError(f"{where}.{key}: {value!r}; expected one of {', '.join(choices)}")
        values[key] = value
    service = raw.get("reset_service", "")
    if not isinstance(service, str):
        raise ConfigError(f"{where}.reset_service: expected a service name, got {service!r}")
    values["reset_service"] = service
    for key in ("real_time_factor", "start_timeout_s", "silence_s"):
        value = raw.get(key, getattr(StackSpec, key))
        if isinstance(value, bool) or not isinstance(value, (int, float)) or value <= 0:
            raise ConfigError(f"{where}.{key}: expected a positive number, got {value!r}")
        values[key] = float(value)
    return StackSpec(**values)
