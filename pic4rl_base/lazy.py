"""Public names of a package, imported from their modules on first use (PEP 562).

A sub-package's ``__init__`` lists each public name's module and exports them through
``lazy_exports``, so that importing one module of a package does not pay for what its
siblings load: the sim imports ``pic4rl_metrics.errors`` without pandas or rosbags, the bridge's
``config`` reads ``settings.tasks`` without MuJoCo or rclpy (and before the tasks, which read
``config``, have run), and the agents' ``config`` reads the algorithm table without torch.
Every package's sub-packages use this one module (the sim may import it: docs/architecture.md).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from importlib import import_module
from typing import Any


def homes_of(modules: Mapping[str, tuple[str, ...]]) -> dict[str, str]:
    """``{name: module}`` from ``{module: (names it exports)}``, the shape a long list reads
    best in."""
    return {name: module for module, names in modules.items() for name in names}


def lazy_exports(package: str, homes: Mapping[str, str], *,
                 namespace: dict[str, Any] | None = None,
                 before: Callable[[str], None] | None = None,
                 ) -> tuple[Callable[[str], Any], Callable[[], list[str]]]:
    """``(__getattr__, __dir__)`` of ``package``: ``homes`` maps a public name to its module,
    relative to the package (``"reader"``, ``"core.registry"``); a name read is kept in
    ``namespace`` (the package's ``globals()``) when given, so it is looked up once;
    ``before(module)`` runs before that module is first imported for a name."""

    def __getattr__(name: str) -> Any:
        home = homes.get(name)
        if home is None:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        if before is not None:
            before(home)
        value = getattr(import_module(f".{home}", package), name)
        if namespace is not None:
            namespace[name] = value
        return value

    def __dir__() -> list[str]:
        return sorted({*(namespace or ()), *homes})

    return __getattr__, __dir__
