"""What ``pic4rl-test`` tests: a ``TestPlan`` (agents, baselines, episodes, where the bags
go), and the agents it names, each with its test env (``resolve_agents``).

An agent's env is its training config, then the plan's params files key by key, then its
overrides; a baseline's is the first agent's at the robot's full speed range, or the params
files alone. All drive the same test episodes (``pic4rl_agents.testing.tester`` says which).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

from pic4rl_agents.runs import rundir
from pic4rl_agents.runs.config import ENV_NODE, NODES, SIM_NODE, RunConfig, run_config
from pic4rl_agents.models.algorithm_table import ALGORITHM_TABLE
from pic4rl_base import params_file
from pic4rl_bridge.baselines import BASELINES, check_fits
from pic4rl_bridge.config import EnvConfig, agent_conflicts
from pic4rl_bridge.errors import ConfigError
from pic4rl_bridge.robot_info import RobotInfo
from pic4rl_bridge.scenario import Scenario
from pic4rl_bridge.settings.baselines import BASELINES_NODE, BaselinesConfig, baselines_config

from .policies import is_plugin, load_plugin, torchscript_env

Sections = dict[str, dict[str, Any]]

#: The paper's testing set for the indoor world: 5 start–goal pairs, walked in order.
DEFAULT_PAIRS = Path(__file__).resolve().parents[1] / "data" / "goals_indoor_test.json"
DEFAULT_PAIRS_WORLD = ("indoor", 0)  # the world and variant those pairs are in


@dataclass(frozen=True)
class TestPlan:
    """What to test and how: the agents and baselines, the episodes, where the bags go."""

    agents: tuple[str, ...] = ()  # [NAME=]PATH: a run dir, model zip/.pt or plugin reference
    baselines: tuple[str, ...] = ()
    algorithm: str = ""  # of a bare model zip (its run's config names it otherwise)
    episodes: int = 5
    random: int | None = None  # draw this many pairs instead of a pairs file
    pairs: str | None = None  # the kind of the drawn pairs (PAIR_KINDS)
    seed: int = 0
    bags_dir: Path = Path("bags")
    run: str = ""  # the bags' run name; empty: test_<date>-<time>
    params_files: tuple[str, ...] = ()  # applied over each agent's config
    env_overrides: Mapping[str, Any] = field(default_factory=dict)
    sim_overrides: Mapping[str, Any] = field(default_factory=dict)
    baseline_overrides: Mapping[str, Any] = field(default_factory=dict)  # dwa.horizon_s, ...
    with_std: bool = False  # mean ± std cells in table.md
    video: bool = False  # an MP4 per episode beside its bag (episode_NNNN.mp4)
    progress: bool = True

    def __post_init__(self) -> None:
        for flag, value in (("--episodes", self.episodes), ("--random", self.random)):
            if value is not None and value < 1:
                raise ConfigError(f"{flag} {value}: expected a positive number of episodes")

    @property
    def n_episodes(self) -> int:
        return self.random or self.episodes


@dataclass(frozen=True)
class AgentSpec:
    """One row of the table: a trained model (``model``: an SB3 zip or TorchScript ``.pt``), a
    policy plugin (``plugin``: its reference) or a baseline (``baseline``)."""

    name: str
    run: RunConfig
    model: Path | None = None
    baseline: str = ""
    episode_set: str = ""  # its test episodes, in words
    trained: str = ""  # a model's training config, in words (``RunConfig.origin``)
    settings: BaselinesConfig | None = None  # a baseline's: the baselines: section
    env_from: str = ""  # a baseline's or plugin's env, in words
    plugin: str = ""  # FILE.py:NAME, package.module:NAME or an entry point (testing.policies)
    algorithm: str = ""  # an SB3/sb3-contrib class beyond the table's (--algorithm RecurrentPPO)
    #: Its test env resolved (``test_env``), once, for the sim node's file and the env.
    scenario: Scenario | None = field(default=None, compare=False, repr=False)

    @property
    def env_line(self) -> str:
        """A baseline's env and step budget in one line (``pic4rl-test`` prints it)."""
        return (f"{self.name} runs in {self.env_from}: {self.run.env.episode_max_steps} steps "
                "an episode (episode_max_steps)")


