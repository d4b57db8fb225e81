"""The bag contract, as names and as code: what a recorder writes and the metrics read.

One rosbag2 per episode. Topics are recorded as on the wire (relative names resolve to
``/<name>``). Episode facts go to the metadata's ``custom_data`` (string values; structured
ones JSON-encoded) *and* to the ``episode/facts`` topic at the episode's start, so a bag whose
recorder was killed before writing ``metadata.yaml`` still carries them. The outcome is
published on ``episode/outcome`` when the episode ends, so its time is known.

Both writers (``pic4rl_bridge.recorder`` and ``synthetic``) encode through ``EpisodeFacts``
and ``encode_custom_data`` here, and the reader decodes through ``parse_facts``, so a new fact
is one field and one ``FACT_KEYS`` entry.
"""

from __future__ import annotations

import json
import math
from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from enum import Enum
from functools import cache
from typing import Any

import numpy as np
from rosbags.rosbag2 import StoragePlugin
from rosbags.typesys import Stores, get_typestore
from rosbags.typesys.store import Typestore

from .errors import ConfigError
from .facts import Footprint, Mount

#: Default topics, as recorded by pic4rl's recorder (the sim node's names).
GROUND_TRUTH_TOPIC = "/ground_truth"
ODOM_TOPIC = "/odom"
SCAN_TOPIC = "/scan"
CMD_VEL_TOPIC = "/cmd_vel"
GOAL_TOPIC = "/goal_pose"
PERSON_TOPIC = "/person/pose"
CLOCK_TOPIC = "/clock"

#: ``std_msgs/msg/String`` whose ``data`` is a JSON object with the keys of ``FACT_KEYS``.
FACTS_TOPIC = "/episode/facts"
#: ``std_msgs/msg/String``; ``data`` is a JSON object ``{"outcome": "goal"|"collision"|"timeout"|"diverged",
#: "stamp_ns": <int, on the pose topic's header time base>}`` or just the outcome word.
OUTCOME_TOPIC = "/episode/outcome"
#: ``tf2_msgs/msg/TFMessage``: a real bag's moving transforms, where ``--pose-frames`` reads
#: poses (``odom -> base_link``) when it has no pose topic.
TF_TOPIC = "/tf"
#: ``tf2_msgs/msg/TFMessage``: a real bag's static transforms, where the LiDAR's mount is read
#: when the facts carry no ``scan_mount``.
TF_STATIC_TOPIC = "/tf_static"

#: Keys of ``custom_data`` and of the facts JSON. Scalars are strings of numbers; ``start``
#: is ``[x, y, yaw]``, ``goal`` is ``[x, y]``, ``footprint`` is ``{"radius_m": r}`` or
#: ``{"length_m": l, "width_m": w}``, ``row_centerline`` is ``[[x, y], ...]`` (JSON).
#: ``shortest_path_m`` is the shortest collision-free start-goal path of a simulated episode and
#: ``straight_line_m`` the straight start-goal distance (m); ``scan_mount`` is the LiDAR's pose
#: in the base frame, ``{"x_m": x, "y_m": y, "yaw_rad": yaw}``; ``time_budget_s`` is the
#: episode's time limit (s). ``person_distance_m`` is the distance a person-monitoring robot
#: should keep to the person (m) and ``camera_fov_rad`` the horizontal field of view of the
#: camera that should see it (rad).
FACT_KEYS = (
    "agent",
    "task",
    "world",
    "robot",
    "run",
    "episode",
    "seed",
    "footprint",
    "start",
    "goal",
    "goal_tolerance_m",
    "collision_tolerance_m",
    "safety_margin_m",
    "max_speed_mps",
    "row_centerline",
    "shortest_path_m",
    "straight_line_m",
    "scan_mount",
    "time_budget_s",
    "person_distance_m",
    "camera_fov_rad",
    "outcome",
)


#: Storage plugins a bag may be written with (``.db3`` by default, ``.mcap`` as an option).
STORAGES = {"sqlite3": StoragePlugin.SQLITE3, "mcap": StoragePlugin.MCAP}
#: The ROS 2 distribution whose message definitions and bag format the bags hold.
ROS_DISTRO = "jazzy"


@cache
def typestore() -> Typestore:
    """The message types the writers serialize and describe in the bags (ROS 2 Jazzy's)."""
    return get_typestore(Stores.ROS2_JAZZY)


class Outcome(str, Enum):
    """How an episode ended. ``DIVERGED``: the physics diverged and the episode was cut (not a
    success, not a collision). ``ABORTED``: no outcome was recorded and the episode is shorter
    than its time budget (the sim or the tester died mid-episode): not the agent's timeout.
    ``UNKNOWN`` when nothing recorded it and it cannot be inferred."""

    GOAL = "goal"
    COLLISION = "collision"
    TIMEOUT = "timeout"
    DIVERGED = "diverged"
    ABORTED = "aborted"
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


#: The outcome words a writer records (``ABORTED`` and ``UNKNOWN`` are only the reader's
#: verdicts).
OUTCOMES = tuple(o.value for o in Outcome if o not in (Outcome.ABORTED, Outcome.UNKNOWN))
#: Outcomes that say nothing of the agent: out of the success rate's denominator.
UNJUDGED = (Outcome.ABORTED, Outcome.UNKNOWN)

#: What the metrics assume for a tolerance (m) the facts do not give.
TOLERANCE_DEFAULTS_M = {"goal_tolerance_m": 0.3, "collision_tolerance_m": 0.05,
                        "safety_margin_m": 0.3}


