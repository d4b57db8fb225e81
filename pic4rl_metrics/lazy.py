"""Public names of a package, imported from their modules on first use (PEP 562).

A sub-package's ``__init__`` lists each public name's module and exports them through
``lazy_exports``, so that ``import pic4rl_metrics.viz.raster`` (the bridge's renderer) or
``pic4rl_metrics.errors`` (the sim) does not pay for the matplotlib, pandas or rosbags its
siblings load.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from importlib import import_module
from typing import Any


def lazy_exports(package: str, namespace: dict[str, Any], homes: Mapping[str, str],
                 before: Callable[[str], None] | None = None,
                 ) -> tuple[Callable[[str], Any], Callable[[], list[str]]]:
    """``(__getattr__, __dir__)`` of ``package``: ``homes`` maps a public name to its module,
    relative to the package (``"reader"``, ``"core.registry"``); ``before(module)`` runs
    before that module is first imported for a name."""

    def __getattr__(name: str) -> Any:
        home = homes.get(name)
        if home is None:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        if before is not None:
            before(home)
        value = getattr(import_module(f".{home}", package), name)
        namespace[name] = value
        return value

    def __dir__() -> list[str]:
        return sorted({*namespace, *homes})

    return __getattr__, __dir__