def _agent_files(path: Path) -> tuple[Path, Path | None]:
    """The model zip and its run's config, from a directory or a zip (the config is looked
    for beside the zip and up to two folders above: checkpoints/, best/<session>/)."""
    if path.is_dir():
        model = path / rundir.MODEL
        if not model.is_file():
            raise ConfigError(f"--agent {path}: no {rundir.MODEL} in it")
        return model, rundir.run_config_file(path)
    if path.is_file() and path.suffix == ".pt":  # TorchScript: its sidecar names its env
        return path, torchscript_env(path)
    if path.is_file() and path.suffix == ".zip":
        run_dir = rundir.run_of(path)
        return path, rundir.run_config_file(run_dir) if run_dir is not None else None
    raise ConfigError(f"--agent {path}: no such model (expected a run directory with "
                      f"{rundir.MODEL} and {rundir.CONFIG}, a model .zip, a TorchScript .pt "
                      "or a plugin FILE.py:NAME / package.module:NAME)")


def _agents(plan: TestPlan, files: Sections) -> list[AgentSpec]:
    """The trained agents, each with its run's config and the plan's files (``files``, read
    once) and overrides."""
    table = plan.algorithm.lower() in ALGORITHM_TABLE
    train_overrides = {"algorithm": plan.algorithm} if plan.algorithm and table else {}
    specs: list[AgentSpec] = []
    for item in plan.agents:
        name, sep, location = item.partition("=")
        if is_plugin(location if sep else item):
            continue
        path = Path(location if sep else item)
        model, config = _agent_files(path)
        if config is None and not plan.params_files:
            raise ConfigError(f"--agent {path}: no {rundir.CONFIG} beside the model; give the "
                              "env with --ros-args --params-file FILE and --algorithm")
        own = rundir.agent_sections(params_file.load([config], NODES)) if config else {}
        sources = ([str(config)] if config else []) + list(plan.params_files)
        run = run_config(params_file.merge(own, files), sources, train=train_overrides,
                         env=plan.env_overrides, sim=plan.sim_overrides)
        if not sep:
            model_file = path.suffix in (".zip", ".pt")
            name = path.stem if model_file and path.stem != "model" else (
                path.parent.name if model_file else path.name)
        trained = "no config beside it"
        if config:
            own_run = run_config(own, [str(config)])
            check_trained(f"--agent {path}", config, own_run.env, run.env,
                          plan.params_files, plan.env_overrides, plan.sim_overrides)
            trained = own_run.origin
        specs.append(AgentSpec(name, run, model=model, trained=f"trained with {trained}",
                               algorithm="" if table else plan.algorithm))
    return specs


#: The ``sim:`` settings that shape what an agent observes or what its actions do: its robot,
#: the control period, and the fields of its sensors (``lidar.*``, ``depth.*``: the agent's
#: ``sensors``) that set the beams, field of view, ranges and image. A test takes them from the
#: agent's own config, as it takes ``pic4rl_bridge.config.agent_keys`` (``check_trained``);
#: the others (the world, its variant, seeds, sensor noise) are the test's to choose.
AGENT_SIM_KEYS = ("robot", "control_dt_s",
                  "lidar.enabled", "lidar.beams", "lidar.fov_deg", "lidar.range_min_m",
                  "lidar.range_max_m",
                  "depth.enabled", "depth.width", "depth.height", "depth.hfov_deg",
                  "depth.min_depth_m", "depth.max_depth_m")


def sim_conflicts(trained: Scenario, test: Scenario) -> list[tuple[str, Any, Any]]:
    """``(key, trained value, test value)`` of every ``AGENT_SIM_KEYS`` setting of
    ``trained``'s sensors that the simulator of ``test`` changes (both as their ``Scenario``
    resolved them: the sim's defaults for their robot filled in); none when either drives no
    pic4rl simulator."""
    mine, theirs = trained.values, test.values
    if not (mine and theirs):
        return []
    keys = [k for k in AGENT_SIM_KEYS
            if "." not in k or k.split(".")[0] in trained.config.observed]
    return [(k, mine[k], theirs[k]) for k in keys if mine[k] != theirs[k]]


def _resolved(env: EnvConfig) -> tuple[Scenario, Scenario]:
    """``env`` resolved for ``check_trained``, without its training worlds (hundreds): its sim
    section as written (its own robot's defaults; an env ``robot`` is a robot check's), and
    the robot it drives: one ``Scenario`` for both unless an env ``robot`` overrides the sim's."""
    env = env.replace(**{"episodes.world_variants": ""})
    if not (env.robot and env.simulated):
        return (scenario := Scenario(env)), scenario
    return Scenario(env.replace(robot="")), Scenario(env)


