"""Errors of pic4rl_bridge, one class per boundary.

Messages name the key, file or topic first, then the offending value and what was expected.
A bad parameter is every package's one ``ConfigError`` (defined in ``pic4rl_metrics.errors``,
re-exported here and by ``pic4rl_sim.errors``): every node's parameters are checked by one
schema (``pic4rl_base.schema``), and the bag contract's by the metrics, so one class names them
all.
"""

from __future__ import annotations

from pic4rl_base.errors import ConfigError, require, unknown_key

__all__ = ["BridgeError", "ConfigError", "EpisodeRejected", "RecorderError", "SimConflict",
           "StaleSensor", "TransportError", "require", "unknown_key"]


class BridgeError(Exception):
    """Base class of every error this package raises on purpose."""


class TransportError(BridgeError):
    """The robot or simulator did not answer: a missing service, a silent topic, a bad message."""


class StaleSensor(TransportError):
    """A topic the task needs went silent mid-episode (``ros.max_sensor_age_s``): the robot was
    stopped, and the env aborts the episode with this message as its reason."""


class SimConflict(BridgeError):
    """Two simulator nodes answer on the same names (a forgotten sim, say): every message
    would come twice, or from the wrong world."""


class EpisodeRejected(BridgeError):
    """The simulator refused an episode's start or goal (e.g. not free); another may do."""


class RecorderError(BridgeError):
    """An episode bag cannot be written (its directory exists, the disk refuses)."""
