"""A benchmark suite file (``pic4rl-bench SUITE.yaml``) and the cells it expands to.

    suite: table1                # bags under <bags>/<suite>/<cell>/
    bags: bags                   # relative to the suite file; default ./bags
    transport: inprocess         # inprocess | ros (a sim node per cell, its own ROS domain)
    retries: 2                   # a failing cell is tried 1 + retries times
    tasks:                       # one cross product each; a case study is one more entry
      - name: goto_lidar         # the leaderboard's task
        env: config/env_goto_lidar.yaml  # the test env (applied over each agent's config)
        agents: {td3_lidar: checkpoints/td3_lidar, gaps: examples/gap_follower.py:GapFollower,
                 gap_node: {stack: {command: "python examples/ros_gap_follower_node.py"}}}
        baselines: [dwa, proportional]
        worlds: ["indoor:0", {world: barn, variants: [0, 6], label: barn_test}]  # default: the env's
        robots: [jackal]         # default: the env's
        pairs: [paper, {random: 100, kind: paper, seed: 0}, {file: g.json}, {episodes: 10}]
        repetitions: 1           # cells per combination, seeds seed, seed+1, ...
        seed: 0

A cell is one agent or baseline × world × robot × pair set × repetition: one ``pic4rl-test``
run; a stack's (``{stack: ...}``, ``pic4rl_agents.stack.spec``, named by its key, its command
run from the suite file's folder) is one ``pic4rl-run stack`` run in a ROS domain of its own,
whatever the suite's ``transport``. The keys are checked by ``checks``. Pair sets:
``paper`` (the paper's 5 indoor pairs), ``{random: N, kind, seed}`` (N pairs drawn once from
the seed, the same on every machine), ``{file: PATH}`` (a goals_and_poses file),
``{episodes: N}`` (N episodes as the env draws them, for tasks without goal pairs).
A world group (``{world, variants, label}``) is a cell per variant and one table row,
``WORLD:LABEL``, for all of them (a benchmark's test worlds). ``table: barn`` gives the table
BARN's columns (``pic4rl_metrics.tables.protocol.LAYOUTS``).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from pic4rl_agents.runs.config import SIM_NODE
from pic4rl_agents.stack.spec import StackSpec
from pic4rl_agents.testing.plan import DEFAULT_PAIRS
from pic4rl_base import params_file
from pic4rl_base.schema import read_yaml
from pic4rl_bridge.config import TransportName
from pic4rl_bridge.errors import ConfigError, require
from pic4rl_metrics.tables.protocol import LAYOUTS
from pic4rl_sim.engine.sampling import PAIR_KINDS

from . import checks

SUITE_KEYS = ("suite", "bags", "transport", "retries", "table", "tasks")
#: The results table's layouts (``pic4rl_metrics.tables.protocol.LAYOUTS``, which
#: ``pic4rl-metrics compare --table`` names too): the paper's columns, BARN's, the explore
#: task's or the crowd's (social columns).
TABLES = tuple(LAYOUTS)
WORLD_GROUP_KEYS = ("world", "variants", "label")
TASK_KEYS = ("name", "env", "agents", "baselines", "worlds", "robots", "pairs", "repetitions",
             "seed")
PAIR_KEYS = {"random": ("random", "kind", "seed"), "file": ("file", "episodes"),
             "episodes": ("episodes",)}


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
    agent: str  # the row's name: the agent's (or stack's) key or the baseline
    env: str  # the task's env params file
    agent_path: str = ""  # a checkpoint or plugin reference; empty for a baseline, stack
    world: str = ""  # empty: the env's
    variant: int | None = None
    world_label: str = ""  # a world group's row label: its variants share one row
    robot: str = ""
    pairs: PairSet = PairSet("paper")
    repetition: int = 0
    seed: int = 0
    transport: str = TransportName.INPROCESS.value
    stack: StackSpec | None = None  # a ROS 2 stack as the agent (always transport ros)
    stack_cwd: str = ""  # the folder its command runs from: the suite file's

    @property
    def baseline(self) -> str:
        return "" if self.agent_path or self.stack else self.agent

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
    checks.keys(item, PAIR_KEYS[first], where)
    if first == "random":
        n = checks.count(item["random"], f"{where}.random")
        kind = item.get("kind", "paper")
        require(kind in PAIR_KINDS, f"{where}.kind", kind, " or ".join(PAIR_KINDS))
        seed = checks.count(item.get("seed", 0), f"{where}.seed", 0)
        return PairSet(f"random{n}_{kind}_s{seed}", random=n, kind=kind, seed=seed)
    episodes = (checks.count(item.get("episodes", 1), f"{where}.episodes") if "episodes" in item
                else 0)
    if first == "file":
        file = checks.path(item["file"], f"{where}.file", base)
        return PairSet(f"file_{Path(file).stem}", file=file, episodes=episodes)
    return PairSet(f"episodes{episodes}_s{seed}", episodes=episodes)


def _worlds(item: Any, where: str) -> list[tuple[str, int | None, str]]:
    """(world, variant, row label) of a ``WORLD[:VARIANT]`` item or a world group."""
    if isinstance(item, Mapping):
        checks.keys(item, WORLD_GROUP_KEYS, where)
        variants = item.get("variants")
        require(isinstance(variants, list) and bool(variants) and all(
            isinstance(v, int) and not isinstance(v, bool) and v >= 0 for v in variants),
            f"{where}.variants", variants, "a non-empty list of integers >= 0")
        world = checks.name(item.get("world"), f"{where}.world")
        label = checks.name(item.get("label"), f"{where}.label")
        return [(world, v, label) for v in variants]
    require(isinstance(item, str) and bool(item), where, item,
            "WORLD, WORLD:VARIANT or {world, variants, label}")
    world, _, variant = item.partition(":")
    require(variant == "" or variant.isdigit(), where, item, "WORLD:VARIANT, VARIANT >= 0")
    return [(checks.name(world, where), int(variant) if variant else None, "")]


def _task_cells(data: Any, where: str, base: Path, transport: str) -> list[Cell]:
    data = checks.keys(data, TASK_KEYS, where)
    for key in ("name", "env"):
        if key not in data:
            raise ConfigError(f"{where}: missing key {key!r}")
    task = checks.name(data["name"], f"{where}.name")
    env = checks.path(data["env"], f"{where}.env", base)
    sim = params_file.node_section(params_file.read(env), SIM_NODE, source=env) or {}
    worlds = [w for item in checks.items(data, "worlds", where, [])
              for w in _worlds(item, f"{where}.worlds")] or [
        (str(sim.get("world", "")), sim.get("world_variant"), "")]
    robots = [checks.name(r, f"{where}.robots")
              for r in checks.items(data, "robots", where, [])] or [str(sim.get("robot", ""))]
    reps = checks.count(data.get("repetitions", 1), f"{where}.repetitions")
    seed = checks.count(data.get("seed", 0), f"{where}.seed", 0)
    pairs = [_pair_set(p, f"{where}.pairs", base, seed)
             for p in checks.items(data, "pairs", where, ["paper"])]
    checks.check_pair_worlds([(p.label, p.file) for p in pairs if p.file], worlds, sim,
                             f"{where}.pairs")
    checks.check_worlds(env, worlds, robots, where)
    cells = []
    for agent, at, stack in checks.agent_rows(data, where, base, env, robots):
        for world, variant, label in worlds:
            for robot in robots:
                for pair_set in pairs:
                    for rep in range(reps):
                        parts = [task, agent, world + ("" if variant is None else str(variant)),
                                 robot, pair_set.label, f"r{rep}"]
                        cells.append(Cell(
                            "-".join(p for p in parts if p), task, agent, env, at, world,
                            variant, label, robot, pair_set, rep, seed + rep,
                            "ros" if stack else transport, stack,
                            str(base.absolute()) if stack else ""))
    return cells


def load_suite(path: str | Path, *, bags_dir: str | Path | None = None) -> Suite:
    """The suite of ``path``, checked whole before any cell runs; ``ConfigError`` naming the
    file and the key otherwise."""
    path = Path(path)
    data = read_yaml(path, "suite file")
    data = checks.keys(data, SUITE_KEYS, str(path))
    for key in ("suite", "tasks"):
        if key not in data:
            raise ConfigError(f"{path}: missing key {key!r}")
    suite = checks.name(data["suite"], f"{path}: suite")
    transport = data.get("transport", TransportName.INPROCESS.value)
    names = [t.value for t in TransportName]
    require(transport in names, f"{path}: transport", transport, " or ".join(names))
    retries = checks.count(data.get("retries", 2), f"{path}: retries", 0)
    table = data.get("table", TABLES[0])
    require(table in TABLES, f"{path}: table", table, " or ".join(TABLES))
    tasks = checks.items(data, "tasks", str(path), [])
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
    return Suite(suite, path, bags, retries, tuple(cells), table)
