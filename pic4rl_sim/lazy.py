"""A sub-package's public names, imported on first use (PEP 562): a sub-package ``__init__``
lists what it exports without loading what its users did not ask for (MuJoCo, rclpy), and
without running its modules before the lower modules they import have finished (the bridge's
``config`` reads ``tasks.registry``, whose tasks read ``config``)."""

from __future__ import annotations

import importlib
from collections.abc import Callable, Mapping
from typing import Any


def lazy_exports(package: str, exports: Mapping[str, str]
                 ) -> tuple[Callable[[str], Any], Callable[[], list[str]]]:
    """``__getattr__`` and ``__dir__`` for ``package``, whose public name ``n`` lives in its
    module ``exports[n]`` (a name relative to ``package``)."""

    def __getattr__(name: str) -> Any:
        if name not in exports:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        return getattr(importlib.import_module(f".{exports[name]}", package), name)

    def __dir__() -> list[str]:
        return sorted(exports)

    return __getattr__, __dir__
