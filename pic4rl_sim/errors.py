"""Errors of pic4rl_sim, one class per boundary; ``ConfigError`` and the helpers that word it
(``require``, ``unknown_key``) are every package's (``pic4rl_base.errors``), re-exported here.

Messages name the key (or file) first, then the offending value (``{x!r}``) and what was
expected, so that a bad parameter file stops the node with one readable line.
"""

from __future__ import annotations

from pic4rl_base.errors import ConfigError, Pic4rlError, require, unknown_key

__all__ = ["ConfigError", "SimError", "WorldError", "require", "unknown_key"]


class SimError(Pic4rlError):
    """Base class of the errors this package raises on purpose, but ``ConfigError``: a bad
    parameter is every package's one ``pic4rl_base.errors.ConfigError``, so catch
    ``(SimError, ConfigError)`` (or their base, ``Pic4rlError``) for both."""


class WorldError(SimError):
    """A world cannot be built (bad MJCF file, no free space for a start or goal)."""
