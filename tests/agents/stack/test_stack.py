"""A ROS 2 stack as the agent (``pic4rl_agents.stack``): the example rclpy node
(``examples/ros_gap_follower_node.py``, which imports nothing of this project) drives the sim
node in lockstep; its bags are judged under the stack's name. A stack that stays silent, dies
or sends NaN ends its episode ``aborted`` with the reason, and leaves no process behind; one
that never starts fails with one line. ``stack:`` is checked when read."""

from __future__ import annotations

import os
import sys
import time
from pathlib import Path

import numpy as np
import pytest
import yaml

from pic4rl_agents.stack.driver import StackError, drive_stack
from pic4rl_agents.stack.spec import StackSpec, stack_spec
from pic4rl_bridge.errors import ConfigError
from pic4rl_metrics import read_episode

REPO = Path(__file__).resolve().parents[3]
PAIRS = REPO / "pic4rl_agents" / "data" / "goals_indoor_test.json"
NODE = REPO / "examples" / "ros_gap_follower_node.py"


def _env(folder: Path, steps: int = 300) -> Path:
    path = folder / "env.yaml"
    path.write_text(yaml.safe_dump({
        "sim": {"ros__parameters": {"robot": "jackal", "world": "indoor", "world_variant": 0}},
        "nav_env": {"ros__parameters": {"task": "goToPose", "sensor": "lidar",
                                        "episode_max_steps": steps}}}))
    return path


def _drive(tmp_path: Path, stack: StackSpec, domain: int, episodes: int = 2,
           steps: int = 300) -> list[str]:
    overrides = {"episodes.file": str(PAIRS), "record.enabled": True,
                 "record.bags_dir": str(tmp_path / "bags"), "record.run": stack.name,
                 "ros.timeout_s": 20.0, "episodes.ordered": True}
    return drive_stack(stack, str(_env(tmp_path, steps)), overrides=overrides,
                       episodes=episodes, seed=0, domain=domain, cwd=tmp_path,
                       sim_file=tmp_path / "sim.yaml")


def _tagged(tag: str) -> list[int]:
    """Live processes whose environment holds ``tag``."""
    found = []
    for entry in os.scandir("/proc"):
        if entry.name.isdigit():
            try:
                environ = Path(f"/proc/{entry.name}/environ").read_bytes()
                state = Path(f"/proc/{entry.name}/stat").read_text().split(") ")[1][0]
            except (OSError, IndexError):
                continue
            if tag.encode() in environ.split(b"\0") and state != "Z":
                found.append(int(entry.name))
    return found


@pytest.mark.integration
def test_the_example_node_drives_two_paper_pairs_judged_under_its_name(
        tmp_path: Path, domain: int, monkeypatch: pytest.MonkeyPatch) -> None:
    tag = f"PIC4RL_STACK_TEST={tmp_path.name}"
    monkeypatch.setenv(*tag.split("=", 1))
    stack = stack_spec({"command": f"{sys.executable} {NODE}", "name": "gap_node"}, "test")
    start = time.monotonic()
    outcomes = _drive(tmp_path, stack, domain)
    wall = time.monotonic() - start
    assert len(outcomes) == 2 and "aborted" not in outcomes, outcomes
    bags = sorted((tmp_path / "bags" / "gap_node").glob("episode_*"))
    assert len(bags) == 2
    steps = 0
    for bag, outcome in zip(bags, outcomes):
        episode = read_episode(bag)
        assert episode.facts.agent == "gap_node" and episode.facts.outcome == outcome
        cmd = episode.inputs["cmd"]
        assert len(cmd.vx) > 5 and max(cmd.vx) > 0.1  # the stack's commands, recorded
        steps += len(cmd.vx)
    assert outcomes[0] == "goal", outcomes  # along the corridor: 5.5 m, straight
    print(f"stack: {steps} steps in {wall:.1f} s wall, {steps / wall:.0f} steps/s")
    assert _tagged(tag) == []


SILENT = "import rclpy, time\nfrom geometry_msgs.msg import Twist\nfrom sensor_msgs.msg import " \
         "LaserScan\nrclpy.init()\nn = rclpy.create_node('bad')\np = n.create_publisher(Twist, " \
         "'cmd_vel', 10)\nn.create_subscription(LaserScan, 'scan', lambda m: {body}, " \
         "rclpy.qos.qos_profile_sensor_data)\n{extra}rclpy.spin(n)\n"
BAD = {
    "silent": ("(c.append(1), len(c) <= 3 and p.publish(Twist()))", "c = []\n",
               "sent no cmd_vel within 2 s"),
    "dies": ("(c.append(p.publish(Twist())), len(c) > 5 and os._exit(3))",
             "import os, subprocess\nc = []\nsubprocess.Popen(['sleep', '300'])\n",
             "exited with code 3"),
    "nan": ("(c.append(p.publish(Twist())), len(c) > 5 and p.publish(Twist(linear=Vector3("
            "x=float('nan')))))", "from geometry_msgs.msg import Vector3\nc = []\n",
            "non-finite cmd_vel (nan, 0.0, 0.0)"),
}


@pytest.mark.integration
@pytest.mark.parametrize("kind", sorted(BAD))
def test_a_failing_stack_ends_its_episode_aborted_and_leaves_no_process(
        tmp_path: Path, domain: int, monkeypatch: pytest.MonkeyPatch, kind: str) -> None:
    body, extra, reason = BAD[kind]
    (tmp_path / "bad.py").write_text(SILENT.format(body=body, extra=extra))
    tag = f"PIC4RL_STACK_TEST={tmp_path.name}"
    monkeypatch.setenv(*tag.split("=", 1))
    stack = stack_spec({"command": f"{sys.executable} bad.py", "name": "bad",
                        "silence_s": 2}, "test")
    assert _drive(tmp_path, stack, domain, episodes=1) == ["aborted"]
    episode = read_episode(next((tmp_path / "bags" / "bad").glob("episode_*")))
    assert episode.facts.outcome == "aborted" and reason in episode.facts.end_reason
    assert _tagged(tag) == []  # the stack, its child (sleep 300) and the sim: all gone


