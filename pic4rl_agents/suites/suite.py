"""A benchmark suite file (``pic4rl-bench SUITE.yaml``) and the cells it expands to.

    suite: table1                # bags under <bags>/<suite>/<cell>/
    bags: bags                   # relative to the suite file; default ./bags
    transport: inprocess         # inprocess | ros (a sim node per cell, its own ROS domain)
    retries: 2                   # a failing cell is tried 1 + retries times
    tasks:                       # one cross product each; a case study is one more entry
      - name: goto_lidar         # the leaderboard's task
        env: config/env_goto_lidar.yaml  # the test env (applied over each agent's config)
        agents: {td3_lidar: checkpoints/td3_lidar, gaps: examples/gap_follower.py:GapFollower}
        baselines: [dwa, proportional]
        worlds: ["indoor:0", {world: barn, variants: [0, 6], label: barn_test}]  # default: the env's
        robots: [jackal]         # default: the env's
        pairs: [paper, {random: 100, kind: paper, seed: 0}, {file: g.json}, {episodes: 10}]
        repetitions: 1           # cells per combination, seeds seed, seed+1, ...
        seed: 0

A cell is one agent or baseline × world × robot × pair set × repetition: one ``pic4rl-test``
run. Pair sets: ``paper`` (the paper's 5 indoor pairs), ``{random: N, kind, seed}`` (N pairs
drawn once from the seed, the same on every machine), ``{file: PATH}`` (a goals_and_poses
file), ``{episodes: N}`` (N episodes as the env draws them, for tasks without goal pairs).
A world group (``{world, variants, label}``) is a cell per variant and one table row,
``WORLD:LABEL``, for all of them (a benchmark's test worlds). ``table: barn`` gives the table
BARN's columns (``pic4rl_metrics.tables.protocol.LAYOUTS``).
"""

from __future__ import annotations

import dataclasses
import re
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any


from pic4rl_bridge.baselines import BASELINES
from pic4rl_bridge.config import TransportName
from pic4rl_bridge.errors import ConfigError, require, unknown_key
from pic4rl_sim import params_file
from pic4rl_sim.engine.sampling import PAIR_KINDS
from pic4rl_sim.schema import read_yaml
from pic4rl_metrics.tables.protocol import LAYOUTS

from pic4rl_agents.config import SIM_NODE
from pic4rl_agents.testing.plan import DEFAULT_PAIRS, TestPlan, resolve_agents

SUITE_KEYS = ("suite", "bags", "transport", "retries", "table", "tasks")
#: The results table's layouts (``pic4rl_metrics.tables.protocol.LAYOUTS``, which
#: ``pic4rl-metrics compare --table`` names too): the paper's columns, or BARN's.
TABLES = tuple(LAYOUTS)
WORLD_GROUP_KEYS = ("world", "variants", "label")
TASK_KEYS = ("name", "env", "agents", "baselines", "worlds", "robots", "pairs", "repetitions",
             "seed")
PAIR_KEYS = {"random": ("random", "kind", "seed"), "file": ("file", "episodes"),
             "episodes": ("episodes",)}
_NAME = re.compile(r"[A-Za-z0-9_.]+")


@dataclass(frozen=True)
class PairSet:
    """The episodes of a cell: a pairs file, N pairs drawn from a seed, or the env's own."""

    label: str  # in cell names and the table
    file: str = ""  # a goals_and_poses file (paper, file)
    random: int = 0  # pairs to draw (random)
    kind: str = "paper"
    seed: int = 0
    episodes: int = 0  # the env's own episodes, or a file's pairs to drive (0: each once)


