"""Topic map: which topics of a bag hold the pose, scan, command, goal and person.

Real-robot bags name things their own way (``/odometry/filtered``, ``/front/scan``); a topic
map, from a YAML file or the command line, says where to look. A YAML topic map may also carry
the episode facts a real-robot bag lacks::

    pose: [/odometry/filtered, /odom]   # first present wins
    scan: /front/scan
    cmd_vel: /cmd_vel
    goal: /move_base_simple/goal
    facts:
      footprint: {length_m: 0.99, width_m: 0.67}
      goal: [12.0, 3.5]
    metrics: [success, path_length_m, spl]   # columns to compute (default: all)
"""

from __future__ import annotations

import difflib
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import yaml

from . import contract
from .contract import EpisodeFacts, parse_facts
from .errors import ConfigError


def normalize_topic(name: str) -> str:
    """Return ``name`` as an absolute topic name (bags store ``/scan`` for ``scan``)."""
    name = name.strip()
    return name if name.startswith("/") else f"/{name}"


@dataclass(frozen=True)
class TopicMap:
    """Where each input of the metrics lives in a bag; ``None`` switches an input off."""

    pose: tuple[str, ...] = (contract.GROUND_TRUTH_TOPIC, contract.ODOM_TOPIC)
    scan: str | None = contract.SCAN_TOPIC
    cmd_vel: str | None = contract.CMD_VEL_TOPIC
    goal: str | None = contract.GOAL_TOPIC
    person: str | None = contract.PERSON_TOPIC
    facts: str | None = contract.FACTS_TOPIC
    outcome: str | None = contract.OUTCOME_TOPIC
    #: Metric columns to compute (``None``: every registered metric).
    metrics: tuple[str, ...] | None = None
    #: Roles the user named: a missing topic for one of these is an error, not a skip.
    explicit: frozenset[str] = frozenset()

    def __post_init__(self) -> None:
        if not self.pose:
            msg = "topic map: 'pose' needs at least one topic"
            raise ConfigError(msg)
        object.__setattr__(self, "pose", tuple(normalize_topic(t) for t in self.pose))
        for name in ("scan", "cmd_vel", "goal", "person", "facts", "outcome"):
            value = getattr(self, name)
            if value is not None:
                object.__setattr__(self, name, normalize_topic(value))

    def with_overrides(self, **overrides: str | Sequence[str] | None) -> TopicMap:
        """Return a copy with the given (non-``None``) entries replaced."""
        given: dict[str, object] = {k: v for k, v in overrides.items() if v is not None}
        if isinstance(given.get("pose"), str):
            given["pose"] = (given["pose"],)
        return replace(self, **given, explicit=self.explicit | frozenset(given))  # type: ignore[arg-type]


_KEYS = (
    "pose", "scan", "cmd_vel", "goal", "person", "facts_topic", "outcome_topic", "facts", "metrics",
)


def load_topic_map(path: Path | str) -> tuple[TopicMap, EpisodeFacts, frozenset[str]]:
    """Load a topic-map YAML; return the map and the facts (with the names it gave)."""
    path = Path(path)
    try:
        data = yaml.safe_load(path.read_text())
    except OSError as err:
        msg = f"topic map {str(path)!r}: cannot read: {err.strerror}"
        raise ConfigError(msg) from err
    except yaml.YAMLError as err:
        msg = f"topic map {str(path)!r}: not valid YAML: {err}"
        raise ConfigError(msg) from err
    return topic_map_from_dict(data or {}, source=f"topic map {str(path)!r}")


def topic_map_from_dict(
    data: Mapping[str, Any], *, source: str
) -> tuple[TopicMap, EpisodeFacts, frozenset[str]]:
    """Build a topic map from a mapping with the keys documented in this module."""
    if not isinstance(data, Mapping):
        msg = f"{source}: expected a mapping of keys {', '.join(_KEYS)}, got {type(data).__name__}"
        raise ConfigError(msg)
    for key in data:
        if key not in _KEYS:
            hint = difflib.get_close_matches(str(key), _KEYS, n=1)
            suggestion = f"; did you mean {hint[0]!r}?" if hint else ""
            msg = f"{source}: unknown key {key!r}{suggestion} (known: {', '.join(_KEYS)})"
            raise ConfigError(msg)
    kwargs: dict[str, Any] = {}
    for key, field_name in (("facts_topic", "facts"), ("outcome_topic", "outcome")):
        if key in data:
            kwargs[field_name] = data[key]
    for key in ("scan", "cmd_vel", "goal", "person"):
        if key in data:
            kwargs[key] = data[key]
    if "pose" in data:
        pose = data["pose"]
        kwargs["pose"] = (pose,) if isinstance(pose, str) else tuple(pose)
    for key, value in kwargs.items():
        values = value if isinstance(value, tuple) else (value,)
        if not all(v is None or isinstance(v, str) for v in values):
            msg = f"{source}: {key}={value!r} must be a topic name (or null to switch it off)"
            raise ConfigError(msg)
    facts, given = parse_facts(data.get("facts") or {}, source=f"{source}: facts")
    explicit = frozenset(kwargs)
    if data.get("metrics") is not None:
        names = data["metrics"]
        names = [names] if isinstance(names, str) else names
        if not isinstance(names, list) or not all(isinstance(n, str) for n in names):
            msg = f"{source}: metrics={data['metrics']!r} must be a list of metric names"
            raise ConfigError(msg)
        kwargs["metrics"] = tuple(names)
    return TopicMap(**kwargs, explicit=explicit), facts, given
