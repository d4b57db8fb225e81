"""The errors every package shares: the one ``ConfigError`` and the helpers that word it.

Messages name the key (or file) first, then the offending value (``{x!r}``) and what was
expected, so that a bad parameter file stops a command with one readable line. Each package's
own classes (``MetricsError``, ``SimError``, ``BridgeError``) live in its own ``errors``.
"""

from __future__ import annotations

import difflib
from collections.abc import Iterable
from typing import Any


class Pic4rlError(Exception):
    """Base class of the errors a pic4rl package raises on purpose for bad input: what a
    console script prints as one line (``pic4rl_base.entry``)."""


class ConfigError(Pic4rlError):
    """A parameter (of any node or package: sim, env, trainer, metrics), a topic map, an episode
    fact, a robot, a world or a file they name is unknown or invalid. The one class for every
    pic4rl package; each package's ``errors`` re-exports it."""


class OutputError(Pic4rlError):
    """An output (``--out``) cannot be written: a full disk, a parent that is a file, no
    permission."""


def require(ok: bool, key: str, value: Any, expected: str) -> None:
    """Raise ``ConfigError`` naming ``key`` unless ``ok``."""
    if not ok:
        msg = f"{key}: {value!r} is invalid; expected {expected}"
        raise ConfigError(msg)


#: Keys given a new name, old → new: refused with the new name wherever the new one is a key.
#: The env's LiDAR and depth observation keys, renamed apart from the sim's sensor keys of the
#: same spelling (the sim's ``lidar.beams`` are rays, the env's sectors; the sim's
#: ``depth.max_depth_m`` is the camera's range, the env's the observation's clip).
RENAMED_KEYS = {"lidar.beams": "lidar.sectors", "lidar.max_range_m": "lidar.clip_m",
                "depth.max_depth_m": "depth.clip_m", "depth.width": "depth.obs_width",
                "depth.height": "depth.obs_height"}
#: Values given a new name, (key, old) → new: refused with the new name (``require_choice``).
#: Imitation's person-following expert is the ``dwa_heading`` baseline, by its name.
RENAMED_VALUES = {("imitation.expert", "heading"): "dwa_heading"}


def require_choice(key: str, value: Any, choices: Iterable[str]) -> None:
    """Raise ``ConfigError`` naming ``key`` unless ``value`` is one of ``choices``; a value
    that was renamed (``RENAMED_VALUES``) is told its new name."""
    choices = tuple(choices)
    new = RENAMED_VALUES.get((key, value)) if isinstance(value, str) else None
    require(value in choices, key, value,
            f"its new name {new!r}" if new in choices else f"one of {', '.join(choices)}")


def unknown_key(key: str, known: Iterable[str], *, where: str) -> ConfigError:
    """An error for an unknown ``key`` in ``where`` (no prefix when empty: the caller adds
    one): its new name when it was renamed (``RENAMED_KEYS``), else a "did you mean" when one
    is close."""
    known = sorted(known)
    prefix = f"{where}: " if where else ""
    if RENAMED_KEYS.get(key) in known:
        return ConfigError(f"{prefix}key {key!r} is renamed {RENAMED_KEYS[key]!r}")
    close = difflib.get_close_matches(key, known, n=1)
    hint = f"; did you mean {close[0]!r}?" if close else f"; known keys: {', '.join(known)}"
    return ConfigError(f"{prefix}unknown key {key!r}{hint}")
