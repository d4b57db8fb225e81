"""``pic4rl_sim.interfaces`` in rclpy's terms: type names to message and service classes and
back, QoS settings to profiles and back."""

from __future__ import annotations

import importlib
from typing import Any

from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy

from ..interfaces import Interface, QosKind, QosSettings


def profile(settings: QosSettings) -> QoSProfile:
    """The rclpy profile of ``settings`` (keep last ``depth``)."""
    return QoSProfile(
        depth=settings.depth,
        reliability=(ReliabilityPolicy.RELIABLE if settings.reliable
                     else ReliabilityPolicy.BEST_EFFORT),
        durability=(DurabilityPolicy.TRANSIENT_LOCAL if settings.transient_local
                    else DurabilityPolicy.VOLATILE))


def settings_of(qos: QoSProfile) -> QosSettings:
    """``profile``'s inverse: what a publisher's profile (the ROS graph's) offers."""
    return QosSettings(reliable=qos.reliability == ReliabilityPolicy.RELIABLE,
                       transient_local=qos.durability == DurabilityPolicy.TRANSIENT_LOCAL,
                       depth=int(qos.depth))


#: The profile the node offers each QoS kind with (``SENSOR_DATA``: rclpy's
#: ``qos_profile_sensor_data``).
PROFILES = {kind: profile(kind.value) for kind in QosKind}


def ros_type(type_name: str) -> Any:
    """The rclpy class of a ROS type name (``sensor_msgs/msg/LaserScan``)."""
    package, kind, name = type_name.split("/")
    return getattr(importlib.import_module(f"{package}.{kind}"), name)


def type_name(kind: type) -> str:
    """``ros_type``'s inverse for a message class: ``LaserScan`` → ``sensor_msgs/msg/LaserScan``."""
    return f"{kind.__module__.split('.')[0]}/msg/{kind.__name__}"


def starts_with_stamp(kind: type) -> bool:
    """Whether a message class's CDR starts with a ``builtin_interfaces/Time``: its first
    field is a header (whose first field is the stamp) or a time (``rosgraph_msgs/Clock``)."""
    fields = kind.get_fields_and_field_types()  # type: ignore[attr-defined]
    return next(iter(fields.values()), "") in ("std_msgs/Header", "builtin_interfaces/Time")


def qos_profile(interface: Interface) -> QoSProfile:
    """The profile the node offers ``interface`` with (a topic's: its QoS kind is set)."""
    assert interface.qos is not None, f"{interface.name} is a service"
    return PROFILES[interface.qos]
