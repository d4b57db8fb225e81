"""Training steps per second of the SB3 agents: in process vs through ROS 2, one env vs two.

One run, one task (goToPose with the Jackal's LiDAR in the seeded ``indoor`` world, the
trainer's own file ``config/train_goto_lidar_td3.yaml``: nets [128, 128], batch 128, one torch
thread), with the algorithm switched per case. For each of ``--algorithms`` (ddpg, td3, sac,
ppo) it builds the model as ``pic4rl-train`` does (``pic4rl_agents.models.algorithms.new_model``
on ``pic4rl_agents.training.envs.make_vec_env``) and times ``model.learn``:

- in-process, ``n_envs`` 1: the env's engine in this process;
- ROS 2, ``n_envs`` 1: the env over a real ``pic4rl-sim`` process (lockstep), started as
  ``pic4rl-run`` starts it (``--params-file`` with the run's ``sim:`` section under ``/**``,
  ``-r __ns:=...``), one sim per env;
- in-process, ``n_envs`` 2: two ``SubprocVecEnv`` workers, one engine each;
- ROS 2, ``n_envs`` 2 (``--nenvs2-ros``, td3 by default): two workers, two sims in
  namespaces ``<ns>/env_0`` and ``<ns>/env_1``.

Plus a context row without learning: a monitored env stepped with random actions, in process
and through ROS (``n_envs`` 1), i.e. what the warm-up costs per step.

Each model first learns untimed past ``learning_starts`` (shortened to 500 steps here: the
warm-up acts randomly and updates nothing) so every timed step includes its gradient update;
PPO warms up with one rollout and its update, and its timed runs are whole rollouts
(``ppo.n_steps`` x ``n_envs`` steps, then ``ppo.n_epochs`` epochs). Note that SB3 counts
``train_freq`` and ``gradient_steps`` per vectorised step: with two envs an off-policy model
makes one update per two env steps. Every case keeps its env, model and sims for the whole
run; the timed runs (``--steps`` env steps each, continuing the same training) go round the
cases interleaved, best of ``--repeats``. The last lines are ``RESULT <name> <value>``.

    .venv/bin/python benchmarks/train_throughput.py
"""

from __future__ import annotations

import argparse
import math
import multiprocessing
import os
import random
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import torch
import yaml
from _sim import stop_sim

from pic4rl_agents.models.algorithms import new_model
from pic4rl_agents.runs.config import RunConfig, load_run_config
from pic4rl_agents.training.envs import env_namespace, make_vec_env

ROOT = Path(__file__).resolve().parents[1]
CONFIG = ROOT / "config" / "train_goto_lidar_td3.yaml"
ALGORITHMS = ("ddpg", "td3", "sac", "ppo")
LEARNING_STARTS = 500  # the shipped 5,000 random warm-up steps would only lengthen the run
AFTER_WARMUP = 200  # untimed steps with updates before the first timed run
ROS_TIMEOUT_S = 60.0  # a sim starting on a loaded machine may take longer than the usual 10 s
SEED = 0


@dataclass
class Case:
    """One measured configuration; ``algorithm`` empty: the env alone, random actions."""

    algorithm: str
    transport: str  # inprocess | ros
    n_envs: int
    run: RunConfig
    steps: int  # env steps per timed run
    env: Any = None
    model: Any = None
    best_s_per_step: float = math.inf
    rng: Any = None

    @property
    def name(self) -> str:
        who = self.algorithm or "envonly"
        return f"{who}_{self.transport}" + ("_n2" if self.n_envs == 2 else "")

    @property
    def rate(self) -> float:
        return 1.0 / self.best_s_per_step


@dataclass
class Sizes:
    steps: int
    learning_starts: int = LEARNING_STARTS
    after_warmup: int = AFTER_WARMUP
    train: dict[str, Any] = field(default_factory=dict)  # extra trainer overrides


def run_config(algorithm: str, transport: str, n_envs: int, sizes: Sizes) -> RunConfig:
    """The shipped file with this case's algorithm, transport and number of envs."""
    train: dict[str, Any] = {"algorithm": algorithm or "td3", "n_envs": n_envs,
                             "learning_starts": sizes.learning_starts, "tensorboard": False,
                             "imitation.enabled": False,  # RL's throughput is measured
                             **sizes.train}
    if algorithm == "ppo":
        train["epsilon.initial"] = 0.0  # ε-greedy is off-policy only
    env: dict[str, Any] = {"transport": transport}
    if transport == "ros":
        tag = algorithm or "envonly"
        env.update({"ros.namespace": f"train_bench/{tag}_n{n_envs}",
                    "ros.timeout_s": ROS_TIMEOUT_S})
    return load_run_config([CONFIG], train=train, env=env)