@dataclass(frozen=True)
class Cell:
    """One ``pic4rl-test`` run of the suite; its bags go to ``<bags>/<suite>/<name>/``."""

    name: str
    task: str
    agent: str  # the row's name: the agent's key or the baseline
    env: str  # the task's env params file
    agent_path: str = ""  # a checkpoint or plugin reference; empty for a baseline
    world: str = ""  # empty: the env's
    variant: int | None = None
    world_label: str = ""  # a world group's row label: its variants share one row
    robot: str = ""
    pairs: PairSet = PairSet("paper")
    repetition: int = 0
    seed: int = 0
    transport: str = TransportName.INPROCESS.value

    @property
    def baseline(self) -> str:
        return "" if self.agent_path else self.agent

    @property
    def row(self) -> dict[str, str]:
        """The table row this cell adds episodes to (every repetition shares it)."""
        label = self.world_label or ("" if self.variant is None else str(self.variant))
        world = (self.world or "env") + (f":{label}" if label else "")
        return {"task": self.task, "agent": self.agent, "world": world,
                "robot": self.robot or "env", "pairs": self.pairs.label}


@dataclass(frozen=True)
class Suite:
    name: str
    path: Path
    bags_dir: Path
    retries: int
    cells: tuple[Cell, ...]
    table: str = TABLES[0]

    @property
    def root(self) -> Path:
        return self.bags_dir / self.name


def _keys(data: Any, known: tuple[str, ...], where: str) -> Mapping[str, Any]:
    if not isinstance(data, Mapping):
        raise ConfigError(f"{where}: {data!r} is invalid; expected a mapping of "
                          f"{', '.join(known)}")
    for key in data:
        if key not in known:
            raise unknown_key(str(key), known, where=where)
    return data


def _name(value: Any, where: str) -> str:
    require(isinstance(value, str) and bool(_NAME.fullmatch(value)), where, value,
            "a name of letters, digits, '_' and '.'")
    return value


def _count(value: Any, where: str, low: int = 1) -> int:
    require(isinstance(value, int) and not isinstance(value, bool) and value >= low, where,
            value, f"an integer >= {low}")
    return value


def _path(value: Any, where: str, base: Path) -> str:
    require(isinstance(value, str) and bool(value), where, value, "a file path")
    path = Path(value) if Path(value).exists() or Path(value).is_absolute() else base / value
    require(path.exists(), where, value, "an existing file or directory")
    return str(path.absolute())


def _agent(value: Any, where: str, base: Path) -> str:
    """An agent's location: a checkpoint (``_path``), a plugin ``FILE.py:NAME`` (its file
    relative to the suite file, made absolute: a worker imports it by the same reference), or
    ``package.module:NAME`` and an entry point as given (``pic4rl_agents.testing.policies``)."""
    from pic4rl_agents.testing.policies import is_plugin

    if not (isinstance(value, str) and is_plugin(value)):
        return _path(value, where, base)
    target, sep, attr = value.rpartition(":")
    return f"{_path(target, where, base)}:{attr}" if target.endswith(".py") else value


def _pair_set(item: Any, where: str, base: Path, seed: int) -> PairSet:
    """A ``pairs`` item, named after what sets its episodes: ``paper``, its file
    (``file_<stem>``), its draw (``random<N>_<kind>_s<seed>``) or, for the env's own
    episodes, their count and the task's ``seed`` (``episodes<N>_s<seed>``)."""
    if item == "paper":
        return PairSet("paper", file=str(DEFAULT_PAIRS))
    if not isinstance(item, Mapping) or not any(k in item for k in PAIR_KEYS):
        raise ConfigError(f"{where}: {item!r} is invalid; expected paper, {{random: N, kind, "
                          "seed}, {file: PATH} or {episodes: N}")
    first = next(k for k in PAIR_KEYS if k in item)
    _keys(item, PAIR_KEYS[first], where)
    if first == "random":
        n = _count(item["random"], f"{where}.random")
        kind = item.get("kind", "paper")
        require(kind in PAIR_KINDS, f"{where}.kind", kind, " or ".join(PAIR_KINDS))
        seed = _count(item.get("seed", 0), f"{where}.seed", 0)
        return PairSet(f"random{n}_{kind}_s{seed}", random=n, kind=kind, seed=seed)
    episodes = _count(item.get("episodes", 1), f"{where}.episodes") if "episodes" in item else 0
    if first == "file":
        file = _path(item["file"], f"{where}.file", base)
        return PairSet(f"file_{Path(file).stem}", file=file, episodes=episodes)
    return PairSet(f"episodes{episodes}_s{seed}", episodes=episodes)


