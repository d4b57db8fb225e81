"""``pic4rl-run``: the sim node(s) and a trainer or tester started together, and stopped
together on exit, Ctrl-C or SIGTERM (what ``ros2 launch`` would do; there is none here).

    pic4rl-run train --ros-args --params-file config/train_goto_lidar_td3.yaml
    pic4rl-run test --agent checkpoints/td3_lidar --baseline proportional

The command after ``train``/``test`` is ``pic4rl-train``'s or ``pic4rl-test``'s, unchanged,
with the env switched to the ROS 2 transport (``-p transport:=ros``). One ``pic4rl-sim`` is
started per env with the run's ``sim:`` section (``n_envs > 1``: in namespaces ``env_0``,
``env_1``, ...), in the same ROS domain. Each process gets its own process group: Ctrl-C
reaches the trainer first (it saves its model), then the sims are stopped; a launcher killed
outright takes its sims with it (``pic4rl_agents.launch.simproc``).
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import tempfile
import time
from collections.abc import Sequence
from pathlib import Path
from types import FrameType

from pic4rl_agents.training.envs import env_namespace
from pic4rl_base import params_file
from pic4rl_base.entry import entry_point
from pic4rl_bridge.config import EnvConfig
from pic4rl_bridge.errors import BridgeError
from pic4rl_bridge.scenario import Scenario

from pic4rl_agents.launch.rosargs import RosArgs, split_ros_args
from pic4rl_agents.launch.simproc import start_sim, stop_group

COMMANDS = {"train": "pic4rl_agents.training.train", "test": "pic4rl_agents.testing.tester"}
STOP_TIMEOUT_S = 30.0  # a trainer saving its replay buffer may need a while


def _resolve(command: str, plain: list[str], ros: RosArgs) -> tuple[EnvConfig, int]:
    """The env the child will drive (its sim section, its ROS domain), and its number of
    envs."""
    if command == "train":
        from pic4rl_agents.training.args import build_parser, resolve

        run, _ = resolve(build_parser().parse_args(plain), ros)
        return run.env, run.train.n_envs
    from pic4rl_agents.testing.plan import first_env
    from pic4rl_agents.testing.tester import build_parser as test_parser
    from pic4rl_agents.testing.tester import build_plan

    return first_env(build_plan(test_parser().parse_args(plain), ros)), 1


def _usage() -> str:
    return ("usage: pic4rl-run {train,test} [pic4rl-train or pic4rl-test arguments] "
            "--ros-args --params-file FILE ...\n       pic4rl-run stack --command CMD "
            "--params-file FILE ... (a ROS 2 stack as the agent: pic4rl-run stack --help)")


@entry_point("pic4rl-run", BridgeError)
def main(argv: Sequence[str] | None = None) -> int:
    """Run; the child's exit code (1 if a sim died under it, 2 for bad arguments)."""
    argv = list(sys.argv[1:] if argv is None else argv)
    if not argv or argv[0] in ("-h", "--help"):
        print(_usage() + "\n\n" + __doc__)
        return 0 if argv else 2
    command, rest = argv[0], argv[1:]
    if command == "stack":  # a ROS 2 stack as the agent (docs/your-agent.md)
        from pic4rl_agents.stack.cli import main as stack_main

        return stack_main(rest)
    if command not in COMMANDS:
        print(f"pic4rl-run: unknown command {command!r}\n{_usage()}", file=sys.stderr)
        return 2
    try:
        plain, ros = split_ros_args(rest)
        ros.params["transport"] = "ros"
        run_env, n_envs = _resolve(command, plain, ros)
    except SystemExit as exit_:  # argparse's --help or usage error, printed already
        return int(exit_.code or 0)
    env = dict(os.environ)
    if run_env.ros.domain_id >= 0:
        env["ROS_DOMAIN_ID"] = str(run_env.ros.domain_id)
    with tempfile.TemporaryDirectory(prefix="pic4rl-run-") as tmp:
        sim_file = Path(tmp) / "sim.yaml"
        sim_file.write_text(params_file.dump({"/**": Scenario(run_env).node_values}))
        sims: list[subprocess.Popen[bytes]] = []
        for rank in range(n_envs):
            namespace = env_namespace(run_env, rank, n_envs) or "/"
            sims.append(start_sim(["--params-file", str(sim_file),
                                   "-r", f"__ns:={'/' + namespace.lstrip('/')}"], env))
        child = subprocess.Popen([sys.executable, "-m", COMMANDS[command], *plain,
                                  *ros.as_args()], env=env, start_new_session=True)
        return _watch(command, child, sims)


def _watch(command: str, child: subprocess.Popen[bytes],
           sims: list[subprocess.Popen[bytes]]) -> int:
    """Wait for the child, or a signal to us, or a sim's death; then stop them all, the child
    first. The child's exit code, or 1 when a sim died under it."""
    stopping: list[int] = []

    def forward(signum: int, frame: FrameType | None) -> None:
        stopping.append(signum)

    previous = {s: signal.signal(s, forward) for s in (signal.SIGINT, signal.SIGTERM)}
    code = 0
    try:
        while child.poll() is None:
            if stopping:
                print("pic4rl-run: stopping", file=sys.stderr)
                break
            dead = [s for s in sims if s.poll() is not None]
            if dead:
                print(f"pic4rl-run: a sim exited with code {dead[0].returncode}; "
                      f"stopping the {command}er", file=sys.stderr)
                code = 1
                break
            time.sleep(0.2)
    finally:
        child_code = stop_group(child, STOP_TIMEOUT_S)
        for sim in sims:
            stop_group(sim, 10.0)
        for signum, handler in previous.items():
            signal.signal(signum, handler)
    return code or child_code

if __name__ == "__main__":
    sys.exit(main())
