"""Errors of pic4rl_sim, one class per boundary; ``ConfigError`` is every package's one,
re-exported from ``pic4rl_metrics.errors``.

Messages name the key (or file) first, then the offending value (``{x!r}``) and what was
expected, so that a bad parameter file stops the node with one readable line.
"""

from __future__ import annotations

import difflib
from collections.abc import Iterable
from typing import Any

from pic4rl_metrics.errors import ConfigError

__all__ = ["ConfigError", "SimError", "WorldError", "require", "unknown_key"]


class SimError(Exception):
    """Base class of the errors this package raises on purpose, but ``ConfigError``: a bad
    parameter is every package's one ``pic4rl_metrics.errors.ConfigError`` (the lowest room),
    so catch ``(SimError, ConfigError)`` for both."""


class WorldError(SimError):
    """A world cannot be built (bad MJCF file, no free space for a start or goal)."""


def require(ok: bool, key: str, value: Any, expected: str) -> None:
    """Raise ``ConfigError`` naming ``key`` unless ``ok``."""
    if not ok:
        msg = f"{key}: {value!r} is invalid; expected {expected}"
        raise ConfigError(msg)


def unknown_key(key: str, known: Iterable[str], *, where: str) -> ConfigError:
    """An error for an unknown ``key`` in ``where`` (no prefix when empty: the caller adds
    one), with a "did you mean" when one is close."""
    known = sorted(known)
    close = difflib.get_close_matches(key, known, n=1)
    hint = f"; did you mean {close[0]!r}?" if close else f"; known keys: {', '.join(known)}"
    return ConfigError(f"{f'{where}: ' if where else ''}unknown key {key!r}{hint}")
