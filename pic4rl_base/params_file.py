"""ROS 2 params files: the one place that reads, merges and writes their node sections.

A pic4rl params file holds one section per node, as ``--params-file`` expects::

    sim:      {ros__parameters: {robot: jackal, world: indoor, ...}}      # pic4rl-sim
    nav_env:  {ros__parameters: {task: goToPose, sensor: lidar, ...}}     # the env
    trainer:  {ros__parameters: {algorithm: td3, max_steps: 100000, ...}} # pic4rl-train

A section is found under ``node``, ``/node`` or ``/**/node``; a file with none of these but a
``/**`` section (``config/sim_*.yaml``, which any node name may load) gives it to ``sim``.
Several files merge key by key, later files winning, as ROS merges several ``--params-file``.
A relative file named inside a section (``episodes.file``) is taken from the working directory
when it exists there (ROS's rule), else beside the params file, for every caller alike.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence
from pathlib import Path
from typing import Any

import yaml

from .errors import ConfigError
from .schema import flatten, read_yaml

SIM_NODE = "sim"
ENV_NODE = "nav_env"
TRAINER_NODE = "trainer"
#: Parameters, per section, that name a file relative to the params file.
FILE_KEYS = {ENV_NODE: ("episodes.file",), TRAINER_NODE: ("trained_agent",)}


def read(path: str | Path) -> Mapping[str, Any]:
    """The node sections of a ROS 2 parameter YAML, or ``ConfigError`` naming the file."""
    data = read_yaml(path, "config file")
    if not isinstance(data, Mapping):
        raise ConfigError(f"{path}: expected a mapping of node sections "
                          "(sim:, nav_env:, ...: ros__parameters: ...)")
    return data


def node_section(data: Mapping[str, Any], node: str, *, source: str) -> dict[str, Any] | None:
    """The flat ``ros__parameters`` of the first section for ``node`` (``node``, ``/node``,
    ``/**/node``; for ``sim`` also a lone ``/**``), or ``None`` when the file has none."""
    keys = [node, f"/{node}", f"/**/{node}"]
    if node == SIM_NODE and not any(k in data for k in keys):
        keys.append("/**")
    for key in keys:
        if key in data:
            section = data[key]
            params = section.get("ros__parameters") if isinstance(section, Mapping) else None
            if not isinstance(params, Mapping):
                raise ConfigError(f"{source}: section {key!r} needs a 'ros__parameters' mapping")
            return flatten(params)
    return None


def beside(file: str, params_file: Path) -> str:
    """A relative path named in a params file: as given when it exists from the working
    directory (ROS's rule), else the file beside the params file, so that a shipped config
    works from any directory."""
    if Path(file).is_absolute() or Path(file).exists():
        return file
    candidate = params_file.parent / file
    return str(candidate.resolve()) if candidate.exists() else file


def read_sections(path: str | Path, nodes: Iterable[str]) -> dict[str, dict[str, Any]]:
    """The flat sections ``nodes`` of one file, its relative files (``FILE_KEYS``) found
    ``beside`` it; a file with none of them is an error naming the file."""
    nodes = tuple(nodes)
    data = read(path)
    sections = {node: node_section(data, node, source=str(path)) for node in nodes}
    if all(section is None for section in sections.values()):
        raise ConfigError(f"{path}: no section for {' or '.join(repr(n) for n in nodes)} "
                          f"(expected '{nodes[0]}: ros__parameters: ...')")
    out: dict[str, dict[str, Any]] = {}
    for node, section in sections.items():
        out[node] = dict(section or {})
        for key in FILE_KEYS.get(node, ()):
            value = out[node].get(key)
            if isinstance(value, str) and value:
                out[node][key] = beside(value, Path(path))
    return out


def merge(*layers: Mapping[str, Mapping[str, Any]]) -> dict[str, dict[str, Any]]:
    """Sections merged key by key, later layers winning (as ROS merges several
    ``--params-file``): the one rule for files and for overrides over them."""
    merged: dict[str, dict[str, Any]] = {}
    for layer in layers:
        for node, params in layer.items():
            merged.setdefault(node, {}).update(params)
    return merged


def load(paths: Sequence[str | Path], nodes: Iterable[str]) -> dict[str, dict[str, Any]]:
    """The flat sections ``nodes`` of ``paths``, each file read once and merged key by key
    (later files win)."""
    nodes = tuple(nodes)
    return merge({node: {} for node in nodes}, *(read_sections(p, nodes) for p in paths))


def param_rules(args: Sequence[str]) -> dict[str, Any]:
    """The ``-p name:=value`` rules of ``args``' ``--ros-args`` segments, values read as YAML
    as rcl reads them. rcl drops a rule whose type differs from a params file's value for the
    same key; the sim applies these after the files so that such a rule is checked, not lost."""
    rules: dict[str, Any] = {}
    inside = False
    for arg, following in zip(args, [*args[1:], None]):
        if arg == "--ros-args":
            inside = True
        elif arg == "--":
            inside = False
        elif inside and arg in ("-p", "--param") and following and ":=" in following:
            name, _, text = following.partition(":=")
            try:
                rules[name] = yaml.safe_load(text) if text.strip() else ""
            except yaml.YAMLError as err:
                raise ConfigError(f"{arg} {following}: the value is not valid YAML") from err
    return rules


def dump(sections: Mapping[str, Mapping[str, Any]]) -> str:
    """A params file of ``sections`` (node → flat parameters), as ``load`` reads it back."""
    doc = {node: {"ros__parameters": dict(params)} for node, params in sections.items()}
    return yaml.safe_dump(doc, sort_keys=False)
