"""The ``--ros-args`` part of a command line: params files and ``-p key:=value``.

There is no ``ros2 launch`` here, and our nodes read three sections of one params file (sim,
nav_env, trainer), so the agents' commands read ``--params-file`` and ``-p`` themselves, with
ROS's syntax, and hand rcl's other ROS arguments (``-r``, ``--log-level``) to ``rclpy.init``.
A segment runs to a lone ``--`` or to the end of the line, as in ROS; a command's own flag
inside it is refused in one line (rcl would refuse it too).
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import yaml

from pic4rl_bridge.config import EnvConfig
from pic4rl_bridge.errors import ConfigError

from pic4rl_agents.runs.overrides import yaml_value


@dataclass
class RosArgs:
    params_files: list[str] = field(default_factory=list)
    params: dict[str, Any] = field(default_factory=dict)  # -p key:=value, values as YAML
    rest: list[str] = field(default_factory=list)  # other ROS args, for rclpy.init

    def as_args(self) -> list[str]:
        """These arguments as a ``--ros-args`` tail again (for a child process)."""
        out = ["--ros-args"]
        for path in self.params_files:
            out += ["--params-file", path]
        for key, value in self.params.items():
            out += ["-p", f"{key}:={yaml.safe_dump(value, default_flow_style=True).strip()}"
                    .replace("\n...", "")]
        return out + self.rest


#: rcl's other ROS arguments (besides ``--params-file`` and ``-p``): those taking a value,
#: and the flags. Anything else inside ``--ros-args`` is refused, as rcl refuses it.
ROS_VALUE_ARGS = ("-r", "--remap", "-e", "--enclave", "--log-level", "--log-file-name",
                  "--log-config-file")
ROS_FLAGS = tuple(f"--{state}-{logs}-logs" for state in ("enable", "disable")
                  for logs in ("rosout", "stdout", "external-lib"))


def split_ros_args(argv: Sequence[str]) -> tuple[list[str], RosArgs]:
    """``argv`` without its ``--ros-args ... [--]`` segments, and what those segments held; a
    segment holds ROS arguments only (a command's flag there, such as ``--no-progress``
    after ``--params-file FILE``, is a ``ConfigError``, never silently dropped)."""
    plain: list[str] = []
    ros = RosArgs()
    i, inside = 0, False
    while i < len(argv):
        arg = argv[i]
        if arg == "--ros-args":
            inside = True
        elif inside and arg == "--":
            inside = False
        elif not inside:
            plain.append(arg)
        elif arg == "--params-file":
            if i + 1 >= len(argv):
                raise ConfigError("--params-file: expected a file name after it")
            ros.params_files.append(argv[i + 1])
            i += 1
        elif arg in ("-p", "--param"):
            if i + 1 >= len(argv) or ":=" not in argv[i + 1]:
                raise ConfigError(f"{arg}: expected key:=value after it")
            key, _, text = argv[i + 1].partition(":=")
            try:
                ros.params[key] = yaml_value(text)
            except yaml.YAMLError as err:
                raise ConfigError(f"{arg} {argv[i + 1]}: the value is not valid YAML") from err
            i += 1
        elif arg in ROS_VALUE_ARGS or arg in ROS_FLAGS:
            ros.rest.append(arg)
            if arg in ROS_VALUE_ARGS and i + 1 < len(argv):
                ros.rest.append(argv[i + 1])
                i += 1
        else:
            raise ConfigError(f"{arg}: not a ROS argument, but inside --ros-args (which runs to "
                              "a lone -- or to the end of the line); give the command's own "
                              "flags before --ros-args or after --")
        i += 1
    return plain, ros


def no_sim_hint(command: str, env: EnvConfig | None) -> str:
    """What to tell a user whose ROS env heard nothing (``command``: train or test): to start
    a sim, or, when no sim is configured (``ros.sim_node`` empty: a real robot), to check the
    robot's topics."""
    if env is not None and not env.ros.sim_node:
        return (f"  Is the robot publishing in ROS domain {ros_domain(env)}? Check the topic "
                "names (ros2 topic list, ros2 topic info -v NAME) and map each with "
                "-p topics.<key>:=NAME (topics.pose, topics.scan, ...), or its QoS with "
                "-p ros.sensor_qos:=reliable|best_effort")
    return (f"  Is a sim answering in ROS domain {ros_domain(env)}? Start one with the same "
            f"params file (pic4rl-sim --ros-args --params-file FILE), or use pic4rl-run "
            f"{command}, or -p transport:=inprocess")


def ros_domain(env: EnvConfig | None) -> str:
    """The ROS domain an env talks in: its ``ros.domain_id``, else ``ROS_DOMAIN_ID`` (or 0)."""
    if env is not None and env.ros.domain_id >= 0:
        return str(env.ros.domain_id)
    return os.environ.get("ROS_DOMAIN_ID", "0")
