"""Typed parameters: a node's parameters are one frozen dataclass whose fields carry a
description, a unit and a range.

From that one description come the flat dotted names ROS 2 uses (``reward.goal``), the
declarations of a node, the checks (one message format, ``"<key>: <value> is invalid; expected
<what>"``, and a "did you mean" for an unknown key), the docs' tables and the ``--help`` text.
The sim's, the env's and the trainer's parameters, and the robots' sensor specs, all go through
here. Pure Python (no ROS, no MuJoCo), so that pic4rl_bridge and pic4rl_agents use it freely.
"""

from __future__ import annotations

import array
import dataclasses
import math
import typing
from collections.abc import Iterator, Mapping
from dataclasses import MISSING, dataclass, field
from enum import Enum
from pathlib import Path
from typing import Any, TypeVar

import yaml

from .errors import ConfigError, require, unknown_key

T = TypeVar("T")


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


def param(default: Any = MISSING, *, doc: str, unit: str = "", range: Range | None = None,
          choices: tuple[str, ...] = (), factory: Any = MISSING) -> Any:
    """A parameter field: its default (``factory`` for a mutable one), what it means, its unit
    (``"m"``, ``"rad/s"``), its range and, for a string naming an entry of a registry (pair
    kinds), the registry's names; ``check`` enforces range and choices (an enum-typed field
    needs no ``choices``: its values are the enum's)."""
    meta = {"doc": doc, "unit": unit, "range": range, "choices": tuple(choices)}
    if factory is not MISSING:
        return field(default_factory=factory, metadata=meta)
    return field(default=default, metadata=meta)


def redefault(cls: type, name: str, default: Any) -> Any:
    """``cls``'s parameter ``name`` (doc, unit, range) with another default, for a dataclass
    that shares a parameter with ``cls`` (the person world's obstacle field)."""
    return field(default=default, metadata=cls.__dataclass_fields__[name].metadata)


def section(cls: type, doc: str = "") -> Any:
    """A nested group of parameters (``reward.*``), defaulting to ``cls()``."""
    return field(default_factory=cls, metadata={"doc": doc or (cls.__doc__ or "").strip()})


# -- the parameters of a dataclass ------------------------------------------------------------


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


@dataclass(frozen=True)
class ParamSpec:
    """One flat parameter: its dotted name, ROS type, default, description, unit, range and
    (for an enum) choices. ``range`` is the inclusive closure a ROS declaration carries."""

    name: str
    type: ParamType
    default: Any
    description: str
    range: tuple[float, float] | None = None
    choices: tuple[str, ...] = ()
    unit: str = ""
    bounds: Range | None = None

    def check(self, value: Any) -> Any:
        """``value`` in this parameter's type (an integer where a number is wanted becomes a
        float), or ``ConfigError`` naming the key, the value and what was expected."""
        value = coerce(self.name, self.type, value)
        if self.range is not None:
            lo, hi = self.range
            require(lo <= value <= hi, self.name, value, f"a value in [{lo}, {hi}]")
        if self.choices:
            require(value in self.choices, self.name, value, f"one of {', '.join(self.choices)}")
        return value


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


def _is_section(hint: Any) -> bool:
    return isinstance(hint, type) and dataclasses.is_dataclass(hint)


def _param_fields(cls: type) -> Iterator[tuple[dataclasses.Field[Any], Any]]:
    hints = typing.get_type_hints(cls)
    for f in dataclasses.fields(cls):  # type: ignore[arg-type]
        if f.init and ("doc" in f.metadata or _is_section(hints[f.name])):
            yield f, hints[f.name]


def specs(cls: type, *, defaults: Any = None, prefix: str = "") -> tuple[ParamSpec, ...]:
    """Every parameter of the dataclass ``cls``, dotted, with ``defaults``' values (an
    instance; ``cls()`` when ``None``) as defaults."""
    defaults = cls() if defaults is None else defaults
    out: list[ParamSpec] = []
    for f, hint in _param_fields(cls):
        value = getattr(defaults, f.name)
        if _is_section(hint):
            out += specs(hint, defaults=value, prefix=f"{prefix}{f.name}.")
            continue
        kind, enum = param_type(hint)
        bounds = f.metadata.get("range")
        unit = f.metadata.get("unit", "")
        out.append(ParamSpec(
            f"{prefix}{f.name}", kind, _plain(value),
            f"{f.metadata['doc']} ({unit})" if unit else f.metadata["doc"],
            bounds.closure if bounds else None,
            tuple(m.value for m in enum) if enum else f.metadata.get("choices", ()),
            unit, bounds))
    return tuple(out)


def _plain(value: Any) -> Any:
    """A field's value as a params file holds it: enums as their value, tuples as lists."""
    if isinstance(value, Enum):
        return value.value
    if isinstance(value, tuple):
        return [_plain(v) for v in value]
    return value


