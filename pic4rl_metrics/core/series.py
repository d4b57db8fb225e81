"""Decoded time series of one episode, as plain numpy arrays: the ``Episode``.

Its series besides the pose are those the input roles fill (``roles.SERIES_ROLES``): each is an
attribute (``episode.scan``), ``None`` when the bag has none, and a keyword of ``Episode`` and
of ``dataclasses.replace``. The series' kinds live in ``series_kinds``.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from ..contract import EpisodeFacts
from .roles import SERIES_ROLES
from .series_kinds import CmdSeries, PointSeries, PoseSeries, ScanSeries

__all__ = ["CmdSeries", "Episode", "PointSeries", "PoseSeries", "ScanSeries"]


@dataclass(frozen=True, init=False)
class Episode:
    """Everything the metrics need from one bag."""

    bag: Path
    facts: EpisodeFacts
    pose: PoseSeries
    pose_topic: str
    #: The roles' series by name (``scan``, ``cmd``, ``person``), ``None`` for those it lacks.
    inputs: Mapping[str, Any] = field(default_factory=dict)
    #: Things noticed while reading that do not stop the metrics (e.g. reordered stamps).
    warnings: tuple[str, ...] = field(default_factory=tuple)

    def __init__(self, bag: Path, facts: EpisodeFacts, pose: PoseSeries, pose_topic: str,
                 inputs: Mapping[str, Any] | None = None, warnings: tuple[str, ...] = (),
                 **series: Any) -> None:
        unknown = sorted(set(series) - set(SERIES_ROLES))
        if unknown:
            msg = f"Episode() got unknown series {unknown}; known: {sorted(SERIES_ROLES)}"
            raise TypeError(msg)
        merged = dict.fromkeys(SERIES_ROLES) | dict(inputs or {}) | series
        for name, value in (("bag", bag), ("facts", facts), ("pose", pose),
                            ("pose_topic", pose_topic), ("inputs", merged),
                            ("warnings", tuple(warnings))):
            object.__setattr__(self, name, value)

    def __getattr__(self, name: str) -> Any:
        """A role's series (``episode.scan``); only called for names that are no field."""
        if name in SERIES_ROLES:
            return self.__dict__["inputs"][name]
        msg = f"{type(self).__name__!r} object has no attribute {name!r}"
        raise AttributeError(msg)