def check_trained(agent: str, config: Path, trained: EnvConfig, test: EnvConfig,
                  params_files: Sequence[str], overrides: Mapping[str, Any],
                  sim_overrides: Mapping[str, Any]) -> None:
    """``ConfigError`` in one line when ``test`` changes a setting that shapes what the agent
    observes or what its actions do (``pic4rl_bridge.config.agent_keys``, the sim's
    ``AGENT_SIM_KEYS``): it names the key, the value the params file or override gives, and
    the agent's own (from ``config``)."""
    conflicts = [(ENV_NODE, *c) for c in agent_conflicts(trained, test)]
    if not conflicts:
        (mine_sim, mine_robot), (theirs_sim, theirs_robot) = _resolved(trained), _resolved(test)
        conflicts = [(SIM_NODE, *c) for c in sim_conflicts(mine_sim, theirs_sim)]
    if not conflicts:
        mine, theirs = _drive(mine_robot.robot), _drive(theirs_robot.robot)
        if mine != theirs:  # the same keys, another robot or control period under them
            raise ConfigError(f"{agent}: its test robot drives {theirs} but the agent was "
                              f"trained on {mine} ({config}); an action must mean what it "
                              "meant in training: test it on a robot as fast, at its period")
        return
    node, key, mine, theirs = conflicts[0]
    flag, section = (("-p/--env-kwargs", "") if node == ENV_NODE else
                     ("--sim-kwargs", " (sim section)"))
    given = overrides if node == ENV_NODE else sim_overrides
    source = flag if key in given else next(
        (f"{f}{section}" for f in reversed(params_files)
         if key in params_file.read_sections(f, (ENV_NODE, SIM_NODE))[node]),
        "the test env")
    more = f" (also {', '.join(c[1] for c in conflicts[1:])})" if conflicts[1:] else ""
    raise ConfigError(f"{agent}: {key}: {source} gives {theirs!r} but the agent was trained "
                      f"with {mine!r} ({config}){more}; a test env must not change what an "
                      f"agent observes or how it acts: remove {key} there or set it to "
                      f"{mine!r}")


def _drive(robot: RobotInfo) -> str:
    """What an action means on ``robot``: its speed ranges and control period, in words."""
    lateral = f", vy ≤ {robot.max_lateral_m_s:g} m/s" if robot.omni else ""
    return (f"v in [{robot.min_linear_m_s:g}, {robot.max_linear_m_s:g}] m/s, "
            f"|ω| ≤ {robot.max_angular_rad_s:g} rad/s{lateral} every {robot.control_dt_s:g} s")


def _plugins(plan: TestPlan, agents: list[AgentSpec], files: Sections) -> list[AgentSpec]:
    """The plan's policy plugins, each loaded once (to check it and take its name) and run
    in the env a baseline would run in."""
    specs = []
    for item in plan.agents:
        name, sep, location = item.partition("=")
        if is_plugin(location if sep else item):
            ref = location if sep else item
            own = load_plugin(ref)[1]
            run, env_from = free_env(plan, f"--agent {ref}", agents, files)
            specs.append(AgentSpec(name if sep else own, run, plugin=ref, env_from=env_from))
    return specs


def _baseline(plan: TestPlan, baseline: str, agents: list[AgentSpec],
              files: Sections) -> AgentSpec:
    """A baseline in the first agent's env (at the robot's full speed range), or in the
    plan's params files (``files``, read once)."""
    if baseline not in BASELINES:
        raise ConfigError(f"--baseline {baseline!r}: expected one of {', '.join(BASELINES)}")
    run, env_from = free_env(plan, f"--baseline {baseline}", agents, files)
    check_fits(baseline, run.env)  # before any run directory or bag exists
    settings = baselines_config(files[BASELINES_NODE], plan.baseline_overrides,
                                where=" + ".join(plan.params_files))
    return AgentSpec(baseline, run, baseline=baseline, settings=settings, env_from=env_from)


def free_env(plan: TestPlan, flag: str, agents: list[AgentSpec],
              files: Sections) -> tuple[RunConfig, str]:
    """The env of an agent not trained here (a baseline, a plugin: ``flag``) and where it came
    from, in words: the first trained agent's (at the robot's full speed range), or the
    plan's params files (``files``, read once)."""
    # The test env's one world, as the agents' (``test_env``): never a world per episode.
    unset = {"episodes.world_variants": ""}
    if agents:
        run = agents[0].run
        env_from = f"the env of agent {agents[0].name} ({run.origin})"
        if "min_linear_m_s" not in plan.env_overrides:
            # An agent's speed floor is its own training choice; a baseline drives the
            # robot's full range unless the user says otherwise.
            unset["min_linear_m_s"] = 0.0
            env_from += " at the robot's full speed range"
        run = run.replace(env=unset)
    elif plan.params_files:
        run = run_config(files, plan.params_files, env=plan.env_overrides,
                         sim=plan.sim_overrides)
        env_from = f"the params files' env ({run.origin})"
        run = run.replace(env=unset)
    else:
        raise ConfigError(f"{flag}: no env to run it in; give a trained --agent or "
                          "--ros-args --params-file FILE")
    return run, env_from


