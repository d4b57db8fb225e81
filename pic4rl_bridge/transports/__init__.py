"""Transports: how the env reaches a robot, simulated or real, and what comes back.

``transport`` (the ``Transport`` interface every transport implements, ``EpisodeRequest``,
``RawMessage``), ``inprocess`` (the engine in this process; loads MuJoCo), ``ros_transport``
(ROS 2 topics, with ``ros_topics``: its subscriptions and their QoS, and ``ros_sim``: what it asks
of a sim node; loads rclpy). Both make ``SensorFrame``s through the frame's sensor table and
its decoders, which every room below reads too: ``pic4rl_bridge.readings``. Names are
imported on first use, so importing one light module loads no MuJoCo or rclpy.
"""

from __future__ import annotations

from pic4rl_base.lazy import lazy_exports

_EXPORTS = {
    "Transport": "transport", "EpisodeRequest": "transport", "RawMessage": "transport",
    "InProcessTransport": "inprocess",
    "RosTransport": "ros_transport",
}
__all__ = sorted(_EXPORTS)
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
