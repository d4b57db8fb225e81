"""Topic map: which topics of a bag hold the pose, scan, command, goal and person.

Real-robot bags name things their own way (``/odometry/filtered``, ``/front/scan``); a topic
map, from a YAML file or the command line, says where to look, and ``choose_topics`` picks them
in a bag. A YAML topic map may also carry the episode facts a real-robot bag lacks::

    pose: [/odometry/filtered, /odom]   # first present wins
    pose_frames: odom:base_link         # or poses from /tf and /tf_static: child in parent
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

from pic4rl_base.errors import ConfigError

from .. import contract
from ..contract import EpisodeFacts, parse_facts
from ..core.roles import ODOMETRY, ROLE, ROLE_TYPES, ROLE_TABLE, SUPPORTED_POSE_MSGS, TF_MESSAGE
from ..errors import TopicError


def normalize_topic(name: str) -> str:
    """Return ``name`` as an absolute topic name (bags store ``/scan`` for ``scan``)."""
    name = name.strip()
    return name if name.startswith("/") else f"/{name}"


_YAML_KEY = {role.name: role.key for role in ROLE_TABLE}
_DEFAULT_TOPICS = tuple((role.name, role.topic) for role in ROLE_TABLE)


@dataclass(frozen=True, init=False)
class TopicMap:
    """Where each input of the metrics lives in a bag; ``None`` switches an input off.

    Besides the pose, a topic per role of ``roles.ROLES``: an attribute (``topic_map.scan``)
    and a keyword (``TopicMap(scan="/front/scan")``, ``dataclasses.replace``)."""

    pose: tuple[str, ...] = (contract.GROUND_TRUTH_TOPIC, contract.ODOM_TOPIC)
    #: (role, topic) for every role, in ``ROLE_TABLE`` order.
    topics: tuple[tuple[str, str | None], ...] = _DEFAULT_TOPICS
    #: (parent, child): the pose is ``child``'s in ``parent`` from the ``TFMessage`` topics
    #: (``pose``, default ``/tf``, and its ``_static`` sibling) instead of a pose topic.
    pose_frames: tuple[str, str] | None = None
    #: Metric columns to compute (``None``: every registered metric).
    metrics: tuple[str, ...] | None = None
    #: Roles the user named: a missing topic for one of these is an error, not a skip.
    explicit: frozenset[str] = frozenset()

    def __init__(self, pose: Sequence[str] = (contract.GROUND_TRUTH_TOPIC, contract.ODOM_TOPIC),
                 topics: Sequence[tuple[str, str | None]] = _DEFAULT_TOPICS,
                 pose_frames: tuple[str, str] | str | None = None,
                 metrics: tuple[str, ...] | None = None,
                 explicit: frozenset[str] = frozenset(), **roles: str | None) -> None:
        unknown = sorted(set(roles) - set(ROLE))
        if unknown:
            msg = f"TopicMap() got unknown roles {unknown}; known: {sorted(ROLE)}"
            raise TypeError(msg)
        if not pose:
            msg = "topic map: 'pose' needs at least one topic"
            raise ConfigError(msg)
        if isinstance(pose_frames, str):
            pose_frames = parse_frames(pose_frames, "pose_frames")
        merged = dict(topics) | roles
        values = {
            "pose": tuple(normalize_topic(t) for t in pose),
            "topics": tuple((name, None if merged[name] is None else normalize_topic(merged[name]))
                            for name in ROLE),
            "pose_frames": pose_frames, "metrics": metrics, "explicit": explicit,
        }
        for name, value in values.items():
            object.__setattr__(self, name, value)

    def __getattr__(self, name: str) -> str | None:
        """A role's topic (``topic_map.scan``); only called for names that are no field."""
        if name in ROLE:
            return dict(self.__dict__["topics"])[name]
        msg = f"{type(self).__name__!r} object has no attribute {name!r}"
        raise AttributeError(msg)

    def with_overrides(self, **overrides: str | Sequence[str] | None) -> TopicMap:
        """Return a copy with the given (non-``None``) entries replaced."""
        given: dict[str, object] = {k: v for k, v in overrides.items() if v is not None}
        if isinstance(given.get("pose"), str):
            given["pose"] = (given["pose"],)
        return replace(self, **given, explicit=self.explicit | frozenset(given))  # type: ignore[arg-type]


def parse_frames(text: str, source: str) -> tuple[str, str]:
    """``PARENT:CHILD`` (``odom:base_link``) as two frame names, without leading ``/``."""
    parts = [p.strip().lstrip("/") for p in str(text).split(":")]
    if len(parts) != 2 or not all(parts):
        msg = f"{source} {text!r}: expected PARENT:CHILD frames, e.g. odom:base_link"
        raise ConfigError(msg)
    return parts[0], parts[1]


_KEYS = ("pose", "pose_frames", *_YAML_KEY.values(), "facts", "metrics")


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
    for role, key in _YAML_KEY.items():
        if key in data:
            kwargs[role] = data[key]
    if "pose" in data:
        pose = data["pose"]
        kwargs["pose"] = (pose,) if isinstance(pose, str) else tuple(pose)
    frames = data.get("pose_frames")
    if frames is not None:
        frames = parse_frames(frames, f"{source}: pose_frames")
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
    return TopicMap(**kwargs, pose_frames=frames, explicit=explicit), facts, given


