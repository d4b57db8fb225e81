"""``pic4rl_sim.interfaces`` in rclpy's terms: type names to message and service classes, QoS
kinds to profiles."""

from __future__ import annotations

import importlib
from typing import Any

from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy, qos_profile_sensor_data

from ..interfaces import Interface, QosKind

PROFILES = {
    QosKind.SENSOR_DATA: qos_profile_sensor_data,
    QosKind.RELIABLE: QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE),
    QosKind.LATCHED: QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE,
                                durability=DurabilityPolicy.TRANSIENT_LOCAL),
}


def ros_type(type_name: str) -> Any:
    """The rclpy class of a ROS type name (``sensor_msgs/msg/LaserScan``)."""
    package, kind, name = type_name.split("/")
    return getattr(importlib.import_module(f"{package}.{kind}"), name)


def qos_profile(interface: Interface) -> QoSProfile:
    """The profile the node offers ``interface`` with (a topic's: its QoS kind is set)."""
    assert interface.qos is not None, f"{interface.name} is a service"
    return PROFILES[interface.qos]
