"""Decoders of episode-fact values, one per kind of value; each ``EpisodeFacts`` field names its
own (``contract``), so a new fact picks one here or adds one.

A decoder takes the raw value (a ``custom_data`` string, a JSON value of the facts topic, a
topic map's or the command line's value), the fact's key and the source to name, and returns
the typed value or raises ``ConfigError`` naming the source, the key and what was expected.
"""

from __future__ import annotations

import json
import math
from collections.abc import Callable, Mapping
from typing import Any

from pic4rl_base.errors import ConfigError
from pic4rl_base.geometry import Footprint, Pose2D
from pic4rl_base.goal import Goal

#: ``decode(raw, key, source) -> value``.
Decoder = Callable[[Any, str, str], Any]


def text(raw: Any, key: str, source: str) -> str:
    return str(raw)


def integer(raw: Any, key: str, source: str) -> int:
    try:
        return int(raw)
    except (ValueError, TypeError) as err:
        msg = f"{source}: {key}={raw!r} is not an integer"
        raise ConfigError(msg) from err


def _number(value: Any, key: str, source: str, *, positive: bool) -> float:
    try:
        number = float(value)
    except (ValueError, TypeError) as err:
        msg = f"{source}: {key}={value!r} is not a number"
        raise ConfigError(msg) from err
    if not math.isfinite(number) or number < 0 or (positive and number == 0):
        msg = f"{source}: {key}={value!r} must be a finite {'positive' if positive else 'non-negative'} number"
        raise ConfigError(msg)
    return number


def non_negative(raw: Any, key: str, source: str) -> float:
    return _number(raw, key, source, positive=False)


def positive(raw: Any, key: str, source: str) -> float:
    return _number(raw, key, source, positive=True)


def path_length(raw: Any, key: str, source: str) -> float:
    """A positive length (m), or ``inf``: no collision-free path (the straight line stands in)."""
    if str(raw).strip().lower() in ("inf", "infinity"):
        return math.inf
    return positive(raw, key, source)


def floats(value: Any, counts: tuple[int, ...], key: str, source: str) -> tuple[float, ...]:
    """Parse a JSON list (or a list) of finite numbers, as many as one of ``counts``."""
    try:
        items = json.loads(value) if isinstance(value, str) else value
        numbers = tuple(float(x) for x in items)
    except (ValueError, TypeError) as err:
        msg = f"{source}: {key}={value!r} is not a list of numbers"
        raise ConfigError(msg) from err
    if len(numbers) not in counts:
        msg = f"{source}: {key}={value!r} needs {' or '.join(map(str, counts))} numbers"
        raise ConfigError(msg)
    if not all(math.isfinite(x) for x in numbers):
        msg = f"{source}: {key}={value!r} holds a non-finite number"
        raise ConfigError(msg)
    return numbers


def pose(raw: Any, key: str, source: str) -> tuple[float, ...]:
    """``[x, y, yaw]`` (m, rad)."""
    return floats(raw, (3,), key, source)


def goal(raw: Any, key: str, source: str) -> Goal:
    """``[x, y]`` (m), or ``[x, y, yaw]`` (m, m, rad) with the goal's heading."""
    return Goal(*floats(raw, (2, 3), key, source))


def polyline(raw: Any, key: str, source: str) -> tuple[tuple[float, float], ...]:
    """``[[x, y], ...]`` (m), at least two points."""
    try:
        points = json.loads(raw) if isinstance(raw, str) else raw
        line = tuple((float(p[0]), float(p[1])) for p in points)
    except (ValueError, TypeError, IndexError, KeyError) as err:
        msg = f"{source}: {key}={raw!r} is not a list of [x, y] points"
        raise ConfigError(msg) from err
    if len(line) < 2:
        msg = f"{source}: {key} needs at least two points, got {len(line)}"
        raise ConfigError(msg)
    return line


#: The ``scan_mount`` fact's keys: a sensor's pose in the base frame, ``Pose2D``'s x, y, yaw.
MOUNT_KEYS = ("x_m", "y_m", "yaw_rad")


def mount(raw: Any, key: str, source: str) -> Pose2D:
    """``{"x_m": x, "y_m": y, "yaw_rad": yaw}`` (or its JSON, or ``[x, y, yaw]``)."""
    try:
        value = json.loads(raw) if isinstance(raw, str) else raw
        if isinstance(value, Mapping):
            unknown = set(value) - set(MOUNT_KEYS)
            if unknown:
                raise KeyError(sorted(unknown))
            value = [value.get(name, 0.0) for name in MOUNT_KEYS]
    except (ValueError, TypeError, KeyError) as err:
        msg = f"{source}: {key}={raw!r} is not {{'x_m': X, 'y_m': Y, 'yaw_rad': YAW}}"
        raise ConfigError(msg) from err
    return Pose2D(*floats(value, (3,), key, source))


def mount_json(value: Any) -> Any:
    """A mount as its fact is written: a ``Pose2D`` as ``{"x_m": x, "y_m": y, "yaw_rad": yaw}``
    (``MOUNT_KEYS``), any other value as it is."""
    return dict(zip(MOUNT_KEYS, value)) if isinstance(value, Pose2D) else value


def footprint(raw: Any, key: str, source: str) -> Footprint:
    """A ``Footprint`` in any form ``Footprint.parse`` reads."""
    return Footprint.parse(raw, source=source)
