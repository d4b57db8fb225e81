"""A ROS 2 stack as one more agent of a ``pic4rl-bench`` suite (``agents: {NAME: {stack:
...}}``): the example rclpy node, which imports nothing of this project, drives its cell through
the sim node in a ROS domain of its own beside an in-process baseline, and both are rows of one
BARN table judged from their bags; a bad stack entry stops the command with one line, exit code
2, before any cell runs."""

from __future__ import annotations

import csv
import os
import subprocess
import sys
from pathlib import Path

import pytest
import yaml

from pic4rl_agents.suites import runner as bench
from pic4rl_agents.suites.suite import load_suite
from pic4rl_metrics import compute

REPO = Path(__file__).resolve().parents[3]
NODE = REPO / "examples" / "ros_gap_follower_node.py"


def _suite(folder: Path, agents: dict) -> Path:
    """One task, BARN's table: ``agents`` and DWA on 2 episodes of barn:0 (at most 150 steps)."""
    env = yaml.safe_load((REPO / "config" / "env_barn.yaml").read_text())
    env["nav_env"]["ros__parameters"]["episode_max_steps"] = 150
    (folder / "env.yaml").write_text(yaml.safe_dump(env))
    (folder / "suite.yaml").write_text(yaml.safe_dump({
        "suite": "stacked", "bags": "bags", "table": "barn", "retries": 0,
        "tasks": [{"name": "barn", "env": "env.yaml", "agents": agents, "baselines": ["dwa"],
                   "worlds": ["barn:0"], "pairs": [{"episodes": 2}]}]}))
    return folder / "suite.yaml"


@pytest.mark.integration
def test_a_stack_and_a_baseline_are_two_rows_of_one_barn_table(tmp_path: Path,
                                                               domain: int) -> None:
    # a command relative to the suite file's folder, where it runs
    (tmp_path / "node.py").write_text(NODE.read_text())
    suite = load_suite(_suite(tmp_path, {"gap_node": {"stack": {
        "command": f"{sys.executable} node.py", "silence_s": 20}}}))
    stack_cell, dwa_cell = suite.cells
    assert (stack_cell.agent, stack_cell.transport, stack_cell.baseline) == ("gap_node", "ros", "")
    assert stack_cell.stack is not None and stack_cell.stack.name == "gap_node"
    assert (dwa_cell.baseline, dwa_cell.transport, dwa_cell.stack) == ("dwa", "inprocess", None)

    # the command in a process of its own, as a user runs it: its pool forks workers from a
    # process that has not used rclpy (this one has, in other tests)
    env = {**os.environ, "PYTHONPATH": str(REPO), "ROS_DOMAIN_ID": str(domain),
           "ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST"}
    done = subprocess.run([sys.executable, "-m", "pic4rl_agents.suites.runner",
                           str(suite.path), "--local", "--workers", "2", "--no-progress"],
                          env=env, capture_output=True, text=True, timeout=300, check=False)
    assert done.returncode == 0, done.stderr[-2000:]
    with (suite.root / "results.csv").open() as f:
        rows = list(csv.DictReader(f))
    assert [r["agent"] for r in rows] == ["gap_node", "dwa"]
    assert "BARN score [-]" in rows[0]
    for row in rows:
        assert (row["status"], row["world"], row["n"]) == ("ok", "barn:0", "2"), row
        bags = sorted(suite.root.glob(f"barn-{row['agent']}-*/{row['agent']}/episode_*"))
        frame = compute(bags).frame
        assert len(frame) == 2 and set(frame["agent"]) == {row["agent"]}
        for rate, outcome in (("success", "goal"), ("collision", "collision"),
                              ("timeout", "timeout")):
            assert row[rate] == f"{int((frame['outcome'] == outcome).sum())}/2"
    stack_bags = suite.root / stack_cell.name / "gap_node"
    assert (suite.root / stack_cell.name / "sim.yaml").is_file()  # its own sim node's params
    frame = compute(sorted(stack_bags.glob("episode_*"))).frame
    assert (frame["world"] == "barn:0").all() and (frame["path_length_m"] > 0.1).all()
    assert "gap_node" in (suite.root / "results.md").read_text()


@pytest.mark.bad_input
@pytest.mark.parametrize(("entry", "message"), [
    ({"stack": {"clock": "lockstep"}}, "tasks[0].agents.gap.stack.command: expected a command "
     "line, got None"),
    ({"stack": {"command": "python n.py", "restart": "always"}},
     "tasks[0].agents.gap.stack.restart: 'always'; expected one of episode, never"),
    ({"stack": {"command": "python n.py", "silence_s": 0}},
     "tasks[0].agents.gap.stack.silence_s: expected a positive number, got 0"),
    ({"stack": {"command": "no_such_program_xyz --go"}}, "tasks[0].agents.gap.stack.command: "
     "'no_such_program_xyz' is invalid; expected a program on the PATH or a file beside"),
    ({"stack": {"command": "python n.py", "name": "other"}},
     "tasks[0].agents.gap.stack.name: 'other'; a suite's stack is named by its agents key"),
    ({"stack": "python n.py"}, "tasks[0].agents.gap.stack: expected a mapping with a "
     "'command', got 'python n.py'"),
    ({"stak": {"command": "python n.py"}}, "tasks[0].agents.gap: unknown key 'stak'; did you "
     "mean 'stack'?"),
])
def test_a_bad_stack_entry_exits_2_in_one_line_before_any_cell(
        tmp_path: Path, capsys: pytest.CaptureFixture, entry: dict, message: str) -> None:
    path = _suite(tmp_path, {"gap": entry})
    assert bench.main([str(path), "--local", "--workers", "1", "--no-progress"]) == 2
    out, err = capsys.readouterr()
    line, = err.splitlines()
    assert line.startswith(f"pic4rl-bench: {path}: {message}"), line
    assert out == ""
    assert not (tmp_path / "bags").exists()  # no cell ran, not even the bags folder
