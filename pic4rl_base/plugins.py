"""The reader of pic4rl's tables' entry-point groups: how a user's installed package adds a
piece to one of pic4rl's tables without editing a file of pic4rl. Its ``pyproject.toml`` names the
piece in the group of its table::

    [project.entry-points."pic4rl.baselines"]
    mine = "my_package.my_baseline:SPEC"

The groups read here: ``pic4rl.baselines`` (``BASELINE_TABLE``), ``pic4rl.tasks`` (``TASK_TABLE``)
and, for a sensor, ``pic4rl.sensors`` (``SENSOR_TABLE``), ``pic4rl.interfaces``
(``INTERFACE_TABLE``), ``pic4rl.readings`` (``READING_TABLE``) and ``pic4rl.observations``
(``OBSERVED_TABLE``); ``docs/extending.md`` shows each. A table reads its group once, when its
module is imported, so that everything derived from it (choices, ids, parameters, topics) sees the
new entry. (Metrics and policies, whose registries load on demand, read ``pic4rl.metrics`` and
``pic4rl.policies`` themselves.)
"""

from __future__ import annotations

import functools
from collections.abc import Callable, Collection
from importlib.metadata import EntryPoint, EntryPoints, entry_points
from typing import Any

from .errors import ConfigError


@functools.cache
def installed() -> EntryPoints:
    """Every installed package's entry points, read once a process (each table's group is a
    selection of them)."""
    return entry_points()


def group_points(group: str) -> list[EntryPoint]:
    """The entry points of ``group``, one per name (the first found on the path)."""
    found: dict[str, EntryPoint] = {}
    for point in installed().select(group=group):
        found.setdefault(point.name, point)
    return list(found.values())


def _attempt(action: Callable[[], Any], where: str, doing: str) -> Any:
    try:
        return action()
    except Exception as err:
        raise ConfigError(f"{where}: {doing} failed: {type(err).__name__}: {err}") from err


def load_group(group: str, kind: type, *, taken: Collection[str]) -> dict[str, Any]:
    """Every entry of ``group``, by its entry point's name: each a ``kind`` (or a function of
    no arguments that makes one when the table loads, so that a module whose entries go to
    several tables imports their classes only then) whose name none of ``taken`` (the shipped
    entries) has; ``ConfigError`` naming the entry point otherwise."""
    loaded: dict[str, Any] = {}
    for point in group_points(group):
        where = f"entry point {point.name} = {point.value} (group {group})"
        if point.name in taken:
            raise ConfigError(f"{where}: {point.name!r} is one of pic4rl's own; choose another "
                              "name")
        obj = _attempt(point.load, where, "loading it")
        if not isinstance(obj, kind) and callable(obj):
            obj = _attempt(obj, where, "calling it")
        if not isinstance(obj, kind):
            raise ConfigError(f"{where}: it names a {type(obj).__name__}; expected a "
                              f"{kind.__name__}")
        if getattr(obj, "name", point.name) != point.name:
            raise ConfigError(f"{where}: it names {kind.__name__} {obj.name!r}; expected the "
                              f"entry point's name {point.name!r}")
        loaded[point.name] = obj
    return loaded
