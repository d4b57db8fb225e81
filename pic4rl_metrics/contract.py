"""The bag contract, as names and as code: what a recorder writes and the metrics read.

One rosbag2 per episode. Topics are recorded as on the wire (relative names resolve to
``/<name>``). Episode facts go to the metadata's ``custom_data`` (string values; structured
ones JSON-encoded) *and* to the ``episode/facts`` topic at the episode's start, so a bag whose
recorder was killed before writing ``metadata.yaml`` still carries them. The outcome is
published on ``episode/outcome`` when the episode ends, so its time is known.

The one writer (``bagwriter``, for ``pic4rl_bridge.recorder`` and ``synthetic``) encodes
through ``EpisodeFacts`` and ``encode_custom_data`` here, and the reader decodes through
``parse_facts``. ``FACT_KEYS`` and the decoder derive from ``EpisodeFacts``' fields, each
naming its decoder (``fact_values``), so a new fact is one field.
"""

from __future__ import annotations

import json
from collections.abc import Mapping
from dataclasses import dataclass, field, fields, replace
from enum import Enum
from functools import cache
from typing import Any

import numpy as np
from rosbags.rosbag2 import StoragePlugin
from rosbags.typesys import Stores, get_typestore
from rosbags.typesys.store import Typestore

from pic4rl_base.errors import ConfigError
from pic4rl_base.geometry import Footprint, Pose2D
from pic4rl_base.goal import GOAL_TOLERANCE_M, Goal

from . import fact_values as decode

#: Default topics, as recorded by pic4rl's recorder (the sim node's names).
GROUND_TRUTH_TOPIC = "/ground_truth"
ODOM_TOPIC = "/odom"
SCAN_TOPIC = "/scan"
CMD_VEL_TOPIC = "/cmd_vel"
GOAL_TOPIC = "/goal_pose"
PERSON_TOPIC = "/person/pose"
#: ``geometry_msgs/msg/PoseArray`` of the people around the robot, in the pose topic's frame;
#: the array's index is the person (docs/metrics.md, "Social metrics").
PEOPLE_TOPIC = "/people"
CLOCK_TOPIC = "/clock"

#: ``std_msgs/msg/String`` whose ``data`` is a JSON object with the keys of ``FACT_KEYS``.
FACTS_TOPIC = "/episode/facts"
#: ``std_msgs/msg/String``; ``data`` is a JSON object
#: ``{"outcome": "goal"|"collision"|"timeout"|"diverged"|"aborted",
#: "stamp_ns": <int, on the pose topic's header time base>}`` or just the outcome word.
OUTCOME_TOPIC = "/episode/outcome"
#: ``tf2_msgs/msg/TFMessage``: the moving transforms (the sim's ``odom -> base_link``, as its
#: ``/odom``; a real robot's), where ``--pose-frames`` reads poses (``odom:base_link``).
TF_TOPIC = "/tf"
#: ``tf2_msgs/msg/TFMessage``: the static transforms (``base_link ->`` each sensor frame),
#: where the LiDAR's mount is read when the facts carry no ``scan_mount``.
TF_STATIC_TOPIC = "/tf_static"

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
    success, not a collision). ``ABORTED``: cut short for a reason not the agent's: the env
    recorded it (a sensor went silent; ``end_reason`` says which), or no outcome was recorded
    and the episode is shorter than its time budget (the sim or the tester died mid-episode).
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


class CollisionRule(str, Enum):
    """Which rule ended an episode as a ``collision``: ``SENSED``, the paper's (a sensed point
    closer to the footprint than ``collision_tolerance_m``, what a real robot can judge), or
    ``CONTACT``, a simulator's contact (the robot touched something, sensed or not)."""

    SENSED = "sensed"
    CONTACT = "contact"


#: The outcome words of an episode that ran its course (the agent's or the physics' end).
OUTCOMES = tuple(o.value for o in Outcome if o not in (Outcome.ABORTED, Outcome.UNKNOWN))
#: The outcome words a writer records: those, and ``aborted`` with an ``end_reason``
#: (``UNKNOWN`` is only the reader's verdict).
WRITTEN_OUTCOMES = (*OUTCOMES, Outcome.ABORTED.value)
#: Outcomes that say nothing of the agent: out of the success rate's denominator.
UNJUDGED = (Outcome.ABORTED, Outcome.UNKNOWN)