def make_cases(algorithms: list[str], nenvs2_ros: list[str], sizes: Sizes) -> list[Case]:
    cases: list[Case] = []
    for algorithm in algorithms:
        shapes = [("inprocess", 1), ("ros", 1), ("inprocess", 2)]
        if algorithm in nenvs2_ros:
            shapes.append(("ros", 2))
        for transport, n_envs in shapes:
            run = run_config(algorithm, transport, n_envs, sizes)
            steps = sizes.steps
            if algorithm == "ppo":  # whole rollouts, each followed by its update
                rollout = run.train.ppo.n_steps * n_envs
                steps = max(1, round(steps / rollout)) * rollout
            cases.append(Case(algorithm, transport, n_envs, run, steps))
    for transport in ("inprocess", "ros"):
        cases.append(Case("", transport, 1, run_config("", transport, 1, sizes), sizes.steps))
    return cases


def start_sims(cases: list[Case], tmp: Path,
               sims: list[tuple[subprocess.Popen[bytes], Path]]) -> None:
    """One ``pic4rl-sim`` per ROS env, as ``pic4rl-run`` starts them (own process groups), each
    appended to ``sims`` with its log file as soon as it runs."""
    for case in cases:
        if case.transport != "ros":
            continue
        sim_file = tmp / f"{case.name}_sim.yaml"
        sim_file.write_text(yaml.safe_dump({"/**": {"ros__parameters": dict(
            case.run.env.sim_params)}}))
        for rank in range(case.n_envs):
            namespace = env_namespace(case.run.env, rank, case.n_envs) or "/"
            log = tmp / f"{case.name}_{rank}.log"
            with log.open("wb") as out:
                proc = subprocess.Popen(
                    [sys.executable, "-m", "pic4rl_sim.node", "--ros-args", "--params-file",
                     str(sim_file), "-r", f"__ns:={'/' + namespace.lstrip('/')}"],
                    env=dict(os.environ), start_new_session=True, stdin=subprocess.DEVNULL,
                    stdout=out, stderr=subprocess.STDOUT)
            sims.append((proc, log))


def set_up(case: Case, sizes: Sizes) -> None:
    """The case's env and model, trained (untimed) past the warm-up."""
    case.env = make_vec_env(case.run.env, n_envs=case.n_envs, seed=SEED)
    if not case.algorithm:
        case.rng = np.random.default_rng(SEED)
        case.env.reset()
        env_steps(case, sizes.after_warmup)
        return
    case.model = new_model(case.run.train, case.env)
    if case.algorithm == "ppo":
        warm_up = case.run.train.ppo.n_steps * case.n_envs
    else:
        warm_up = sizes.learning_starts + sizes.after_warmup
    case.model.learn(warm_up)


def env_steps(case: Case, steps: int) -> int:
    space = case.env.action_space
    actions = case.rng.uniform(space.low, space.high,
                               size=(steps, case.n_envs, *space.shape)).astype(space.dtype)
    for action in actions:
        case.env.step(action)
    return steps * case.n_envs


def timed_run(case: Case) -> float:
    """Seconds per env step of one timed run of ``case.steps`` steps."""
    start = time.perf_counter()
    if case.model is None:
        done = env_steps(case, case.steps)
    else:
        before = case.model.num_timesteps
        case.model.learn(case.steps, reset_num_timesteps=False)
        done = case.model.num_timesteps - before
    return (time.perf_counter() - start) / done


def rate(case: Case | None) -> float | None:
    return None if case is None else case.rate


def ratio(a: Case | None, b: Case | None) -> float | None:
    return None if a is None or b is None else a.rate / b.rate


