"""Names a sub-package exports, imported when first read (PEP 562).

A sub-package's ``__init__`` names its public names and the module of each, but imports
none: ``pic4rl_agents.config`` reads the light algorithm table in ``models/`` for ``--help``,
and that must not load torch through ``models/algorithms.py``. ``from pic4rl_agents.models
import new_model`` imports ``models/algorithms.py`` then, as its own import would.
"""

from __future__ import annotations

import importlib
from collections.abc import Callable, Mapping
from typing import Any


def lazy_exports(package: str, modules: Mapping[str, tuple[str, ...]]
                 ) -> tuple[list[str], Callable[[str], Any]]:
    """``__all__`` and ``__getattr__`` for ``package``: ``modules`` maps each of its modules
    to the names it exports."""
    owner = {name: module for module, names in modules.items() for name in names}

    def __getattr__(name: str) -> Any:
        if name not in owner:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        return getattr(importlib.import_module(f"{package}.{owner[name]}"), name)

    return sorted(owner), __getattr__