def _worlds(item: Any, where: str) -> list[tuple[str, int | None, str]]:
    """(world, variant, row label) of a ``WORLD[:VARIANT]`` item or a world group."""
    if isinstance(item, Mapping):
        _keys(item, WORLD_GROUP_KEYS, where)
        variants = item.get("variants")
        require(isinstance(variants, list) and bool(variants) and all(
            isinstance(v, int) and not isinstance(v, bool) and v >= 0 for v in variants),
            f"{where}.variants", variants, "a non-empty list of integers >= 0")
        world = _name(item.get("world"), f"{where}.world")
        label = _name(item.get("label"), f"{where}.label")
        return [(world, v, label) for v in variants]
    require(isinstance(item, str) and bool(item), where, item,
            "WORLD, WORLD:VARIANT or {world, variants, label}")
    world, _, variant = item.partition(":")
    require(variant == "" or variant.isdigit(), where, item, "WORLD:VARIANT, VARIANT >= 0")
    return [(_name(world, where), int(variant) if variant else None, "")]


def _list(data: Mapping[str, Any], key: str, where: str, default: list[Any]) -> list[Any]:
    value = data.get(key, default)
    require(isinstance(value, list), f"{where}.{key}", value, "a list")
    return value


def _agents(data: Mapping[str, Any], where: str, base: Path, env: str,
            robots: list[str]) -> list[tuple[str, str]]:
    """(row name, agent path; empty for a baseline) of the task, each agent and baseline
    resolved on each of the task's ``robots`` as its cells will run it, before any runs."""
    agents = data.get("agents", {})
    require(isinstance(agents, Mapping), f"{where}.agents", agents, "a mapping NAME: PATH")
    rows = [(_name(n, f"{where}.agents"), _agent(p, f"{where}.agents.{n}", base))
            for n, p in agents.items()]
    for b in _list(data, "baselines", where, []):
        require(b in BASELINES, f"{where}.baselines", b, f"one of {', '.join(BASELINES)}")
        rows.append((b, ""))
    require(bool(rows), where, dict(data), "at least one of agents, baselines")
    for name, path in rows:
        for robot in robots:
            plan = TestPlan(agents=(f"{name}={path}",) if path else (),
                            baselines=() if path else (name,), params_files=(env,),
                            sim_overrides={"robot": robot} if robot else {})
            try:
                resolve_agents(plan)
            except ConfigError as err:
                key = f"agents.{name}" if path else "baselines"
                raise ConfigError(f"{where}.{key}: {err}") from err
    return rows


def _check_worlds(env: str, worlds: list[tuple[str, int | None, str]], robots: list[str],
                  where: str) -> None:
    """Every robot, world and variant of the task built as its cells will build them (the
    env file's sim section with the cell's world, variant and robot), before any cell runs:
    ``ConfigError`` naming the robot or the world (``WORLD:VARIANT``) otherwise."""
    from pic4rl_bridge.scenario import Scenario

    from pic4rl_agents.config import NODES, run_config

    test = run_config(params_file.load([env], NODES), [env]).env.replace(**{
        "transport": TransportName.INPROCESS.value, "robot": "", "episodes.file": "",
        "episodes.world_variants": ""})

    def built(key: str, name: str, **sim: Any) -> None:
        params = {**test.sim_params, **{k: v for k, v in sim.items() if v not in ("", None)}}
        try:
            Scenario(dataclasses.replace(test, sim_params=params)).world_at(None)
        except ConfigError as err:
            raise ConfigError(f"{where}.{key}: {name}: {err}") from err

    for robot in robots:
        built("robots", robot, robot=robot)
    for world, variant in dict.fromkeys((w, v) for w, v, _ in worlds):
        shown = (world or "env") + ("" if variant is None else f":{variant}")
        built("worlds", shown, world=world, world_variant=variant)