def resolve_agents(plan: TestPlan, run_dir: Path | None = None) -> list[AgentSpec]:
    """The agents and baselines to test, each in its test env (the test episodes, no
    curriculum), recorded under ``run_dir`` when one is given. Every params file is read
    once, here; what follows works on the typed configs."""
    files = params_file.load(plan.params_files, (*NODES, BASELINES_NODE))
    # The pairs named at test time: the params files' (later files win), then the overrides.
    pairs = plan.env_overrides.get("episodes.file", files[ENV_NODE].get("episodes.file") or None)
    agents = _agents(plan, files)
    specs = agents + _plugins(plan, agents, files) + [
        _baseline(plan, b, agents, files) for b in plan.baselines]
    if not specs:
        raise ConfigError("nothing to test: give --agent PATH and/or --baseline "
                          f"{'|'.join(BASELINES)}")
    tested = [test_env(s, plan, pairs) for s in specs]
    return tested if run_dir is None else [recorded(s, run_dir) for s in tested]


def first_env(plan: TestPlan) -> EnvConfig:
    """The env the plan's first agent drives in (its sim section, its ROS domain)."""
    return resolve_agents(plan)[0].run.env


def recorded(spec: AgentSpec, run_dir: Path) -> AgentSpec:
    """``spec`` with its episodes recorded to ``<run_dir>/<its name>/``."""
    run = spec.run.replace(env={
        "record.enabled": True, "record.bags_dir": str(run_dir), "record.run": spec.name})
    return replace(spec, run=run, scenario=spec.scenario and spec.scenario.for_env(run.env))


def scenario_of(spec: AgentSpec) -> Scenario:
    """The resolved test env of ``spec``: ``test_env``'s, else resolved now."""
    return spec.scenario or Scenario(spec.run.env)


def test_env(spec: AgentSpec, plan: TestPlan, pairs: str | None) -> AgentSpec:
    """``spec`` set up for testing: the test episodes, no curriculum, in the test env's world
    (never the training worlds of ``episodes.world_variants``), resolved once (``scenario``)."""
    overrides: dict[str, Any] = {"agent": spec.name, "episodes.starting_episodes": 0,
                                 "episodes.world_variants": ""}
    if not spec.run.env.simulated:
        return replace(spec, run=spec.run.replace(env={**overrides, "episodes.file": ""}),
                       episode_set=_without_sim(plan, pairs))
    from pic4rl_sim.config import SimParams

    scenario = Scenario(spec.run.env.replace(**{"episodes.world_variants": ""}))
    sim = scenario.sim  # none: a sim node with no sim section, in its defaults' world
    world = (sim.world.kind, sim.world.variant) if sim else (SimParams.world,
                                                              SimParams.world_variant)
    if pairs is None and world == DEFAULT_PAIRS_WORLD:
        pairs = str(DEFAULT_PAIRS)
    if plan.random or not pairs:
        kind = plan.pairs or ("paper" if plan.random else "any")
        overrides.update({"episodes.file": "", "episodes.ordered": False,
                          "episodes.pair_kind": kind})
        episode_set = f"{plan.n_episodes} random pairs of kind {kind!r} with seed {plan.seed}"
    else:
        if plan.pairs:
            raise ConfigError(f"--pairs {plan.pairs}: the test pairs come from {pairs}; add "
                              "--random N to draw N pairs of that kind")
        overrides.update({"episodes.file": pairs, "episodes.ordered": True,
                          "episodes.change_goal_and_pose": 1})
        episode_set = ("the paper's 5 indoor pairs" if pairs == str(DEFAULT_PAIRS)
                       else "pairs file") + f" {pairs}"
    run = spec.run.replace(env=overrides)
    return replace(spec, run=run, episode_set=episode_set, scenario=scenario.for_env(run.env))


def _without_sim(plan: TestPlan, pairs: str | None) -> str:
    """The episodes of a run without a simulator (``EnvConfig.simulated``: a real robot), in
    words; drawn pairs and pairs files, which only a simulator can set up, are refused."""
    given = (f"--random {plan.random}" if plan.random else f"--pairs {plan.pairs}"
             if plan.pairs else f"episodes.file {pairs}" if pairs else "")
    if given:
        raise ConfigError(f"{given}: a run without a simulator (transport ros, ros.sim_node "
                          "'') cannot set starts and goals; the operator sends each goal on "
                          "topics.goal")
    return (f"{plan.n_episodes} episodes without a simulator: each goal from the operator on "
            "topics.goal, no world facts recorded")
