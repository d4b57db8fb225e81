"""The metrics' input roles: one table of the topics they read besides the pose.

Each ``Role`` declares its default topic (the bag contract's name), the message types it
accepts, what is kept of each message, the ``Episode`` series it fills (if any) and the test
a metric needing it applies. ``TopicMap``'s role topics, ``ROLE_TYPES``, the reader's
extractors and series, ``Episode``'s optional series, ``INPUT_TESTS``, the topic-map keys and
the ``--<role>-topic`` options all derive from ``ROLE_TABLE``, so a new input is one entry here
(and its row in docs/metrics.md). The pose is no role: it has fallbacks and ``--pose-frames``
(``topics``).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from functools import cache
from typing import Any

from pic4rl_base.geometry import yaw_from_quaternion

from .. import contract
from .timebase import Samples, cmd_series, people_series, point_series, scan_series

ODOMETRY = "nav_msgs/msg/Odometry"
POSE_STAMPED = "geometry_msgs/msg/PoseStamped"
POSE_COV = "geometry_msgs/msg/PoseWithCovarianceStamped"
POSE_ARRAY = "geometry_msgs/msg/PoseArray"
TWIST = "geometry_msgs/msg/Twist"
TWIST_STAMPED = "geometry_msgs/msg/TwistStamped"
LASER_SCAN = "sensor_msgs/msg/LaserScan"
STRING = "std_msgs/msg/String"
TF_MESSAGE = "tf2_msgs/msg/TFMessage"

SUPPORTED_POSE_MSGS = frozenset({ODOMETRY, POSE_STAMPED, POSE_COV})
SUPPORTED_CMD_MSGS = frozenset({TWIST, TWIST_STAMPED})


def pose_row(msg: Any, msgtype: str) -> tuple[float, ...]:
    """(x, y, yaw, vx, vy, wz) of a pose message; NaN twist when the type has none."""
    pose = msg.pose if msgtype == POSE_STAMPED else msg.pose.pose
    p, q = pose.position, pose.orientation
    yaw = yaw_from_quaternion(q.x, q.y, q.z, q.w)
    if msgtype == ODOMETRY:
        t = msg.twist.twist
        return (p.x, p.y, yaw, t.linear.x, t.linear.y, t.angular.z)
    return (p.x, p.y, yaw, math.nan, math.nan, math.nan)


def _cmd_row(msg: Any, msgtype: str) -> tuple[float, float, float]:
    twist = msg.twist if msgtype == TWIST_STAMPED else msg
    return (twist.linear.x, twist.linear.y, twist.angular.z)


def _scan_row(msg: Any, _msgtype: str) -> tuple[Any, ...]:
    return (msg.ranges, msg.angle_min, msg.angle_increment, msg.range_min, msg.range_max)


def _people_row(msg: Any, _msgtype: str) -> tuple[tuple[float, float], ...]:
    return tuple((p.position.x, p.position.y) for p in msg.poses)


def _text(msg: Any, _msgtype: str) -> str:
    return msg.data


@dataclass(frozen=True)
class Role:
    """One input of the metrics read from one topic."""

    #: The ``TopicMap`` field, topic-map YAML key (unless ``yaml_key``) and ``needs`` name.
    name: str
    #: Default topic (``None``: off unless mapped).
    topic: str | None
    types: frozenset[str]
    #: (message, its type) -> the payload kept of each message.
    extract: Callable[[Any, str], Any]
    #: The ``Episode`` attribute it fills, and how: (samples, header-minus-receive offset ns,
    #: warnings) -> series or ``None``; a role without one feeds the facts (``reader``).
    series: str | None = None
    build: Callable[[Samples, int, list[str]], Any] | None = None
    #: The command-line option naming its topic, and the option's help.
    flag: str | None = None
    help: str = ""
    yaml_key: str | None = None
    #: When the default topic is absent (and the user named none): the bag's only topic of
    #: this type (a namespaced ``/robot1/scan``).
    only_of_type: str | None = None

    @property
    def key(self) -> str:
        """Its key in a topic-map YAML."""
        return self.yaml_key or self.name

    def present(self, derived: Any) -> bool:
        """The input test of a metric needing it (``derived.INPUT_TESTS``): the episode has a
        non-empty series."""
        series = derived.episode.inputs.get(self.series)
        return series is not None and len(series) > 0


ROLE_TABLE: tuple[Role, ...] = (
    Role("scan", contract.SCAN_TOPIC, frozenset({LASER_SCAN}), _scan_row,
         series="scan", build=scan_series, flag="--scan-topic", help="LaserScan topic",
         only_of_type=LASER_SCAN),
    Role("cmd_vel", contract.CMD_VEL_TOPIC, SUPPORTED_CMD_MSGS, _cmd_row,
         series="cmd", build=cmd_series, flag="--cmd-topic",
         help="Twist or TwistStamped topic"),
    Role("goal", contract.GOAL_TOPIC, SUPPORTED_POSE_MSGS, pose_row,
         flag="--goal-topic", help="goal PoseStamped topic"),
    Role("person", contract.PERSON_TOPIC, SUPPORTED_POSE_MSGS, pose_row,
         series="person", build=point_series, flag="--person-topic",
         help="tracked person's pose topic"),
    Role("people", contract.PEOPLE_TOPIC, frozenset({POSE_ARRAY}), _people_row,
         series="people", build=people_series, flag="--people-topic",
         help="PoseArray topic of the people around the robot"),
    Role("facts", contract.FACTS_TOPIC, frozenset({STRING}), _text, yaml_key="facts_topic"),
    Role("outcome", contract.OUTCOME_TOPIC, frozenset({STRING}), _text,
         yaml_key="outcome_topic"),
)
ROLE: dict[str, Role] = {role.name: role for role in ROLE_TABLE}
#: The roles that fill an ``Episode`` series, by that series' name.
SERIES_ROLES: dict[str, Role] = {role.series: role for role in ROLE_TABLE if role.series}
#: The message types each role accepts, in the order they are chosen.
ROLE_TYPES: dict[str, frozenset[str]] = {role.name: role.types for role in ROLE_TABLE}


@cache
def has_header(msgtype: str) -> bool:
    """Whether messages of ``msgtype`` begin with a ``std_msgs/Header`` (ROS 2 Jazzy's
    definitions; a type unknown there counts as headerless)."""
    definition = contract.typestore().fielddefs.get(msgtype)
    return bool(definition and definition[1] and definition[1][0][0] == "header")