#: The world set of the BARN challenge's worlds (``barn:<n>``), where the BARN columns apply.
BARN_WORLDS = "barn"


def world_set(world: str | None) -> str | None:
    """The set a ``world`` fact belongs to: ``KIND`` of the env's ``KIND:VARIANT``
    (``barn:12`` → ``barn``, ``indoor:0`` → ``indoor``), else the name whole; None unknown."""
    if not world:
        return None
    kind, sep, variant = str(world).rpartition(":")
    return kind if sep and kind and variant.isdigit() else str(world)


def task_name(task: str | None) -> str | None:
    """The task of a ``task`` fact without its sensor (``goToPose/lidar`` → ``goToPose``):
    agents on one task are compared whatever they observe through; None unknown."""
    return str(task).split("/", 1)[0] or None if task else None


#: What the metrics assume for a tolerance (m) the facts do not give (the goal's: the env's
#: default, ``pic4rl_base.goal.GOAL_TOLERANCE_M``).
TOLERANCE_DEFAULTS_M = {"goal_tolerance_m": GOAL_TOLERANCE_M,
                        "collision_tolerance_m": 0.05, "safety_margin_m": 0.3}


def _outcome(raw: Any, key: str, source: str) -> Outcome:
    return Outcome.parse(str(raw), source=f"{source}: {key}")


def _collision_rule(raw: Any, key: str, source: str) -> CollisionRule:
    text = str(raw).strip().lower()
    rules = {r.value: r for r in CollisionRule}
    if text not in rules:
        raise ConfigError(f"{source}: {key}: {raw!r} is not a collision rule; expected one of "
                          f"{', '.join(rules)}")
    return rules[text]


def _fact(decoder: decode.Decoder, encoder: Any = None) -> Any:
    """An ``EpisodeFacts`` field that is a fact: unknown (``None``) by default, read by
    ``decoder`` and written by ``encoder`` (``plain`` when ``None``); its key in
    ``custom_data`` and the facts JSON is the field's name."""
    return field(default=None, metadata={"decode": decoder, "encode": encoder})


