"""The sim node's parameter table in ROS terms: declarations with descriptors (ranges,
choices), ``-p`` rules as overrides, ``--help``; and the bridge from the package's Python
logging to the node's logger."""

from __future__ import annotations

import logging
from typing import Any

from rcl_interfaces.msg import FloatingPointRange, IntegerRange, ParameterDescriptor
from rclpy.node import Node
from rclpy.parameter import Parameter

from pic4rl_base.errors import ConfigError
from pic4rl_base.schema import ParamSpec, ParamType, help_text

from ..config import ROBOT, parameter_table, resolve
from ..engine.robot_specs import load_robot

_ROS_TYPES = {ParamType.BOOL: Parameter.Type.BOOL, ParamType.INTEGER: Parameter.Type.INTEGER,
              ParamType.DOUBLE: Parameter.Type.DOUBLE, ParamType.STRING: Parameter.Type.STRING,
              ParamType.DOUBLE_ARRAY: Parameter.Type.DOUBLE_ARRAY,
              ParamType.INTEGER_ARRAY: Parameter.Type.INTEGER_ARRAY,
              ParamType.STRING_ARRAY: Parameter.Type.STRING_ARRAY}


def _descriptor(spec: ParamSpec) -> ParameterDescriptor:
    desc = ParameterDescriptor(description=spec.description)
    if spec.choices:
        desc.additional_constraints = f"one of {', '.join(spec.choices)}"
    if spec.range is not None and spec.type is ParamType.INTEGER:
        desc.integer_range = [IntegerRange(from_value=int(spec.range[0]),
                                           to_value=int(spec.range[1]), step=1)]
    elif spec.range is not None:
        desc.floating_point_range = [FloatingPointRange(from_value=float(spec.range[0]),
                                                        to_value=float(spec.range[1]), step=0.0)]
    return desc


def declare(node: Node) -> tuple[dict[str, ParamSpec], dict[str, Any]]:
    """Declare the table on ``node`` (robot first: its sensors are the defaults) with the
    values of the params files and ``-p`` checked against it; the table and the values."""
    overrides = {name: p.value for name, p in node._parameter_overrides.items()}
    robot = load_robot(ROBOT.check(overrides.get(ROBOT.name, ROBOT.default)))
    table = {spec.name: spec for spec in parameter_table(robot)}
    values = resolve(table.values(), overrides, also_known=node._parameters)
    node.declare_parameters("", [(s.name, _ROS_TYPES[s.type], _descriptor(s))
                                 for s in table.values()], ignore_override=True)
    node.set_parameters([Parameter(name, _ROS_TYPES[table[name].type], value)
                         for name, value in values.items()])
    return table, values


def usage() -> str:
    """``pic4rl-sim --help``."""
    return "\n".join(["usage: pic4rl-sim [--ros-args [--params-file FILE] [-p NAME:=VALUE] ...]",
                      "", "parameters (sensor defaults: the default robot's):",
                      help_text(parameter_table(load_robot(ROBOT.default)))])


def rules_as_parameters(rules: dict[str, Any]) -> list[Parameter]:
    """``-p`` rules as overrides for the node (checked against the table there)."""
    out = []
    for name, value in rules.items():
        try:
            out.append(Parameter(name, value=value))
        except (TypeError, ValueError) as err:
            raise ConfigError(f"-p {name}: {value!r} is not a ROS parameter value") from err
    return out


class NodeLogHandler(logging.Handler):
    """Forwards the package's Python log records (the engine's) to the node's logger."""

    def __init__(self, node: Node) -> None:
        super().__init__()
        self._logger = node.get_logger()

    def emit(self, record: logging.LogRecord) -> None:
        level = record.levelno
        log = (self._logger.error if level >= logging.ERROR else self._logger.warning
               if level >= logging.WARNING else self._logger.info)
        log(self.format(record))
