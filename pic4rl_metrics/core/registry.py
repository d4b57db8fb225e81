"""The metric registry: every column of a result is a registered metric.

A metric is a pure function of one episode's series and facts (seen through ``Derived``, which
caches what several metrics share: velocities, accelerations, scan clearance, the outcome),
declared with its name, unit, table label and the inputs it needs. pic4rl's own metrics
register in ``metrics.py``; a user's package adds its own without touching ours, through the
entry-point group ``pic4rl.metrics`` (a module that registers on import, or a ``Metric``)::

    # pyproject.toml of the user's package
    [project.entry-points."pic4rl.metrics"]
    mine = "my_package.my_metrics"

    # my_package/my_metrics.py
    from pic4rl_metrics import metric

    @metric("mean_x_m", unit="m", needs=("pose",))
    def mean_x(d):
        return float(d.pose.x.mean())

A metric whose input the bag lacks gives NaN (with a warning on the row when the metric was
asked for by name or comes from a plugin); one that raises gives NaN and a warning.
"""

from __future__ import annotations

import difflib
import logging
import math
from collections.abc import Callable, Iterable, Iterator, Mapping
from dataclasses import dataclass
from importlib.metadata import entry_points
from typing import Any

from pic4rl_base.errors import ConfigError

from .derived import INPUT_TESTS, Derived

log = logging.getLogger(__name__)

#: Entry-point group through which installed packages add metrics.
ENTRY_POINT_GROUP = "pic4rl.metrics"

#: Inputs a metric may need; ``derived.INPUT_TESTS`` says how an episode has each.
INPUTS: frozenset[str] = frozenset(INPUT_TESTS)

#: The comparison tables' sections, in the order they are shown, and whether a section shows
#: always (the paper's Table 1) or only when some episode has a value (the vineyard's rows, the
#: social columns of an episode with people, the area seen of an exploration).
TABLE_SECTIONS: dict[str, bool] = {"paper": True, "row": False, "social": False, "explore": False}


@dataclass(frozen=True)
class Metric:
    """One column: ``func(derived) -> float`` (or ``str`` when ``text``).

    ``quality``: a trajectory-quality column, which tables average over the successful
    episodes unless asked to average all (``aggregate(over=...)``). ``table``: its place in
    the comparison tables, (section of ``TABLE_SECTIONS``, position in it); ``None``: in the
    per-episode results only.
    """

    name: str
    unit: str
    label: str
    func: Callable[[Derived], Any]
    needs: frozenset[str] = frozenset({"pose"})
    quality: bool = False
    text: bool = False
    builtin: bool = False
    table: tuple[str, int] | None = None

    def __post_init__(self) -> None:
        if self.table is not None and self.table[0] not in TABLE_SECTIONS:
            msg = (f"metric {self.name!r}: table section {self.table[0]!r} is none of "
                   f"{sorted(TABLE_SECTIONS)}")
            raise ConfigError(msg)
        if not self.name.isidentifier():
            msg = f"metric {self.name!r}: a name must be a Python identifier (a column name)"
            raise ConfigError(msg)
        unknown = set(self.needs) - INPUTS
        if unknown:
            msg = f"metric {self.name!r}: unknown inputs {sorted(unknown)}; known: {sorted(INPUTS)}"
            raise ConfigError(msg)


class MetricInfo(Mapping[str, Metric]):
    """Read-only view of the registry: name -> ``Metric`` (``.label``, ``.unit``)."""

    def __init__(self, registry: Registry) -> None:
        self._registry = registry

    def __getitem__(self, name: str) -> Metric:
        return self._registry.metrics[name]

    def __iter__(self) -> Iterator[str]:
        return iter(self._registry.metrics)

    def __len__(self) -> int:
        return len(self._registry.metrics)


class EpisodeMetrics(Mapping[str, Any]):
    """One episode's metric values by column (also as attributes: ``m.path_length_m``) and
    the warnings raised while computing them. NaN: cannot be computed from this bag."""

    def __init__(
        self, values: Mapping[str, Any] | None = None, /, *, warnings: Iterable[str] = (),
        **columns: Any,
    ) -> None:
        self._values = {**(values or {}), **columns}
        self.warnings: tuple[str, ...] = tuple(warnings)

    def __getitem__(self, name: str) -> Any:
        return self._values[name]

    def __iter__(self) -> Iterator[str]:
        return iter(self._values)

    def __len__(self) -> int:
        return len(self._values)

    def __getattr__(self, name: str) -> Any:
        try:
            return self.__dict__["_values"][name]
        except KeyError:
            raise AttributeError(f"no metric column {name!r}") from None

    def __repr__(self) -> str:
        return f"EpisodeMetrics({self._values!r})"

    def as_dict(self) -> dict[str, Any]:
        """Plain dict, one key per column."""
        return dict(self._values)


