"""The suite file's checks (``pic4rl_agents.suites.suite`` reads the file with them): each key's
value, and what only a cell would otherwise find, built before any cell runs (every agent,
baseline and stack resolved, every world, variant and robot built, every pairs file's world);
a wrong one is a ``ConfigError`` in one line naming the file and the key.
"""

from __future__ import annotations

import re
import shutil
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from pic4rl_agents.stack.spec import StackSpec, stack_spec
from pic4rl_agents.testing.plan import TestPlan, resolve_agents
from pic4rl_base import params_file
from pic4rl_bridge.baselines import BASELINES
from pic4rl_bridge.config import TransportName
from pic4rl_bridge.errors import ConfigError, require, unknown_key

_NAME = re.compile(r"[A-Za-z0-9_.]+")
#: An agent entry that names a ROS 2 stack instead of a checkpoint or plugin.
STACK_KEYS = ("stack",)


def keys(data: Any, known: tuple[str, ...], where: str) -> Mapping[str, Any]:
    if not isinstance(data, Mapping):
        raise ConfigError(f"{where}: {data!r} is invalid; expected a mapping of "
                          f"{', '.join(known)}")
    for key in data:
        if key not in known:
            raise unknown_key(str(key), known, where=where)
    return data


def name(value: Any, where: str) -> str:
    require(isinstance(value, str) and bool(_NAME.fullmatch(value)), where, value,
            "a name of letters, digits, '_' and '.'")
    return value


def count(value: Any, where: str, low: int = 1) -> int:
    require(isinstance(value, int) and not isinstance(value, bool) and value >= low, where,
            value, f"an integer >= {low}")
    return value


def path(value: Any, where: str, base: Path) -> str:
    require(isinstance(value, str) and bool(value), where, value, "a file path")
    found = Path(value) if Path(value).exists() or Path(value).is_absolute() else base / value
    require(found.exists(), where, value, "an existing file or directory")
    return str(found.absolute())


def items(data: Mapping[str, Any], key: str, where: str, default: list[Any]) -> list[Any]:
    value = data.get(key, default)
    require(isinstance(value, list), f"{where}.{key}", value, "a list")
    return value


def _agent(value: Any, where: str, base: Path) -> str:
    """An agent's location: a checkpoint (``path``), a plugin ``FILE.py:NAME`` (its file
    relative to the suite file, made absolute: a worker imports it by the same reference), or
    ``package.module:NAME`` and an entry point as given (``pic4rl_agents.testing.policies``)."""
    from pic4rl_agents.testing.policies import is_plugin

    if not (isinstance(value, str) and is_plugin(value)):
        return path(value, where, base)
    target, _, attr = value.rpartition(":")
    return f"{path(target, where, base)}:{attr}" if target.endswith(".py") else value


def _stack(row: str, value: Mapping[str, Any], where: str, base: Path) -> StackSpec:
    """``{stack: {command, ...}}`` (``pic4rl_agents.stack.spec``), named by its row; its
    program found on the PATH or, relative, in the suite file's folder (where it runs)."""
    raw = keys(value, STACK_KEYS, where)["stack"]
    if isinstance(raw, Mapping) and raw.get("name", row) != row:
        raise ConfigError(f"{where}.stack.name: {raw['name']!r}; a suite's stack is named by "
                          f"its agents key ({row!r}): leave name out")
    spec = stack_spec({**raw, "name": row} if isinstance(raw, Mapping) else raw,
                      f"{where}.stack")
    program = spec.command[0]
    require(shutil.which(program) is not None or (base / program).is_file(),
            f"{where}.stack.command", program, "a program on the PATH or a file beside the "
            "suite file")
    return spec


def agent_rows(data: Mapping[str, Any], where: str, base: Path, env: str,
               robots: list[str]) -> list[tuple[str, str, StackSpec | None]]:
    """(row name, agent path: empty for a baseline or stack, the stack) of the task, each
    agent and baseline resolved on each of the task's ``robots`` as its cells will run it,
    and each stack checked, before any runs."""
    agents = data.get("agents", {})
    require(isinstance(agents, Mapping), f"{where}.agents", agents,
            "a mapping NAME: PATH or NAME: {stack: {command, ...}}")
    rows: list[tuple[str, str, StackSpec | None]] = []
    for n, p in agents.items():
        row, at = name(n, f"{where}.agents"), f"{where}.agents.{n}"
        rows.append((row, "", _stack(row, p, at, base)) if isinstance(p, Mapping)
                    else (row, _agent(p, at, base), None))
    for b in items(data, "baselines", where, []):
        require(b in BASELINES, f"{where}.baselines", b, f"one of {', '.join(BASELINES)}")
        rows.append((b, "", None))
    require(bool(rows), where, dict(data), "at least one of agents, baselines")
    for row, agent, stack in rows:
        for robot in robots if stack is None else ():
            plan = TestPlan(agents=(f"{row}={agent}",) if agent else (),
                            baselines=() if agent else (row,), params_files=(env,),
                            sim_overrides={"robot": robot} if robot else {})
            try:
                resolve_agents(plan)
            except ConfigError as err:
                key = f"agents.{row}" if agent else "baselines"
                raise ConfigError(f"{where}.{key}: {err}") from err
    return rows


def check_worlds(env: str, worlds: list[tuple[str, int | None, str]], robots: list[str],
                 where: str) -> None:
    """Every robot, world and variant of the task built as its cells will build them (the
    env file's sim section with the cell's world, variant and robot), before any cell runs:
    ``ConfigError`` naming the robot or the world (``WORLD:VARIANT``) otherwise."""
    from pic4rl_agents.runs.config import NODES, run_config
    from pic4rl_bridge.scenario import Scenario

    files = params_file.load([env], NODES)  # read once; each cell's sim overrides on it
    test = {"transport": TransportName.INPROCESS.value, "robot": "", "episodes.file": "",
            "episodes.world_variants": ""}

    def built(key: str, shown: str, **sim: Any) -> None:
        given = {k: v for k, v in sim.items() if v not in ("", None)}
        try:
            Scenario(run_config(files, [env], env=test, sim=given).env).world_at(None)
        except ConfigError as err:
            raise ConfigError(f"{where}.{key}: {shown}: {err}") from err

    for robot in robots:
        built("robots", robot, robot=robot)
    for world, variant in dict.fromkeys((w, v) for w, v, _ in worlds):
        shown = (world or "env") + ("" if variant is None else f":{variant}")
        built("worlds", shown, world=world, world_variant=variant)


def check_pair_worlds(files: list[tuple[str, str]], worlds: list[tuple[str, int | None, str]],
                      sim: Mapping[str, Any], where: str) -> None:
    """A pairs file (``files``: (label, file)) that records its world runs only there:
    ``ConfigError`` naming the file, its world and the task's other one."""
    from pic4rl_bridge.episodes import load_goals_and_poses
    from pic4rl_sim.config import SimParams

    for label, file in files:
        try:
            drawn = load_goals_and_poses(file).world
        except ConfigError as err:
            raise ConfigError(f"{where}: {label}: {err}") from err
        for world, variant, _label in worlds:
            if variant is None:
                variant = sim.get("world_variant", SimParams.world_variant)
            shown = f"{world or sim.get('world', SimParams.world)}:{variant}"
            require(not drawn or drawn == shown, where, label,
                    f"pairs of the task's world {shown}: {file} was drawn in {drawn}")
