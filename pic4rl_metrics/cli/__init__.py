"""``pic4rl-metrics``: its commands (``commands``: compute, compare, plot, report) and its
``video`` command's options and run (``video``).
"""

from __future__ import annotations

from pic4rl_base.lazy import lazy_exports

_HOMES = {
    "main": "commands", "build_parser": "commands",
}
__getattr__, __dir__ = lazy_exports(__name__, _HOMES, namespace=globals())
__all__ = sorted(_HOMES)
