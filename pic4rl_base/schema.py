"""Typed parameters: a node's parameters are one frozen dataclass whose fields carry a
description, a unit and a range.

From that one description come the flat dotted names ROS 2 uses (``reward.goal``), the
declarations of a node, the checks (one message format, ``"<key>: <value> is invalid; expected
<what>"``, and a "did you mean" for an unknown key), the docs' tables and the ``--help`` text.
The sim's, the env's and the trainer's parameters, and the robots' sensor specs, all go through
here. Pure Python (no ROS, no MuJoCo), so that pic4rl_bridge and pic4rl_agents use it freely.
The values themselves (types, ranges, choices) are ``pic4rl_base.param_types``, re-exported here.
"""

from __future__ import annotations

import dataclasses
import typing
from collections.abc import Iterator, Mapping
from dataclasses import MISSING, dataclass, field
from enum import Enum
from pathlib import Path
from typing import Any, TypeVar

import yaml

from .errors import ConfigError, require, require_choice, unknown_key
from .param_types import (FRACTION, NON_NEGATIVE, POSITIVE, PROBABILITY, TYPE_NAMES, ParamEnum,
                          ParamType, Range, coerce, literal, param_type)

__all__ = ["FRACTION", "NON_NEGATIVE", "POSITIVE", "PROBABILITY", "TYPE_NAMES", "ParamEnum",
           "ParamSpec", "ParamType", "Range", "check", "coerce", "flatten", "from_params",
           "help_text", "literal", "param", "param_names", "param_type", "read_yaml",
           "redefault", "section", "specs", "to_params"]

T = TypeVar("T")


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
            require_choice(self.name, value, self.choices)
        return value


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
            require_choice(key, value, f.metadata["choices"])
        if bounds is not None:
            require(value in bounds, key, value, bounds.expected())


def _choice(key: str, enum: type[Enum], value: Any) -> Enum:
    """``enum(value)``, or ``ConfigError`` listing the values."""
    require_choice(key, value, [m.value for m in enum])
    return enum(value)


# -- documentation ---------------------------------------------------------------------------


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
