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
from typing import Any, NamedTuple

import numpy as np

from .contract import FACT_KEYS
from .errors import ConfigError


class Outcome(str, Enum):
    """How an episode ended. ``DIVERGED``: the physics diverged and the episode was cut (not a
    success, not a collision). ``UNKNOWN`` when nothing recorded it and it cannot be inferred."""

    GOAL = "goal"
    COLLISION = "collision"
    TIMEOUT = "timeout"
    DIVERGED = "diverged"
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

    def signed_distance(self, points: np.ndarray) -> np.ndarray:
        """Signed distance (m) of points (..., 2, base frame) from the footprint's boundary:
        positive outside, negative inside; the env's collision geometry
        (``pic4rl_bridge.tasks.collision.footprint_clearance``), re-implemented here because
        the metrics import no other pic4rl package."""
        p = np.asarray(points, dtype=float)
        return self.signed_distance_xy(p[..., 0], p[..., 1])

    def signed_distance_xy(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        """``signed_distance`` of the points with coordinates ``x`` and ``y`` (same shape)."""
        if self.radius_m is not None:
            return np.hypot(x, y) - self.radius_m
        qx = np.abs(x) - 0.5 * self.length_m  # type: ignore[operator]
        qy = np.abs(y) - 0.5 * self.width_m  # type: ignore[operator]
        outside = np.hypot(np.maximum(qx, 0.0), np.maximum(qy, 0.0))
        return outside + np.minimum(np.maximum(qx, qy), 0.0)


class Mount(NamedTuple):
    """A sensor's pose in the robot's base frame (m, rad)."""

    x_m: float = 0.0
    y_m: float = 0.0
    yaw_rad: float = 0.0


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
    #: Shortest collision-free start-goal path (m), known for simulated episodes.
    shortest_path_m: float | None = None
    #: Straight start-goal distance (m) as the recorder measured it.
    straight_line_m: float | None = None
    #: The LiDAR's pose in the base frame; ``None``: not recorded (see ``reader`` for tf).
    scan_mount: Mount | None = None
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


def _mount(raw: Any, source: str) -> Mount:
    """``{"x_m": x, "y_m": y, "yaw_rad": yaw}`` (or its JSON, or ``[x, y, yaw]``)."""
    try:
        value = json.loads(raw) if isinstance(raw, str) else raw
        if isinstance(value, Mapping):
            unknown = set(value) - set(Mount._fields)
            if unknown:
                raise KeyError(sorted(unknown))
            value = [value.get(name, 0.0) for name in Mount._fields]
    except (ValueError, TypeError, KeyError) as err:
        msg = f"{source}: scan_mount={raw!r} is not {{'x_m': X, 'y_m': Y, 'yaw_rad': YAW}}"
        raise ConfigError(msg) from err
    return Mount(*_floats(value, (3,), "scan_mount", source))


def _parse_value(key: str, raw: Any, source: str) -> Any:
    """The validated value of the known fact ``key``."""
    if key in ("agent", "task", "world", "robot", "run", "episode"):
        return str(raw)
    if key == "seed":
        try:
            return int(raw)
        except (ValueError, TypeError) as err:
            msg = f"{source}: seed={raw!r} is not an integer"
            raise ConfigError(msg) from err
    if key == "footprint":
        return Footprint.parse(raw, source=source)
    if key == "start":
        return _floats(raw, (3,), key, source)
    if key == "goal":
        # [x, y], or [x, y, yaw] from a pose: the yaw is not used.
        return _floats(raw, (2, 3), key, source)[:2]
    if key == "row_centerline":
        try:
            points = json.loads(raw) if isinstance(raw, str) else raw
            line = tuple((float(p[0]), float(p[1])) for p in points)
        except (ValueError, TypeError, IndexError, KeyError) as err:
            msg = f"{source}: row_centerline={raw!r} is not a list of [x, y] points"
            raise ConfigError(msg) from err
        if len(line) < 2:
            msg = f"{source}: row_centerline needs at least two points, got {len(line)}"
            raise ConfigError(msg)
        return line
    if key == "scan_mount":
        return _mount(raw, source)
    if key == "outcome":
        return Outcome.parse(str(raw), source=f"{source}: outcome")
    if key == "shortest_path_m" and str(raw).strip().lower() in ("inf", "infinity"):
        return math.inf  # no collision-free path: the straight line stands in
    positive = key in ("max_speed_mps", "shortest_path_m", "straight_line_m")
    return _number(raw, key, source, positive=positive)


def parse_facts(
    data: Mapping[str, Any], *, source: str, problems: list[str] | None = None
) -> tuple[EpisodeFacts, frozenset[str]]:
    """Parse a ``custom_data``-like mapping; return the facts and the names it gave.

    Unknown keys are kept in ``extra`` (a recorder may add its own); known keys are validated.
    A bad value raises ``ConfigError``, unless ``problems`` is given: then the key is left out
    and the message appended there (a bag's one bad fact must not cost its other metrics).
    """
    values: dict[str, Any] = {}
    extra: dict[str, str] = {}
    for key, raw in data.items():
        if raw is None or raw == "":
            continue
        if key not in FACT_KEYS:
            extra[key] = str(raw)
            continue
        try:
            values[key] = _parse_value(key, raw, source)
        except ConfigError as err:
            if problems is None:
                raise
            problems.append(f"{err}; fact ignored")
    if extra:
        values["extra"] = extra
    return EpisodeFacts(**values), frozenset(values)