def to_params(obj: Any, prefix: str = "") -> dict[str, Any]:
    """The flat dotted parameters of a config dataclass (lists for tuples, values for enums)."""
    out: dict[str, Any] = {}
    for f, hint in _param_fields(type(obj)):
        value = getattr(obj, f.name)
        if _is_section(hint):
            out.update(to_params(value, f"{prefix}{f.name}."))
        else:
            out[f"{prefix}{f.name}"] = _plain(value)
    return out


def flatten(data: Mapping[str, Any], prefix: str = "") -> dict[str, Any]:
    """Nested mappings as dotted names, as ROS 2 reads ``ros__parameters``."""
    out: dict[str, Any] = {}
    for key, value in data.items():
        name = f"{prefix}{key}"
        if isinstance(value, Mapping):
            out.update(flatten(value, f"{name}."))
        else:
            out[name] = value
    return out


def from_params(cls: type[T], params: Mapping[str, Any], *, where: str) -> T:
    """A ``cls`` from dotted (or nested) parameters: each value typed and checked, an unknown
    key an error naming ``where`` ("nav_env parameters") with a "did you mean"."""
    flat = flatten(params)
    known = {spec.name for spec in specs(cls)}
    for key in sorted(flat):
        if key not in known:
            raise unknown_key(key, known, where=where)
    return _build(cls, flat, "")


def _build(cls: type[T], flat: Mapping[str, Any], prefix: str) -> T:
    kwargs: dict[str, Any] = {}
    for f, hint in _param_fields(cls):
        key = f"{prefix}{f.name}"
        if _is_section(hint):
            kwargs[f.name] = _build(hint, flat, f"{key}.")
        elif key in flat:
            kind, enum = param_type(hint)
            value = coerce(key, kind, flat[key])
            if enum is not None:
                value = _choice(key, enum, value)
            kwargs[f.name] = tuple(value) if isinstance(value, list) else value
    return cls(**kwargs)


def check(obj: Any, prefix: str = "") -> None:
    """``ConfigError`` for the first field of ``obj`` (and of its sections) of the wrong type,
    choice or range (ints where floats are wanted become floats, lists tuples); for a dataclass
    built in code as for one read from a file;
    call it from the top dataclass's ``__post_init__`` with the dotted ``prefix`` of its keys."""
    for f, hint in _param_fields(type(obj)):
        value = getattr(obj, f.name)
        if _is_section(hint):
            check(value, f"{prefix}{f.name}.")
            continue
        key, bounds = f"{prefix}{f.name}", f.metadata.get("range")
        kind, enum = param_type(hint)
        if enum is not None:
            if not isinstance(value, enum):  # built from a plain string
                object.__setattr__(obj, f.name, _choice(key, enum, value))
            continue
        typed = coerce(key, kind, value)
        if isinstance(typed, list):
            typed = tuple(typed)
        if typed is not value:
            object.__setattr__(obj, f.name, typed)
            value = typed
        if f.metadata.get("choices"):
            choices = f.metadata["choices"]
            require(value in choices, key, value, f"one of {', '.join(choices)}")
        if bounds is not None:
            require(value in bounds, key, value, bounds.expected())


def _choice(key: str, enum: type[Enum], value: Any) -> Enum:
    """``enum(value)``, or ``ConfigError`` listing the values."""
    names = [m.value for m in enum]
    require(value in names, key, value, f"one of {', '.join(names)}")
    return enum(value)


# -- documentation ---------------------------------------------------------------------------


def literal(value: Any) -> str:
    """A default as a params file (and the docs) write it."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(literal(v) for v in value) + "]"
    if isinstance(value, str):
        return value if value else '""'
    return repr(value)


def help_text(table: tuple[ParamSpec, ...]) -> str:
    """The parameters as ``--help`` lists them: name, type, default, then what it means."""
    lines = []
    for spec in table:
        limits = f" {spec.bounds}" if spec.bounds else ""
        if spec.choices:
            limits = f" {{{', '.join(spec.choices)}}}"
        lines.append(f"  {spec.name} ({TYPE_NAMES[spec.type]}, default {literal(spec.default)})"
                     f"{limits}")
        lines.append(f"      {spec.description}")
    return "\n".join(lines)


def param_names(cls: type) -> tuple[str, ...]:
    """The dotted names of every parameter of the config dataclass ``cls``."""
    return tuple(spec.name for spec in specs(cls))


def read_yaml(path: str | Path, what: str) -> Any:
    """The YAML document of ``path`` (a ``what``: "config file", "robot file", ...), or
    ``ConfigError`` naming the file: unreadable, or not valid YAML."""
    path = Path(path)
    try:
        return yaml.safe_load(path.read_text())
    except OSError as err:
        raise ConfigError(f"{path}: cannot read the {what}: {err.strerror}") from err
    except yaml.YAMLError as err:
        raise ConfigError(f"{path}: not valid YAML: {err}") from err