class Registry:
    """Metrics by name, in registration order (which is table order)."""

    def __init__(self) -> None:
        self.metrics: dict[str, Metric] = {}
        self._plugins_loaded = False
        #: Messages of plugins that failed to load (shown once per run, never fatal).
        self.plugin_errors: list[str] = []

    def add(self, item: Metric) -> Metric:
        if item.name in self.metrics:
            msg = f"metric {item.name!r} is registered already; choose another name"
            raise ConfigError(msg)
        self.metrics[item.name] = item
        return item

    def remove(self, name: str) -> None:
        """Unregister a metric (a test's or a notebook's); pic4rl's own stay."""
        if name in self.metrics and self.metrics[name].builtin:
            raise ConfigError(f"metric {name!r} is one of pic4rl's own; it cannot be removed")
        self.metrics.pop(name, None)

    def load_plugins(self) -> None:
        """Import the ``pic4rl.metrics`` entry points once; a broken one is reported, skipped."""
        if self._plugins_loaded:
            return
        self._plugins_loaded = True
        for point in entry_points(group=ENTRY_POINT_GROUP):
            try:
                loaded = point.load()
                if isinstance(loaded, Metric) and loaded.name not in self.metrics:
                    self.add(loaded)
            except Exception as err:  # noqa: BLE001 - a user's broken plugin must not stop us
                msg = f"metric plugin {point.name!r} ({point.value}): {type(err).__name__}: {err}"
                log.warning(msg)
                self.plugin_errors.append(msg)

    def table(self, section: str) -> tuple[str, ...]:
        """The columns placed in a table ``section``, in their positions' order."""
        placed = sorted((m.table[1], i, m.name) for i, m in enumerate(self.metrics.values())
                        if m.table is not None and m.table[0] == section)
        return tuple(name for _, _, name in placed)

    def select(self, names: Iterable[str] | None = None) -> tuple[Metric, ...]:
        """The metrics to compute: all (``names`` None) or the named ones in table order,
        always with ``outcome`` and ``success`` (tables need them). Unknown names raise
        ``ConfigError`` with the closest known name."""
        self.load_plugins()
        if names is None:
            return tuple(self.metrics.values())
        wanted = [n.strip() for n in names if n.strip()]
        for name in wanted:
            if name not in self.metrics:
                close = difflib.get_close_matches(name, list(self.metrics), n=1)
                hint = f"; did you mean {close[0]!r}?" if close else ""
                msg = f"--metrics: {name!r} is not a metric{hint} (see docs/metrics.md)"
                raise ConfigError(msg)
        chosen = {"outcome", "success", *wanted}
        return tuple(m for m in self.metrics.values() if m.name in chosen)


#: The process-wide registry: pic4rl's metrics, then plugins, then metrics registered at run time.
METRIC_TABLE = Registry()
#: Label and unit of every registered column (``METRICS[name].label``, ``.unit``).
METRICS = MetricInfo(METRIC_TABLE)


def metric(
    name: str,
    *,
    unit: str,
    label: str | None = None,
    needs: Iterable[str] = ("pose",),
    quality: bool = False,
    text: bool = False,
    table: tuple[str, int] | None = None,
    registry: Registry = METRIC_TABLE,
    _builtin: bool = False,
) -> Callable[[Callable[[Derived], Any]], Callable[[Derived], Any]]:
    """Decorator: register ``func(derived) -> float`` as the column ``name`` (``table``: its
    section and position in the comparison tables)."""

    def register(func: Callable[[Derived], Any]) -> Callable[[Derived], Any]:
        registry.add(Metric(
            name, unit, label or name, func, frozenset(needs), quality, text, _builtin, table,
        ))  # fmt: skip
        return func

    return register


def evaluate(
    derived: Derived, selected: Iterable[Metric], *, explicit: bool = False
) -> tuple[dict[str, Any], list[str]]:
    """Each selected metric's value on one episode, and the warnings: a missing input gives
    NaN (warned when ``explicit`` or for a plugin's metric), an exception NaN and a warning."""
    values: dict[str, Any] = {}
    warnings: list[str] = []
    missing_for: dict[str, list[str]] = {}
    for item in selected:
        missing = derived.missing(item.needs)
        if missing:
            values[item.name] = None if item.text else math.nan
            if explicit or not item.builtin:
                missing_for.setdefault(", ".join(sorted(missing)), []).append(item.name)
            continue
        try:
            values[item.name] = item.func(derived)
        except Exception as err:  # noqa: BLE001 - one metric's bug must not cost the others
            if item.builtin:
                raise
            values[item.name] = None if item.text else math.nan
            warnings.append(f"metric {item.name!r} failed: {type(err).__name__}: {err}; NaN")
    for inputs, names in missing_for.items():
        warnings.append(f"no {inputs} in this bag: {', '.join(names)} NaN")
    return values, warnings
