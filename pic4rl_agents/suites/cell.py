"""One cell of a benchmark suite, resumable: ``drive_cell`` drives only the episodes whose bags
are not finished yet, through the tester (``resolve_agents``, ``drive_agent``).

A cell's bags are ``<suite root>/<cell>/<agent>/episode_NNNN/``. A bag is finished when its
``metadata.yaml`` is there (the recorder writes it on close). A worker killed mid-episode
leaves one unfinished bag; the retry moves it, kept, to ``<suite root>/_unfinished/`` and
drives the cell's episodes from that index on: the same pairs in the same order (episode k
drives pair k of the cell's pairs file), so no bag is duplicated or lost. A finished cell gets
``cell.json`` (written atomically); a rerun skips it. A ``transport: ros`` cell holds a ROS
domain of its own for its life (``simproc.domain_lease``) and starts its sim with the sim's
params file ``<cell>/sim.yaml``. A stack's cell is such a cell, driven by ``pic4rl-run
stack``'s driver (``pic4rl_agents.stack.driver.drive_stack``) in the env a plugin gets.
"""

from __future__ import annotations

import contextlib
import dataclasses
import json
import os
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from pic4rl_agents.testing.plan import (AgentSpec, TestPlan, free_env, recorded,
                                        resolve_agents, scenario_of, test_env)
from pic4rl_agents.testing.policies import is_plugin
from pic4rl_base import atomic, params_file
from pic4rl_bridge.episodes import GoalsAndPoses, load_goals_and_poses, save_goals_and_poses
from pic4rl_bridge.errors import ConfigError
from pic4rl_bridge.scenario import Scenario
from pic4rl_metrics.bags.inputs import METADATA

from .suite import Cell

DONE = "cell.json"  # a finished cell's marker
ERROR = "cell.error"  # the last attempt's error, in one line
PAIRS = "pairs.json"  # a random pair set, drawn once per cell
UNFINISHED = "_unfinished"  # beside the cells: killed episodes' bags, kept out of the table
SIM_PARAMS = "sim.yaml"  # a ros cell's sim node's params file


@dataclass(frozen=True)
class CellState:
    """What is on disk of a cell: its finished episodes' bags, and whether it is done."""

    finished: tuple[Path, ...]
    unfinished: tuple[Path, ...]
    done: bool


def cell_dir(root: Path, cell: Cell) -> Path:
    return root / cell.name


def state(root: Path, cell: Cell) -> CellState:
    agent_dir = cell_dir(root, cell) / cell.agent
    bags = sorted(agent_dir.glob("episode_*")) if agent_dir.is_dir() else []
    finished = tuple(b for b in bags if (b / METADATA).is_file())
    unfinished = tuple(b for b in bags if not (b / METADATA).is_file())
    return CellState(finished, unfinished, (cell_dir(root, cell) / DONE).is_file())


def _plan(cell: Cell, root: Path, *, episodes: int, pairs: str, domain: int) -> TestPlan:
    env: dict[str, Any] = {"episodes.file": pairs} if pairs else {}
    if cell.transport == "ros":
        env.update({"transport": "ros", "ros.domain_id": domain})
    sim = {k: v for k, v in (("world", cell.world), ("world_variant", cell.variant),
                             ("robot", cell.robot)) if v not in ("", None)}
    return TestPlan(agents=(f"{cell.agent}={cell.agent_path}",) if cell.agent_path else (),
                    baselines=(cell.baseline,) if cell.baseline else (), episodes=episodes,
                    seed=cell.seed, bags_dir=root, run=cell.name, params_files=(cell.env,),
                    env_overrides=env, sim_overrides=sim, progress=False)


def _cell_pairs(cell: Cell, root: Path, scenario: Scenario) -> GoalsAndPoses | None:
    """The cell's pairs in episode order: its file's, or drawn once from the pair set's seed
    (in ``scenario``'s robot and world) into ``<cell>/pairs.json``; ``None`` for the env's own
    episodes."""
    if cell.pairs.file:
        return load_goals_and_poses(cell.pairs.file)
    if not cell.pairs.random:
        return None
    path = cell_dir(root, cell) / PAIRS
    if not path.is_file():
        from pic4rl_bridge.episodes import PairSampler
        from pic4rl_sim.engine.sampling import PAIR_KINDS

        sampler = PairSampler.for_scenario(scenario)
        if sampler is None:
            raise ConfigError(f"{cell.pairs.label}: drawn pairs need a simulated world")
        drawn = sampler.goals_and_poses(cell.pairs.random, seed=cell.pairs.seed,
                                        kind=PAIR_KINDS[cell.pairs.kind])
        with atomic.replacing(path) as tmp:
            save_goals_and_poses(drawn, tmp, overwrite=True,
                                 comment=f"{cell.pairs.label}: drawn by pic4rl-bench")
    return load_goals_and_poses(path)


def _pairs_file(first: int, folder: Path) -> Path:
    return folder / f"pairs_from_{first:04d}.json"


def _pairs_from(pairs: GoalsAndPoses, first: int, folder: Path) -> None:
    """Write the pairs file whose pair i is the cell's pair ``first + i`` (cycling)."""
    n = len(pairs.goals)
    order = [(first + i) % n for i in range(n)]
    rotated = dataclasses.replace(pairs, goals=tuple(pairs.goals[i] for i in order),
                                  poses=tuple(pairs.poses[i] for i in order))
    with atomic.replacing(_pairs_file(first, folder)) as tmp:
        save_goals_and_poses(rotated, tmp, overwrite=True, exact=True)


