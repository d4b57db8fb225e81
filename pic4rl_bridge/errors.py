"""Errors of pic4rl_bridge, one class per boundary.

Messages name the key, file or topic first, then the offending value and what was expected.
"""

from __future__ import annotations

import difflib
from collections.abc import Iterable
from typing import Any


class BridgeError(Exception):
    """Base class of every error this package raises on purpose."""


class ConfigError(BridgeError):
    """An env parameter, a goals-and-poses file or a task setting is unknown or invalid."""


class TransportError(BridgeError):
    """The robot or simulator did not answer: a missing service, a silent topic, a bad message."""


class EpisodeRejected(BridgeError):
    """The simulator refused an episode's start or goal (e.g. not free); another may do."""


class RecorderError(BridgeError):
    """An episode bag cannot be written (its directory exists, the disk refuses)."""


def require(ok: bool, key: str, value: Any, expected: str) -> None:
    """Raise ``ConfigError`` naming ``key`` unless ``ok``."""
    if not ok:
        msg = f"{key}: {value!r} is invalid; expected {expected}"
        raise ConfigError(msg)


def unknown_key(key: str, known: Iterable[str], *, where: str) -> ConfigError:
    """An error for an unknown ``key`` in ``where``, with a "did you mean" when one is close."""
    known = sorted(known)
    close = difflib.get_close_matches(key, known, n=1)
    hint = f"; did you mean {close[0]!r}?" if close else f"; known keys: {', '.join(known)}"
    return ConfigError(f"{where}: unknown key {key!r}{hint}")
