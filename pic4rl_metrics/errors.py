"""Errors of pic4rl_metrics, one class per boundary; ``ConfigError`` and ``OutputError`` are
every package's (``pic4rl_base.errors``), re-exported here.

Messages are built first with the offending value (``{x!r}``) and name the file, topic or
key, and what was expected; lower errors are translated with ``raise ... from err``.
"""

from __future__ import annotations

from pic4rl_base.errors import ConfigError, OutputError, Pic4rlError

__all__ = ["BagError", "ConfigError", "CorruptBagError", "EpisodeError", "MetricsError",
           "OutputError", "TopicError"]


class MetricsError(Pic4rlError):
    """Base class of the bag and episode errors this package raises on purpose."""


class BagError(MetricsError):
    """A bag cannot be found, opened or decoded (corrupt, truncated, empty, unknown type)."""


class CorruptBagError(BagError):
    """A bag's stream holds two sources (two publishers of one sensor topic, header stamps
    jumping back and forth): refused, never scored."""


class TopicError(BagError):
    """A topic the metrics need is missing from a bag or has an unsupported type."""


class EpisodeError(MetricsError):
    """The data in a bag cannot make an episode (e.g. fewer than two poses)."""
