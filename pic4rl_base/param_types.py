"""The values a parameter holds: its ROS 2 type, its range, a string choice, and how a value
from a file or the command line becomes one (``coerce``) or is written back (``literal``).

The building blocks of ``pic4rl_base.schema``, which re-exports them. Pure Python.
"""

from __future__ import annotations

import array
import math
import typing
from dataclasses import dataclass
from enum import Enum
from typing import Any

import yaml

from .errors import ConfigError, require

__all__ = ["FRACTION", "NON_NEGATIVE", "POSITIVE", "PROBABILITY", "TYPE_NAMES", "ParamEnum",
           "ParamType", "Range", "coerce", "literal", "param_type"]


class ParamEnum(str, Enum):
    """A string-valued choice that reads, prints, hashes and compares as its value, so that a
    typed field stays what a params file holds (``task: goToPose``) and error messages quote
    it as the user wrote it."""

    def __str__(self) -> str:
        return str(self.value)

    def __repr__(self) -> str:
        return repr(str(self.value))

    def __format__(self, spec: str) -> str:
        return format(str(self.value), spec)

    def __hash__(self) -> int:
        return hash(str(self.value))


# A summary or a run's config written with yaml.safe_dump holds the value, as a params file does.
yaml.SafeDumper.add_multi_representer(
    ParamEnum, lambda dumper, value: dumper.represent_str(str(value.value)))


@dataclass(frozen=True)
class Range:
    """Bounds of a number; ``lo_open``/``hi_open`` exclude the bound itself. ROS 2's declared
    ranges are inclusive, so a node declares ``closure`` and the dataclass checks the rest."""

    lo: float = -math.inf
    hi: float = math.inf
    lo_open: bool = False
    hi_open: bool = False

    def __contains__(self, value: float) -> bool:
        if not math.isfinite(value):
            return False
        above = value > self.lo if self.lo_open else value >= self.lo
        below = value < self.hi if self.hi_open else value <= self.hi
        return above and below

    @property
    def closure(self) -> tuple[float, float] | None:
        """The inclusive (lo, hi) a ROS declaration can carry; ``None`` when unbounded."""
        if math.isinf(self.lo) or math.isinf(self.hi):
            return None
        return self.lo, self.hi

    def expected(self) -> str:
        """What a value must be, as error messages and docs say it."""
        if math.isinf(self.hi) and self.lo == 0:
            return "a positive number" if self.lo_open else "a number >= 0"
        if math.isinf(self.hi):
            return f"a number {'>' if self.lo_open else '>='} {_num(self.lo)}"
        if math.isinf(self.lo):
            return f"a number {'<' if self.hi_open else '<='} {_num(self.hi)}"
        return f"a value in {self}"

    def __str__(self) -> str:
        return (f"{'(' if self.lo_open else '['}{_num(self.lo)}, {_num(self.hi)}"
                f"{')' if self.hi_open else ']'}")


def _num(value: float) -> str:
    return str(int(value)) if float(value).is_integer() else repr(value)


POSITIVE = Range(0.0, lo_open=True)
NON_NEGATIVE = Range(0.0)
PROBABILITY = Range(0.0, 1.0)
FRACTION = Range(0.0, 1.0, hi_open=True)


class ParamType(str, Enum):
    """The ROS 2 parameter types (names as in ``rclpy.Parameter.Type``)."""

    BOOL = "BOOL"
    INTEGER = "INTEGER"
    DOUBLE = "DOUBLE"
    STRING = "STRING"
    INTEGER_ARRAY = "INTEGER_ARRAY"
    DOUBLE_ARRAY = "DOUBLE_ARRAY"
    STRING_ARRAY = "STRING_ARRAY"


_SCALARS = {bool: ParamType.BOOL, int: ParamType.INTEGER, float: ParamType.DOUBLE,
            str: ParamType.STRING}
_ARRAYS = {int: ParamType.INTEGER_ARRAY, float: ParamType.DOUBLE_ARRAY,
           str: ParamType.STRING_ARRAY}
_EXPECTED = {ParamType.BOOL: "true or false", ParamType.INTEGER: "an integer",
             ParamType.DOUBLE: "a number", ParamType.STRING: "a string",
             ParamType.INTEGER_ARRAY: "a list of integers",
             ParamType.DOUBLE_ARRAY: "a list of numbers",
             ParamType.STRING_ARRAY: "a list of strings"}
#: ROS 2's names of the types, as the docs' tables write them.
TYPE_NAMES = {ParamType.BOOL: "bool", ParamType.INTEGER: "integer", ParamType.DOUBLE: "double",
              ParamType.STRING: "string", ParamType.INTEGER_ARRAY: "integer[]",
              ParamType.DOUBLE_ARRAY: "double[]", ParamType.STRING_ARRAY: "string[]"}


def coerce(key: str, kind: ParamType, value: Any) -> Any:
    """``value`` as ``kind`` (an int where a float is wanted becomes a float; arrays become
    lists), or ``ConfigError`` naming ``key``."""
    is_int = isinstance(value, int) and not isinstance(value, bool)
    ok: bool
    if kind is ParamType.BOOL:
        ok = isinstance(value, bool)
    elif kind is ParamType.INTEGER:
        ok = is_int
    elif kind is ParamType.DOUBLE:
        ok = is_int or isinstance(value, float)
        value = float(value) if ok else value
    elif kind is ParamType.STRING:
        ok = isinstance(value, str)
    else:
        item = {ParamType.INTEGER_ARRAY: ParamType.INTEGER,
                ParamType.DOUBLE_ARRAY: ParamType.DOUBLE,
                ParamType.STRING_ARRAY: ParamType.STRING}[kind]
        ok = isinstance(value, (list, tuple, array.array))
        if ok:
            try:
                value = [coerce(key, item, v) for v in value]
            except ConfigError:
                ok = False
    require(ok, key, value, _EXPECTED[kind])
    return value


def param_type(hint: Any) -> tuple[ParamType, type[Enum] | None]:
    """The ROS type of a field's annotation, and its enum class if it is one."""
    if isinstance(hint, type) and issubclass(hint, Enum):
        return ParamType.STRING, hint
    if typing.get_origin(hint) is tuple:
        return _ARRAYS[typing.get_args(hint)[0]], None
    return _SCALARS[hint], None


def literal(value: Any) -> str:
    """A default as a params file (and the docs) write it."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(literal(v) for v in value) + "]"
    if isinstance(value, str):
        return value if value else '""'
    return repr(value)