#: Roles that, when their default topic is absent, take the bag's only topic of their type
#: (a namespaced ``/robot1/scan``), as the pose takes the only ``Odometry`` topic.
_ONLY_OF_TYPE = {role.name: role.only_of_type for role in ROLE_TABLE if role.only_of_type}
_FRAMES_HINT = "pass --pose-frames PARENT:CHILD (e.g. odom:base_link) to read poses from it"


@dataclass(frozen=True)
class Chosen:
    """The topics of one bag that fill the map's roles: topic -> role, and what was guessed."""

    pose: str
    wanted: dict[str, str]
    notes: tuple[str, ...]


def _only_of_type(available: Mapping[str, str], msgtype: str) -> list[str]:
    return sorted(t for t, ty in available.items() if ty == msgtype)


def _pose_topic(topic_map: TopicMap, available: Mapping[str, str], bag: str,
                notes: list[str]) -> str:
    """The first mapped pose topic in the bag, else its only Odometry topic; ``TopicError``
    naming the topics it has (and ``--pose-frames`` when it has ``/tf``)."""
    frames = topic_map.pose_frames is not None
    mapped = topic_map.pose if "pose" in topic_map.explicit or not frames else (contract.TF_TOPIC,)
    expected = {TF_MESSAGE} if frames else SUPPORTED_POSE_MSGS
    for topic in (t for t in mapped if t in available):
        got = available[topic]
        if got in expected:
            return topic
        if frames:
            hint = f"--pose-frames reads a {TF_MESSAGE} topic"
        elif got == TF_MESSAGE:
            hint = _FRAMES_HINT
        else:
            hint = f"expected one of {sorted(expected)}"
        msg = f"{bag}: pose topic {topic!r} has type {got!r}; {hint}"
        raise TopicError(msg)
    odometry = _only_of_type(available, ODOMETRY)
    if "pose" not in topic_map.explicit and not frames and len(odometry) == 1:
        notes.append(f"none of the pose topics {list(topic_map.pose)} is in the bag; "
                     f"using its only Odometry topic {odometry[0]!r}")
        return odometry[0]
    candidates = sorted(t for t, ty in available.items() if ty in expected)
    hint = f"; pose-like topics in it: {candidates} (pass --pose-topic)" if candidates else ""
    if not frames and contract.TF_TOPIC in available:
        hint += f"; it has {contract.TF_TOPIC}: {_FRAMES_HINT}"
    msg = (f"{bag}: none of the pose topics {list(mapped)} is in the bag{hint}; "
           f"it has {sorted(available) or 'no topics'}")
    raise TopicError(msg)


def _role_topic(role: str, topic: str | None, topic_map: TopicMap,
                available: Mapping[str, str], notes: list[str]) -> str | None:
    """The topic that fills ``role``: its mapped topic, else (not named by the user) the
    bag's only topic of its type, with a note; several such topics are named in a note."""
    if topic is None or topic in available or role in topic_map.explicit:
        return topic
    if role not in _ONLY_OF_TYPE:
        return topic
    found = _only_of_type(available, _ONLY_OF_TYPE[role])
    if len(found) == 1:
        notes.append(f"{role} topic {topic!r} is not in the bag; using its only "
                     f"{_ONLY_OF_TYPE[role].rsplit('/', 1)[-1]} topic {found[0]!r}")
        return found[0]
    if found:
        notes.append(f"{role} topic {topic!r} is not in the bag, which has {found}; "
                     f"{role} metrics are NaN (pass --{role}-topic)")
    return topic


def choose_topics(topic_map: TopicMap, available: Mapping[str, str], bag: str) -> Chosen:
    """Topic -> role for every mapped topic present in a bag whose topics and types are
    ``available``; a role the user named must be present. ``bag`` names it in errors."""
    notes: list[str] = []
    pose = _pose_topic(topic_map, available, bag, notes)
    static_tf = f"{pose}_static" if topic_map.pose_frames is not None else None
    needs_static = topic_map.scan is not None or static_tf is not None
    roles = {role: (getattr(topic_map, role), types) for role, types in ROLE_TYPES.items()}
    roles["tf_static"] = ((static_tf or contract.TF_STATIC_TOPIC) if needs_static else None,
                          frozenset({TF_MESSAGE}))
    wanted = {pose: "pose"}
    for role, (mapped, types) in roles.items():
        topic = _role_topic(role, mapped, topic_map, available, notes)
        if topic is None:
            continue
        if topic not in available:
            if role in topic_map.explicit:
                msg = f"{bag}: {role} topic {topic!r} is not in the bag; it has {sorted(available)}"
                raise TopicError(msg)
            continue
        if available[topic] not in types:
            msg = (f"{bag}: {role} topic {topic!r} has type {available[topic]!r}; "
                   f"expected one of {sorted(types)}")
            raise TopicError(msg)
        wanted.setdefault(topic, role)
    return Chosen(pose, wanted, tuple(notes))
