"""``Goal``: where an episode should end, one type from the sim's parameters to the bag's facts,
and ``GOAL_TOLERANCE_M``, how close counts as reaching it unless told otherwise.

Its own small module so that every package may import it (the sim's door to the metrics names
it beside ``errors`` and ``geometry``): it loads nothing but the standard library.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

#: The goal tolerance (m) when none is given: the env's ``goal_tolerance_m`` default (the
#: shipped agents' episodes end by it), and what the metrics assume for a bag whose facts give
#: none.
GOAL_TOLERANCE_M = 0.4


class Goal(tuple[float, float]):
    """A goal in the world frame (the frame of the sim's ``goal_pose``): the position
    ``(x, y)`` (m), which is the pair every reader indexes or unpacks, and an optional heading
    ``yaw`` (rad) for a task that judges the final heading (``None``: any heading).

    On the wire (``goal_pose``, a ``PoseStamped``) a goal without heading keeps the identity
    orientation, so a heading of exactly 0 rad reads back as ``None``: a task that judges the
    heading takes ``None`` as 0."""

    yaw: float | None

    def __new__(cls, x: float, y: float, yaw: float | None = None) -> Goal:
        goal = super().__new__(cls, (float(x), float(y)))
        goal.yaw = None if yaw is None else float(yaw)
        return goal

    @classmethod
    def of(cls, value: Goal | Sequence[float]) -> Goal:
        """``value`` as a goal: a goal as it is, ``(x, y)`` or ``(x, y, yaw)``."""
        if isinstance(value, Goal):
            return value
        return cls(*value)

    @property
    def x(self) -> float:
        return self[0]

    @property
    def y(self) -> float:
        return self[1]

    def as_list(self) -> list[float]:
        """``[x, y]``, or ``[x, y, yaw]`` with a heading: the parameter's and the fact's form."""
        return [self[0], self[1]] + ([] if self.yaw is None else [self.yaw])

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, tuple):
            return NotImplemented
        return tuple(self) == tuple(other) and self.yaw == getattr(other, "yaw", None)

    def __ne__(self, other: object) -> bool:
        equal = self.__eq__(other)
        return equal if equal is NotImplemented else not equal

    __hash__ = tuple.__hash__

    def __reduce__(self) -> tuple[Any, ...]:
        return (Goal, (self[0], self[1], self.yaw))

    def __repr__(self) -> str:
        heading = "" if self.yaw is None else f", yaw={self.yaw!r}"
        return f"Goal({self[0]!r}, {self[1]!r}{heading})"