@dataclass(frozen=True)
class EpisodeFacts:
    """What is known of an episode besides its messages; ``None`` means not known.

    Every field made with ``_fact`` is a fact (``FACT_KEYS``, in field order), plus
    ``outcome_stamp_ns`` (read from the outcome topic, not a fact) and ``extra`` (facts of
    keys the contract does not know, kept as strings). Scalars are written as strings of
    numbers, the rest as JSON.
    """

    agent: str | None = _fact(decode.text)
    task: str | None = _fact(decode.text)
    world: str | None = _fact(decode.text)
    robot: str | None = _fact(decode.text)
    run: str | None = _fact(decode.text)
    episode: str | None = _fact(decode.text)
    seed: int | None = _fact(decode.integer)
    #: ``{"radius_m": r}`` or ``{"length_m": l, "width_m": w}``.
    footprint: Footprint | None = _fact(decode.footprint)
    #: ``[x, y, yaw]`` (m, rad).
    start: tuple[float, float, float] | None = _fact(decode.pose)
    #: ``[x, y]`` (m), or ``[x, y, yaw]`` (m, m, rad) with a heading.
    goal: Goal | None = _fact(decode.goal)
    goal_tolerance_m: float | None = _fact(decode.non_negative)
    collision_tolerance_m: float | None = _fact(decode.non_negative)
    #: Closer than this (m, beyond the footprint) is unsafe; the env's ``warning_tolerance_m``.
    safety_margin_m: float | None = _fact(decode.non_negative)
    max_speed_mps: float | None = _fact(decode.positive)
    #: ``[[x, y], ...]`` (m): the centre line of a vineyard episode's row.
    row_centerline: tuple[tuple[float, float], ...] | None = _fact(decode.polyline)
    #: Shortest collision-free start-goal path (m), known for simulated episodes (``inf``:
    #: none).
    shortest_path_m: float | None = _fact(decode.path_length)
    #: Straight start-goal distance (m) as the recorder measured it.
    straight_line_m: float | None = _fact(decode.positive)
    #: A benchmark world's reference path (m), whose length sets the BARN score's optimal
    #: time (BARN's worlds carry one); ``None`` elsewhere.
    reference_path_m: float | None = _fact(decode.positive)
    #: The LiDAR's pose in the base frame, ``{"x_m": x, "y_m": y, "yaw_rad": yaw}``;
    #: ``None``: not recorded (see ``reader`` for tf).
    scan_mount: Pose2D | None = _fact(decode.mount, decode.mount_json)
    #: The episode's time budget (s): an unrecorded end before it is ``ABORTED``, not a timeout.
    time_budget_s: float | None = _fact(decode.positive)
    #: Person monitoring: the desired distance to the person (m).
    person_distance_m: float | None = _fact(decode.non_negative)
    #: Person monitoring: the camera's horizontal field of view (rad), centred on the heading.
    camera_fov_rad: float | None = _fact(decode.positive)
    #: Exploration: the world's free floor area (m²), which coverage is the share of.
    free_area_m2: float | None = _fact(decode.positive)
    #: Crowds: the radius of each person's body disc (m), for the social metrics' distances.
    person_radius_m: float | None = _fact(decode.positive)
    outcome: Outcome | None = _fact(_outcome)
    #: Why the env cut the episode short (an ``aborted`` outcome), in words.
    end_reason: str | None = _fact(decode.text)
    #: Which rule ended a ``collision`` episode (``CollisionRule``); ``None`` otherwise.
    collision_rule: CollisionRule | None = _fact(_collision_rule)
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
        known = {key: plain(_ENCODERS[key](getattr(self, key))) for key in FACT_KEYS}
        return {k: v for k, v in known.items() if v is not None} | dict(self.extra)

    def custom_data(self) -> dict[str, str]:
        """The bag's ``custom_data``."""
        return encode_custom_data(self.values())

    def facts_json(self) -> str:
        """The ``episode/facts`` message's ``data``."""
        return encode_facts_json(self.values())


#: Keys of ``custom_data`` and of the facts JSON: the facts of ``EpisodeFacts``, in field order.
FACT_KEYS: tuple[str, ...] = tuple(f.name for f in fields(EpisodeFacts) if "decode" in f.metadata)
_DECODERS: dict[str, decode.Decoder] = {
    f.name: f.metadata["decode"] for f in fields(EpisodeFacts) if "decode" in f.metadata}


def plain(value: Any) -> Any:
    """``value`` as plain JSON-able Python: enums as their value, numpy values, tuples and
    footprints as lists and objects."""
    if isinstance(value, Enum):
        return plain(value.value)
    if isinstance(value, Footprint):
        return {k: v for k, v in vars(value).items() if v is not None}
    if isinstance(value, Goal):
        return value.as_list()
    if isinstance(value, np.generic | np.ndarray):
        return value.tolist()
    if isinstance(value, Mapping):
        return {str(k): plain(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [plain(v) for v in value]
    return value


#: How each fact is written: its field's encoder, else ``plain``.
_ENCODERS: dict[str, Any] = {
    f.name: f.metadata["encode"] or plain for f in fields(EpisodeFacts) if "decode" in f.metadata}


def fact_text(value: Any) -> str:
    """A ``custom_data`` value: strings as they are, numbers as ``str``, the rest as JSON."""
    value = plain(value)
    if isinstance(value, str):
        return value
    return json.dumps(value) if isinstance(value, dict | list) else str(value)


def _ordered(values: Mapping[str, Any]) -> dict[str, Any]:
    """``values`` in ``FACT_KEYS`` order, each as its fact is written, then other keys as
    given; ``None`` (unknown) left out."""
    keys = [k for k in FACT_KEYS if k in values] + [k for k in values if k not in FACT_KEYS]
    return {k: _ENCODERS.get(k, plain)(values[k]) for k in keys if values[k] is not None}


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
            values[key] = _DECODERS[key](raw, key, source)
        except ConfigError as err:
            if problems is None:
                raise
            problems.append(f"{err}; fact ignored")
    if extra:
        values["extra"] = extra
    return EpisodeFacts(**values), frozenset(values)