@dataclass(frozen=True)
class EpisodeFacts:
    """What is known of an episode besides its messages; ``None`` means not known.

    One field per ``FACT_KEYS`` entry, plus ``outcome_stamp_ns`` (read from the outcome topic,
    not a fact) and ``extra`` (facts of keys the contract does not know, kept as strings).
    """

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
    goal_tolerance_m: float | None = None
    collision_tolerance_m: float | None = None
    #: Closer than this (m, beyond the footprint) is unsafe; the env's ``warning_tolerance_m``.
    safety_margin_m: float | None = None
    max_speed_mps: float | None = None
    row_centerline: tuple[tuple[float, float], ...] | None = None
    #: Shortest collision-free start-goal path (m), known for simulated episodes.
    shortest_path_m: float | None = None
    #: Straight start-goal distance (m) as the recorder measured it.
    straight_line_m: float | None = None
    #: The LiDAR's pose in the base frame; ``None``: not recorded (see ``reader`` for tf).
    scan_mount: Mount | None = None
    #: The episode's time budget (s): an unrecorded end before it is ``ABORTED``, not a timeout.
    time_budget_s: float | None = None
    #: Person monitoring: the desired distance to the person (m).
    person_distance_m: float | None = None
    #: Person monitoring: the camera's horizontal field of view (rad), centred on the heading.
    camera_fov_rad: float | None = None
    outcome: Outcome | None = None
    #: Time of the outcome event (ns, on the pose topic's time base) when it was recorded.
    outcome_stamp_ns: int | None = None
    extra: Mapping[str, str] = field(default_factory=dict)

    def merged(self, other: EpisodeFacts, *, given: frozenset[str]) -> EpisodeFacts:
        """Return ``self`` with the fields named in ``given`` taken from ``other``."""
        return replace(self, **{name: getattr(other, name) for name in given})

    def with_defaults(self) -> EpisodeFacts:
        """These facts with ``TOLERANCE_DEFAULTS_M`` for the tolerances they do not give."""
        missing = {k: v for k, v in TOLERANCE_DEFAULTS_M.items() if getattr(self, k) is None}
        return replace(self, **missing) if missing else self

    def values(self) -> dict[str, Any]:
        """The known facts as plain JSON values, in ``FACT_KEYS`` order, then ``extra``."""
        known = {key: plain(getattr(self, key)) for key in FACT_KEYS}
        return {k: v for k, v in known.items() if v is not None} | dict(self.extra)

    def custom_data(self) -> dict[str, str]:
        """The bag's ``custom_data``."""
        return encode_custom_data(self.values())

    def facts_json(self) -> str:
        """The ``episode/facts`` message's ``data``."""
        return encode_facts_json(self.values())


def plain(value: Any) -> Any:
    """``value`` as plain JSON-able Python: enums as their value, numpy values, tuples and
    footprints as lists and objects."""
    if isinstance(value, Enum):
        return plain(value.value)
    if isinstance(value, Footprint):
        return {k: v for k, v in vars(value).items() if v is not None}
    if isinstance(value, Mount):
        return plain(value._asdict())
    if isinstance(value, np.generic | np.ndarray):
        return value.tolist()
    if isinstance(value, Mapping):
        return {str(k): plain(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [plain(v) for v in value]
    return value


def fact_text(value: Any) -> str:
    """A ``custom_data`` value: strings as they are, numbers as ``str``, the rest as JSON."""
    value = plain(value)
    if isinstance(value, str):
        return value
    return json.dumps(value) if isinstance(value, dict | list) else str(value)


def _ordered(values: Mapping[str, Any]) -> dict[str, Any]:
    """``values`` in ``FACT_KEYS`` order, then other keys as given; ``None`` (unknown) left out."""
    keys = [k for k in FACT_KEYS if k in values] + [k for k in values if k not in FACT_KEYS]
    return {k: values[k] for k in keys if values[k] is not None}


def encode_custom_data(values: Mapping[str, Any]) -> dict[str, str]:
    """Facts (typed or plain values, by key) as ``custom_data``: ``fact_text`` of each."""
    return {k: fact_text(v) for k, v in _ordered(values).items()}


def encode_facts_json(values: Mapping[str, Any]) -> str:
    """Facts (typed or plain values, by key) as the ``episode/facts`` JSON object."""
    return json.dumps(plain(_ordered(values)))


def outcome_event(outcome: Outcome | str, stamp_ns: int) -> str:
    """The ``episode/outcome`` message's ``data``: the outcome word and its time (ns)."""
    return json.dumps({"outcome": plain(outcome), "stamp_ns": int(stamp_ns)})


def parse_outcome_event(payload: str) -> tuple[Outcome, int | None]:
    """The outcome word and its stamp (ns, None when not given) of an ``episode/outcome``
    message (``outcome_event``'s JSON or a bare word); ``ConfigError`` if unreadable."""
    text, source = payload.strip(), "outcome topic"
    if text.startswith("{"):
        try:
            data = json.loads(text)
            stamp = data.get("stamp_ns")
            return Outcome.parse(data["outcome"], source=source), (
                None if stamp is None else int(stamp)
            )
        except (json.JSONDecodeError, KeyError, TypeError, ValueError, AttributeError) as err:
            msg = f"{source}: cannot read {text[:80]!r}: {type(err).__name__}: {err}"
            raise ConfigError(msg) from err
    return Outcome.parse(text, source=source), None


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
    positive = key in ("max_speed_mps", "shortest_path_m", "straight_line_m", "time_budget_s",
                       "camera_fov_rad")
    return _number(raw, key, source, positive=positive)


def parse_facts(
    data: Mapping[str, Any], *, source: str, problems: list[str] | None = None
) -> tuple[EpisodeFacts, frozenset[str]]:
    """Decode facts: ``custom_data`` strings, the facts topic's JSON values, a topic map's or the
    command line's values. Return the facts and the names it gave.

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
