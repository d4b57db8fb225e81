"""Episode facts: who ran, where the goal was, how big the robot is, how it ended.

Facts come from a bag's ``custom_data``, its ``episode/facts`` topic, a goal topic, or the
command line (in rising precedence). Everything is parsed and validated here, so that a bad
value fails with a message naming its key and source.
"""

from __future__ import annotations

import json
import math
from collections.abc import Mapping
from dataclasses import dataclass, field, fields, replace
from enum import Enum
from typing import Any

import numpy as np

from .contract import FACT_KEYS
from .errors import ConfigError


class Outcome(str, Enum):
    """How an episode ended. ``UNKNOWN`` when nothing recorded it and it cannot be inferred."""

    GOAL = "goal"
    COLLISION = "collision"
    TIMEOUT = "timeout"
    UNKNOWN = "unknown"

    @classmethod
    def parse(cls, value: str, *, source: str = "outcome") -> Outcome:
        """Parse ``value`` (case-insensitive); raise ``ConfigError`` naming ``source``."""
        try:
            return cls(str(value).strip().lower())
        except ValueError as err:
            choices = ", ".join(o.value for o in cls)
            msg = f"{source}: {value!r} is not an outcome; expected one of {choices}"
            raise ConfigError(msg) from err


@dataclass(frozen=True)
class Footprint:
    """Robot footprint centred on the base frame: a circle or an axis-aligned rectangle (m)."""

    radius_m: float | None = None
    length_m: float | None = None
    width_m: float | None = None

    def __post_init__(self) -> None:
        is_circle = self.radius_m is not None
        is_rect = self.length_m is not None or self.width_m is not None
        if is_circle == is_rect:
            msg = f"footprint: give either radius_m or length_m and width_m, got {self!r}"
            raise ConfigError(msg)
        for name in ("radius_m", "length_m", "width_m"):
            value = getattr(self, name)
            if is_rect and name != "radius_m" and value is None:
                msg = f"footprint: rectangle needs {name}, got {self!r}"
                raise ConfigError(msg)
            if value is not None and not (math.isfinite(value) and value > 0):
                msg = f"footprint.{name}: {value!r} must be a positive number of metres"
                raise ConfigError(msg)

    @classmethod
    def parse(cls, value: Any, *, source: str = "facts") -> Footprint:
        """Parse ``{"radius_m": r}``, ``{"length_m": l, "width_m": w}``, their JSON, a number
        (a radius), ``"circle:R"`` or ``"rect:LxW"``."""
        if isinstance(value, Footprint):
            return value
        try:
            if isinstance(value, (int, float)):
                return cls(radius_m=float(value))
            if isinstance(value, str):
                text = value.strip()
                if text.startswith("{"):
                    return cls.parse(json.loads(text), source=source)
                kind, _, size = text.partition(":")
                if kind == "circle":
                    return cls(radius_m=float(size))
                if kind in ("rect", "rectangle"):
                    length, width = size.lower().split("x")
                    return cls(length_m=float(length), width_m=float(width))
                return cls(radius_m=float(text))
            if isinstance(value, Mapping):
                unknown = set(value) - {f.name for f in fields(cls)}
                if unknown:
                    msg = f"{source}: unknown keys {sorted(unknown)!r}"
                    raise ConfigError(msg)
                return cls(**{k: float(v) for k, v in value.items()})
        except ConfigError as err:
            raise ConfigError(f"{source}: {err}") from err
        except (ValueError, TypeError) as err:
            cause: Exception | None = err
        else:
            cause = None
        msg = (
            f"{source}: cannot read footprint {value!r}; expected a radius in metres, "
            "'circle:R', 'rect:LxW' or {'length_m': L, 'width_m': W}"
        )
        raise ConfigError(msg) from cause

    def boundary_distance(self, bearing_rad: np.ndarray) -> np.ndarray:
        """Distance (m) from the footprint's centre to its edge along each bearing (rad)."""
        bearing = np.asarray(bearing_rad, dtype=float)
        if self.radius_m is not None:
            return np.full(bearing.shape, self.radius_m)
        half_l = 0.5 * self.length_m  # type: ignore[operator]
        half_w = 0.5 * self.width_m  # type: ignore[operator]
        with np.errstate(divide="ignore", over="ignore"):
            along = half_l / np.abs(np.cos(bearing))
            across = half_w / np.abs(np.sin(bearing))
        return np.minimum(along, across)