def report(cases: list[Case], algorithms: list[str]) -> list[tuple[str, float]]:
    """Print the table; the figures, in order (a case not measured has none)."""
    by = {(c.algorithm, c.transport, c.n_envs): c for c in cases}
    head = ("algorithm", "in-proc/s", "ROS/s", "ROS/in-proc", "in-proc n2/s", "n2/n1 in-proc",
            "ROS n2/s", "n2/n1 ROS")
    print(" ".join(f"{h:>13s}" for h in head))
    figures: list[tuple[str, float]] = []
    for algorithm in [*algorithms, ""]:
        one, ros = by.get((algorithm, "inprocess", 1)), by.get((algorithm, "ros", 1))
        two, ros2 = by.get((algorithm, "inprocess", 2)), by.get((algorithm, "ros", 2))
        values = {"inprocess_steps_per_s": rate(one), "ros_steps_per_s": rate(ros),
                  "ros_over_inprocess": ratio(ros, one),
                  "nenvs2_inprocess_steps_per_s": rate(two),
                  "nenvs2_over_1_inprocess": ratio(two, one),
                  "nenvs2_ros_steps_per_s": rate(ros2), "nenvs2_over_1_ros": ratio(ros2, ros)}
        cells = [algorithm or "env only"] + [
            "-" if v is None else f"{v:.{2 if 'over' in k else 1}f}" for k, v in values.items()]
        print(" ".join(f"{c:>13s}" for c in cells))
        figures += [(f"train_{algorithm or 'envonly'}_{k}", v) for k, v in values.items()
                    if v is not None]
    return figures


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--steps", type=int, default=1000,
                        help="env steps per timed run (ppo: rounded to whole rollouts)")
    parser.add_argument("--repeats", type=int, default=3, help="best of this many timed runs")
    parser.add_argument("--algorithms", nargs="+", default=list(ALGORITHMS),
                        choices=ALGORITHMS, metavar="ALGO", help="of ddpg td3 sac ppo")
    parser.add_argument("--nenvs2-ros", nargs="*", default=["td3"], choices=ALGORITHMS,
                        metavar="ALGO",
                        help="algorithms also measured with two envs through ROS 2")
    parser.add_argument("--domain", type=int, help="ROS domain id (default: random in 1..100)")
    parser.add_argument("--quick", action="store_true",
                        help="tiny sizes (a smoke test of the script, not a measurement)")
    args = parser.parse_args(argv)
    sizes = Sizes(steps=args.steps)
    if args.quick:
        sizes = Sizes(steps=32, learning_starts=32, after_warmup=8,
                      train={"batch_size": 16, "ppo.n_steps": 32, "ppo.n_epochs": 2})
        args.repeats = 1
    domain = args.domain if args.domain is not None else random.SystemRandom().randint(1, 100)
    # Before any env, worker or sim exists: they all inherit it.
    os.environ["ROS_DOMAIN_ID"] = str(domain)
    os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"

    # SubprocVecEnv's workers fork from a server that imported these once (setup time only).
    multiprocessing.set_forkserver_preload(["pic4rl_agents.training.envs"])
    cases = make_cases(args.algorithms, [a for a in args.nenvs2_ros if a in args.algorithms],
                       sizes)
    torch.set_num_threads(cases[0].run.train.torch_threads or torch.get_num_threads())
    tmp = tempfile.TemporaryDirectory(prefix="train_throughput_")
    sims: list[tuple[subprocess.Popen[bytes], Path]] = []
    began = time.perf_counter()
    try:
        start_sims(cases, Path(tmp.name), sims)
        for case in cases:
            t0 = time.perf_counter()
            set_up(case, sizes)
            print(f"set up {case.name}: {time.perf_counter() - t0:.1f} s", file=sys.stderr)
        print(f"set up {len(cases)} cases, {len(sims)} sims in "
              f"{time.perf_counter() - began:.0f} s", file=sys.stderr)
        for round_ in range(args.repeats):
            for case in cases:
                case.best_s_per_step = min(case.best_s_per_step, timed_run(case))
            print(f"round {round_ + 1}/{args.repeats}: " + ", ".join(
                f"{c.name} {c.rate:.0f}/s" for c in cases), file=sys.stderr)
    except BaseException:
        for proc, log in sims:
            if proc.poll() is not None:
                print(f"sim {log.stem} exited with {proc.returncode}:\n"
                      f"{log.read_text(errors='replace')[-2000:]}", file=sys.stderr)
        raise
    finally:
        try:
            for case in cases:
                if case.env is not None:
                    try:
                        case.env.close()
                    except (OSError, EOFError) as err:  # a worker gone (Ctrl-C reaches them)
                        print(f"closing {case.name}: {err!r}", file=sys.stderr)
        finally:
            for proc, _ in sims:
                stop_sim(proc)
            tmp.cleanup()
    print(f"config {CONFIG.relative_to(ROOT)}: nets {list(cases[0].run.train.policy.net_arch)}, "
          f"batch {cases[0].run.train.batch_size}, {sizes.steps} env steps per timed run "
          f"(ppo: whole rollouts), best of {args.repeats}, "
          f"{time.perf_counter() - began:.0f} s in all")
    for name, value in report(cases, args.algorithms):
        print(f"RESULT {name} {value:.{2 if 'over' in name else 1}f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
