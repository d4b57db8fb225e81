"""``pic4rl-run`` without starting anything: usage and bad arguments exit before a sim is
started, and the namespaces its sims get (``env_<rank>`` when there are several envs)."""

from __future__ import annotations

import contextlib
import io
import subprocess
import sys
import uuid

import pytest
from agents_helpers import LIDAR_TD3, ROOT, processes_with

from pic4rl_agents.launch import run as pic4rl_run
from pic4rl_agents.runs.config import load_run_config
from pic4rl_agents.training.envs import env_for_rank, env_namespace


def run_main(argv: list[str]) -> tuple[int, str, str]:
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = pic4rl_run.main(argv)
    return code, out.getvalue(), err.getvalue()


def test_help_prints_the_usage_and_no_command_is_an_error() -> None:
    code, out, _ = run_main(["--help"])
    assert code == 0 and out.startswith("usage: pic4rl-run {train,test}")
    code, out, _ = run_main([])
    assert code == 2 and out.startswith("usage: pic4rl-run")


@pytest.mark.bad_input
@pytest.mark.parametrize(("argv", "message"), [
    (["fly"], "pic4rl-run: unknown command 'fly'"),
    (["train", "--hyperparams", "learning_rat:0.1", "--ros-args", "--params-file",
      str(LIDAR_TD3)], "did you mean 'learning_rate'"),
    (["train", "--ros-args", "--params-file", "/nonexistent/t.yaml"], "/nonexistent/t.yaml"),
    (["train"], "no --params-file given"),
    (["test", "--agent", "/nonexistent/run"], "--agent /nonexistent/run: no such model"),
    (["test"], "nothing to test"),
    (["train", "--ros-args", "-p"], "-p: expected key:=value"),
])
def test_bad_arguments_exit_2_before_any_sim_starts(
        argv: list[str], message: str, monkeypatch: pytest.MonkeyPatch) -> None:
    tag = f"PIC4RL_TEST_TAG={uuid.uuid4().hex}"
    monkeypatch.setenv(*tag.split("=", 1))  # what a sim started by the launcher would inherit
    code, _, err = run_main(argv)
    assert code == 2
    assert message in err
    assert processes_with(tag, "pic4rl_sim") == []


def test_an_argparse_error_of_the_child_command_exits_2(
        capsys: pytest.CaptureFixture[str]) -> None:
    assert pic4rl_run.main(["train", "--no-such-flag", "--ros-args", "--params-file",
                     str(LIDAR_TD3)]) == 2
    assert "unrecognized arguments: --no-such-flag" in capsys.readouterr().err


def test_python_m_runs_the_launcher() -> None:
    done = subprocess.run([sys.executable, "-m", "pic4rl_agents.launch.run"], cwd=ROOT,
                          capture_output=True, text=True, timeout=120)
    assert done.returncode == 2 and "usage: pic4rl-run" in done.stdout


def test_one_env_keeps_its_namespace_several_get_env_rank() -> None:
    env = load_run_config([LIDAR_TD3], env={"transport": "ros"}).env
    assert env_namespace(env, 0, 1) == ""
    assert [env_namespace(env, r, 2) for r in range(2)] == ["/env_0", "/env_1"]
    robot = env.replace(**{"ros.namespace": "/robot/"})
    assert env_namespace(robot, 1, 3) == "/robot/env_1"
    assert env_for_rank(robot, 1, 3).ros.namespace == "/robot/env_1"
    assert env_for_rank(robot, 0, 1) is robot
    local = load_run_config([LIDAR_TD3]).env
    assert env_for_rank(local, 1, 2) is local  # in process: no namespaces