def _set_aside(root: Path, cell: Cell, bags: tuple[Path, ...]) -> None:
    """Move unfinished bags out of the cell (kept, never deleted), stamped with the time."""
    for bag in bags:
        target = root / UNFINISHED / cell.name / cell.agent / f"{bag.name}.{time.time_ns()}"
        target.parent.mkdir(parents=True, exist_ok=True)
        os.replace(bag, target)


def _drive(spec: AgentSpec, cell: Cell, folder: Path, *, episodes: int, seed: int,
           domain: int) -> None:
    """Run the episodes, with the cell's own sim node (in its own ROS domain) when the cell
    drives sim nodes."""
    from pic4rl_agents.launch.simproc import start_sim, stop_group
    from pic4rl_agents.testing.tester import drive_agent

    if cell.stack is not None:  # the stack's driver starts the sim and the stack
        from pic4rl_agents.stack.driver import drive_stack

        drive_stack(cell.stack, scenario_of(spec), overrides={}, episodes=episodes, seed=seed,
                    domain=domain, cwd=Path(cell.stack_cwd), sim_file=folder / SIM_PARAMS)
        return
    if cell.transport != "ros":
        drive_agent(spec, episodes=episodes, seed=seed, progress=False)
        return
    env = {**os.environ, "ROS_DOMAIN_ID": str(domain), "ROS_AUTOMATIC_DISCOVERY_RANGE":
           os.environ.get("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")}
    sim_file = atomic.write_text(folder / SIM_PARAMS,
                                 params_file.dump({"/**": scenario_of(spec).node_values}))
    sim = start_sim(["--params-file", str(sim_file)], env)
    try:
        drive_agent(spec, episodes=episodes, seed=seed, progress=False)
    finally:
        stop_group(sim, 10.0)


def preload(cell: Cell) -> None:
    """Import what driving ``cell`` takes (the tester, the env and its transport; a learned
    agent's SB3 and torch, seconds of CPU) in the process that forks the cells' workers, so
    that each forked worker starts with them instead of importing them again."""
    import pic4rl_agents.testing.tester  # noqa: F401
    import pic4rl_bridge.env  # noqa: F401

    if cell.transport != "ros":
        import pic4rl_bridge.transports.inprocess  # noqa: F401
    if cell.agent_path and not is_plugin(cell.agent_path):
        import pic4rl_agents.models.algorithms  # noqa: F401
    if cell.stack is not None:
        import pic4rl_agents.stack.driver  # noqa: F401


def drive_cell(cell: Cell, root: Path) -> str:
    """Drive what is missing of ``cell`` and mark it done; ``"skipped"`` when it was done
    already, else ``"done"``. Errors propagate (the caller retries)."""
    from pic4rl_agents.launch.simproc import domain_lease

    current = state(root, cell)
    if current.done:
        return "skipped"
    folder = cell_dir(root, cell)
    folder.mkdir(parents=True, exist_ok=True)
    _set_aside(root, cell, current.unfinished)
    total, first = expected_episodes(cell), len(current.finished)
    if first < total:
        ros = cell.transport == "ros"
        with domain_lease() if ros else contextlib.nullcontext(-1) as domain:
            _drive_from(cell, root, folder, first=first, total=total, domain=domain)
    (folder / ERROR).unlink(missing_ok=True)
    atomic.write_text(folder / DONE, json.dumps({"cell": cell.name, "episodes": total}) + "\n")
    return "done"


def _drive_from(cell: Cell, root: Path, folder: Path, *, first: int, total: int,
                domain: int) -> None:
    """Drive the cell's episodes ``first`` to ``total - 1``."""
    own_pairs = bool(cell.pairs.file or cell.pairs.random)
    file = str(_pairs_file(first, folder)) if own_pairs else ""
    # A resumed cell's episodes draw their simulator seeds from seed + first.
    plan = _plan(cell, root, episodes=total - first, pairs=file, domain=domain)
    spec = (recorded(_stack_agent(cell, plan), folder) if cell.stack is not None
            else resolve_agents(plan, folder)[0])  # its files, read once
    pairs = _cell_pairs(cell, root, scenario_of(spec))
    if pairs is not None:
        _pairs_from(pairs, first, folder)
    _drive(spec, cell, folder, episodes=total - first, seed=cell.seed + first, domain=domain)


def _stack_agent(cell: Cell, plan: TestPlan) -> AgentSpec:
    """A stack's row in the env a plugin gets (``plan``'s params files alone, the cell's
    world, variant and robot), set up for testing as the tester sets up every agent's."""
    from pic4rl_agents.runs.config import ENV_NODE, NODES

    files = params_file.load(plan.params_files, NODES)
    pairs = plan.env_overrides.get("episodes.file", files[ENV_NODE].get("episodes.file") or None)
    run, _ = free_env(plan, f"stack {cell.agent}", [], files)
    return test_env(AgentSpec(cell.agent, run), plan, pairs)


def expected_episodes(cell: Cell) -> int:
    """How many episodes the cell drives (its pair set's), without drawing anything."""
    if cell.pairs.file:
        return cell.pairs.episodes or len(load_goals_and_poses(cell.pairs.file).goals)
    return cell.pairs.random or cell.pairs.episodes