@dataclass(frozen=True)
class EpisodeFacts:
    """What is known of an episode besides its messages. ``None`` means not known."""

    agent: str | None = None
    task: str | None = None
    world: str | None = None
    robot: str | None = None
    run: str | None = None
    episode: str | None = None
    seed: int | None = None
    footprint: Footprint | None = None
    start: tuple[float, float, float] | None = None
    goal: tuple[float, float] | None = None
    goal_tolerance_m: float = 0.3
    collision_tolerance_m: float = 0.05
    safety_margin_m: float = 0.3
    max_speed_mps: float | None = None
    row_centerline: tuple[tuple[float, float], ...] | None = None
    outcome: Outcome | None = None
    #: Time of the outcome event (ns, on the pose topic's time base) when it was recorded.
    outcome_stamp_ns: int | None = None
    extra: Mapping[str, str] = field(default_factory=dict)

    def merged(self, other: EpisodeFacts, *, given: frozenset[str]) -> EpisodeFacts:
        """Return ``self`` with the fields named in ``given`` taken from ``other``."""
        return replace(self, **{name: getattr(other, name) for name in given})


def _floats(value: Any, counts: tuple[int, ...], key: str, source: str) -> tuple[float, ...]:
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


def _number(value: Any, key: str, source: str, *, positive: bool = False) -> float:
    try:
        number = float(value)
    except (ValueError, TypeError) as err:
        msg = f"{source}: {key}={value!r} is not a number"
        raise ConfigError(msg) from err
    if not math.isfinite(number) or number < 0 or (positive and number == 0):
        msg = f"{source}: {key}={value!r} must be a finite {'positive' if positive else 'non-negative'} number"
        raise ConfigError(msg)
    return number


def parse_facts(data: Mapping[str, Any], *, source: str) -> tuple[EpisodeFacts, frozenset[str]]:
    """Parse a ``custom_data``-like mapping; return the facts and the names it gave.

    Unknown keys are kept in ``extra`` (a recorder may add its own); known keys are validated.
    """
    values: dict[str, Any] = {}
    extra: dict[str, str] = {}
    for key, raw in data.items():
        if raw is None or raw == "":
            continue
        if key not in FACT_KEYS:
            extra[key] = str(raw)
            continue
        if key in ("agent", "task", "world", "robot", "run", "episode"):
            values[key] = str(raw)
        elif key == "seed":
            try:
                values[key] = int(raw)
            except (ValueError, TypeError) as err:
                msg = f"{source}: seed={raw!r} is not an integer"
                raise ConfigError(msg) from err
        elif key == "footprint":
            values[key] = Footprint.parse(raw, source=source)
        elif key == "start":
            values[key] = _floats(raw, (3,), key, source)
        elif key == "goal":
            # [x, y], or [x, y, yaw] from a pose: the yaw is not used.
            values[key] = _floats(raw, (2, 3), key, source)[:2]
        elif key == "row_centerline":
            try:
                points = json.loads(raw) if isinstance(raw, str) else raw
                line = tuple((float(p[0]), float(p[1])) for p in points)
            except (ValueError, TypeError, IndexError, KeyError) as err:
                msg = f"{source}: row_centerline={raw!r} is not a list of [x, y] points"
                raise ConfigError(msg) from err
            if len(line) < 2:
                msg = f"{source}: row_centerline needs at least two points, got {len(line)}"
                raise ConfigError(msg)
            values[key] = line
        elif key == "outcome":
            values[key] = Outcome.parse(str(raw), source=f"{source}: outcome")
        elif key == "max_speed_mps":
            values[key] = _number(raw, key, source, positive=True)
        else:
            values[key] = _number(raw, key, source)
    if extra:
        values["extra"] = extra
    return EpisodeFacts(**values), frozenset(values)
