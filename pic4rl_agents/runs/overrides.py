"""Command-line overrides: RL-Zoo-style ``key:value`` items and ROS ``-p key:=value`` values,
read as YAML, and checked key by key against their section's parameters, so that a bad one
is blamed on the flag that gave it and not on the params file whose value it replaces."""

from __future__ import annotations

import re
from collections.abc import Mapping, Sequence
from typing import Any

import yaml

from pic4rl_base.schema import ParamSpec, specs
from pic4rl_bridge.config import EnvConfig
from pic4rl_bridge.errors import ConfigError, require, unknown_key

from pic4rl_agents.runs.config import ENV_NODE, TRAINER_NODE, TrainConfig

_FLOAT = re.compile(r"^[-+]?(\d+\.?\d*|\.\d+)[eE][-+]?\d+$")


def yaml_value(text: str) -> Any:
    """A command-line value as ROS reads it: YAML, plus ``1e-3`` as a number (YAML 1.1 wants
    ``1.0e-3``; RL Zoo users write ``1e-3``)."""
    value = yaml.safe_load(text) if text.strip() else ""
    if isinstance(value, str) and _FLOAT.match(value.strip()):
        return float(value)
    return value


def parse_overrides(items: Sequence[str], *, flag: str) -> dict[str, Any]:
    """RL-Zoo-style ``key:value`` items (values read as YAML: ``0.001``, ``[64, 64]``, ``sac``)
    as a dict of dotted names."""
    out: dict[str, Any] = {}
    for item in items:
        key, sep, text = item.partition(":")
        if not sep or not key.strip():
            raise ConfigError(f"{flag} {item!r}: expected key:value (e.g. learning_rate:0.001)")
        try:
            out[key.strip()] = yaml_value(text)
        except yaml.YAMLError as err:
            raise ConfigError(f"{flag} {item!r}: the value is not valid YAML: {err}") from err
    return out


def _table(node: str) -> dict[str, ParamSpec]:
    """The parameters of ``node``'s section (the sim's names are the same for every robot)."""
    if node == TRAINER_NODE:
        return {spec.name: spec for spec in specs(TrainConfig)}
    if node == ENV_NODE:
        return {spec.name: spec for spec in specs(EnvConfig)}
    from pic4rl_sim.config import ROBOT, parameter_table
    from pic4rl_sim.engine.robot_specs import load_robot

    return {spec.name: spec for spec in parameter_table(load_robot(ROBOT.default))}


def check_overrides(node: str, overrides: Mapping[str, Any], *, where: str) -> dict[str, Any]:
    """``overrides`` of ``node``'s section (trainer, nav_env or sim) when every key is known
    and every value of its type and range; else ``ConfigError`` naming ``where``, the flag
    that gave them, so that a bad command-line value is not blamed on the params file."""
    table = _table(node)
    for key, value in overrides.items():
        if key not in table:
            raise unknown_key(key, table, where=where)
        spec = table[key]
        try:
            typed = spec.check(value)
            if spec.bounds is not None:
                require(typed in spec.bounds, key, value, spec.bounds.expected())
        except ConfigError as err:
            raise ConfigError(f"{where}: {err}") from err
    return dict(overrides)
