"""Errors of pic4rl_metrics, one class per boundary.

Messages are built first with the offending value (``{x!r}``) and name the file, topic or
key, and what was expected; lower errors are translated with ``raise ... from err``.
"""

from __future__ import annotations


class MetricsError(Exception):
    """Base class of every error this package raises on purpose."""


class BagError(MetricsError):
    """A bag cannot be found, opened or decoded (corrupt, truncated, empty, unknown type)."""


class CorruptBagError(BagError):
    """A bag's stream holds two sources (two publishers of one sensor topic, header stamps
    jumping back and forth): refused, never scored."""


class TopicError(BagError):
    """A topic the metrics need is missing from a bag or has an unsupported type."""


class EpisodeError(MetricsError):
    """The data in a bag cannot make an episode (e.g. fewer than two poses)."""


class ConfigError(MetricsError):
    """A parameter (of any node or package: sim, env, trainer, metrics), a topic map, an episode
    fact, a robot, a world or a file they name is unknown or invalid. The one class for every
    pic4rl package: ``pic4rl_sim.errors`` and ``pic4rl_bridge.errors`` re-export it, and this
    package, the lowest room, imports no other."""


class OutputError(MetricsError):
    """An output (``--out``) cannot be written: a full disk, a parent that is a file, no
    permission."""