def _task_cells(data: Any, where: str, base: Path, transport: str) -> list[Cell]:
    data = _keys(data, TASK_KEYS, where)
    for key in ("name", "env"):
        if key not in data:
            raise ConfigError(f"{where}: missing key {key!r}")
    task, env = _name(data["name"], f"{where}.name"), _path(data["env"], f"{where}.env", base)
    sim = params_file.node_section(params_file.read(env), SIM_NODE, source=env) or {}
    worlds = [w for item in _list(data, "worlds", where, [])
              for w in _worlds(item, f"{where}.worlds")] or [
        (str(sim.get("world", "")), sim.get("world_variant"), "")]
    robots = [_name(r, f"{where}.robots") for r in _list(data, "robots", where, [])] or [
        str(sim.get("robot", ""))]
    reps = _count(data.get("repetitions", 1), f"{where}.repetitions")
    seed = _count(data.get("seed", 0), f"{where}.seed", 0)
    pairs = [_pair_set(p, f"{where}.pairs", base, seed)
             for p in _list(data, "pairs", where, ["paper"])]
    _check_pair_worlds(pairs, worlds, sim, f"{where}.pairs")
    _check_worlds(env, worlds, robots, where)
    cells = []
    for agent, path in _agents(data, where, base, env, robots):
        for world, variant, label in worlds:
            for robot in robots:
                for pair_set in pairs:
                    for rep in range(reps):
                        parts = [task, agent, world + ("" if variant is None else str(variant)),
                                 robot, pair_set.label, f"r{rep}"]
                        cells.append(Cell("-".join(p for p in parts if p), task, agent, env,
                                          path, world, variant, label, robot, pair_set, rep,
                                          seed + rep, transport))
    return cells


def _check_pair_worlds(pairs: list[PairSet], worlds: list[tuple[str, int | None, str]],
                       sim: Mapping[str, Any], where: str) -> None:
    """A pairs file that records its world runs only there: ``ConfigError`` naming the file,
    its world and the task's other one."""
    from pic4rl_bridge.episodes import load_goals_and_poses
    from pic4rl_sim.config import SimParams

    for pair_set in (p for p in pairs if p.file):
        try:
            drawn = load_goals_and_poses(pair_set.file).world
        except ConfigError as err:
            raise ConfigError(f"{where}: {pair_set.label}: {err}") from err
        for world, variant, _label in worlds:
            if variant is None:
                variant = sim.get("world_variant", SimParams.world_variant)
            name = f"{world or sim.get('world', SimParams.world)}:{variant}"
            require(not drawn or drawn == name, where, pair_set.label,
                    f"pairs of the task's world {name}: {pair_set.file} was drawn in {drawn}")


def load_suite(path: str | Path, *, bags_dir: str | Path | None = None) -> Suite:
    """The suite of ``path``, checked whole before any cell runs; ``ConfigError`` naming the
    file and the key otherwise."""
    path = Path(path)
    data = read_yaml(path, "suite file")
    data = _keys(data, SUITE_KEYS, str(path))
    for key in ("suite", "tasks"):
        if key not in data:
            raise ConfigError(f"{path}: missing key {key!r}")
    name = _name(data["suite"], f"{path}: suite")
    transport = data.get("transport", TransportName.INPROCESS.value)
    names = [t.value for t in TransportName]
    require(transport in names, f"{path}: transport", transport, " or ".join(names))
    retries = _count(data.get("retries", 2), f"{path}: retries", 0)
    table = data.get("table", TABLES[0])
    require(table in TABLES, f"{path}: table", table, " or ".join(TABLES))
    tasks = _list(data, "tasks", str(path), [])
    cells = [c for i, t in enumerate(tasks)
             for c in _task_cells(t, f"{path}: tasks[{i}]", path.parent, transport)]
    require(bool(cells), f"{path}: tasks", tasks, "at least one task")
    seen: dict[str, int] = {}
    for cell in cells:
        seen[cell.name] = seen.get(cell.name, 0) + 1
    twice = [n for n, k in seen.items() if k > 1]
    require(not twice, f"{path}: tasks", twice, "distinct cells (a task name or agent twice?)")
    if bags_dir is None and "bags" in data:  # the file's, like its other paths: from it
        require(isinstance(data["bags"], str) and bool(data["bags"]), f"{path}: bags",
                data["bags"], "a directory path")
        bags_dir = path.parent / data["bags"]
    bags = Path("bags" if bags_dir is None else bags_dir).absolute()
    return Suite(name, path, bags, retries, tuple(cells), table)