@pytest.mark.integration
def test_a_stack_that_never_starts_fails_in_one_line(tmp_path: Path, domain: int) -> None:
    stack = stack_spec({"command": "sleep 60", "name": "late", "start_timeout_s": 2}, "test")
    with pytest.raises(StackError, match=r"^stack late: 'sleep 60' did not start within 2 s "
                       r"\(no publisher on /cmd_vel and subscriber on /scan"):
        _drive(tmp_path, stack, domain, episodes=1)


@pytest.mark.parametrize(("raw", "error"), [
    ("python x.py", r"^s.stack: expected a mapping with a 'command', got 'python x.py'$"),
    ({"name": "a"}, r"^s.stack.command: expected a command line, got None$"),
    ({"command": "x", "clock": "fast"},
     r"^s.stack.clock: 'fast'; expected one of lockstep, realtime$"),
    ({"command": "x", "restart": "always"},
     r"^s.stack.restart: 'always'; expected one of episode, never$"),
    ({"command": "x", "comand": "y"}, r"^s.stack: unknown key 'comand'; expected one of "),
    ({"command": "x", "name": "a/b"}, r"^s.stack.name: expected a name for the bags' folder"),
    ({"command": "x", "silence_s": 0}, r"^s.stack.silence_s: expected a positive number, got 0"),
    ({"command": "x 'y"}, r"^s.stack.command: \"x 'y\": No closing quotation$"),
])
def test_stack_key_errors_are_one_line(raw: object, error: str) -> None:
    with pytest.raises(ConfigError, match=error):
        stack_spec(raw, "s.stack")


def test_stack_key_defaults() -> None:
    spec = stack_spec({"command": "python my_node.py --fast"}, "s")
    assert spec == StackSpec(("python", "my_node.py", "--fast"), "stack", "lockstep", "episode",
                             "", 10.0, 30.0, 5.0)


@pytest.mark.integration
def test_pic4rl_run_stack_drives_the_example_node(tmp_path: Path, domain: int,
                                                  monkeypatch: pytest.MonkeyPatch,
                                                  capfd: pytest.CaptureFixture[str]) -> None:
    from pic4rl_agents.launch import run

    monkeypatch.setenv("ROS_DOMAIN_ID", str(domain))  # the lease takes one after it
    code = run.main(["stack", "--command", f"{sys.executable} {NODE}", "--name", "cli_node",
                     "--params-file", str(_env(tmp_path)), "--pairs", str(PAIRS),
                     "--episodes", "1", "--bags", str(tmp_path / "bags")])
    assert code == 0
    assert capfd.readouterr().out.strip().splitlines()[-1] == "cli_node episode 0: goal"
    bag = tmp_path / "bags" / "cli_node" / "episode_0000"
    assert read_episode(bag).facts.agent == "cli_node"


def test_pic4rl_run_stack_refuses_a_bad_key_in_one_line(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    from pic4rl_agents.launch import run

    code = run.main(["stack", "--command", "x 'y", "--params-file", "env.yaml"])
    assert code == 2
    assert capsys.readouterr().err.strip().splitlines() == [
        "pic4rl-run: pic4rl-run stack.command: \"x 'y\": No closing quotation"]


@pytest.mark.integration
def test_the_example_node_reaches_the_first_pair_in_realtime(tmp_path: Path,
                                                             domain: int) -> None:
    stack = stack_spec({"command": f"{sys.executable} {NODE}", "name": "rt_node",
                        "clock": "realtime", "real_time_factor": 10}, "test")
    assert _drive(tmp_path, stack, domain, episodes=1) == ["goal"]
    bag = next((tmp_path / "bags" / "rt_node").glob("episode_*"))
    episode = read_episode(bag)
    assert episode.facts.agent == "rt_node"
    steps = np.diff(episode.inputs["cmd"].t_ns[1:])  # in sim time: whole control periods
    assert (steps > 0).all() and (steps % 100_000_000 == 0).all()  # (the sim's timer may
    # step twice while the env waits for the machine)


RESETTABLE = """import rclpy, sys
from geometry_msgs.msg import Twist
from sensor_msgs.msg import LaserScan
from std_srvs.srv import Empty
rclpy.init()
n = rclpy.create_node('kept')
p = n.create_publisher(Twist, 'cmd_vel', 10)
n.create_subscription(LaserScan, 'scan', lambda m: p.publish(Twist()),
                      rclpy.qos.qos_profile_sensor_data)
def reset(request, response):
    with open('resets.txt', 'a') as f:
        f.write('reset\\n')
    return response
n.create_service(Empty, 'my_stack/reset', reset)
rclpy.spin(n)
"""


@pytest.mark.integration
def test_a_kept_stack_is_reset_through_its_service_each_episode(tmp_path: Path,
                                                                domain: int) -> None:
    (tmp_path / "kept.py").write_text(RESETTABLE)
    stack = stack_spec({"command": f"{sys.executable} kept.py", "name": "kept",
                        "restart": "never", "reset_service": "my_stack/reset"}, "test")
    assert _drive(tmp_path, stack, domain, episodes=3, steps=5) == ["timeout"] * 3
    # the first episode starts the process; the next two call its reset service first
    assert (tmp_path / "resets.txt").read_text() == "reset\n" * 2
