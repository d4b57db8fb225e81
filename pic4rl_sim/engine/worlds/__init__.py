"""Worlds: the arena a robot drives in, as data, and the generators that make one.

``spec`` (``WorldSpec``: walls, obstacles and people as boxes and cylinders), ``generators``
(``WORLD_TABLE``: each generator's parameters and ``make_world``), ``arena`` (walls and the
seeded random stream), ``barn`` (BARN's 300 worlds, from ``data/``), ``barn_like`` (BARN-like
fields from a seed), ``dynbarn`` (them crossed by moving obstacles), ``held_out`` (the
benchmarks' test worlds, never trained on), ``clutter3d`` (obstacles below and above a LiDAR's
plane), ``vineyard`` (the vineyard's rows and lanes), ``rooms`` (a house of rooms joined by
seeded doors, for exploration; the walls with doors and the furniture ``indoor`` shares) and
``mjcf`` (a user's MJCF world; loads MuJoCo). Names are imported on first use.
"""

from __future__ import annotations

from pic4rl_base.lazy import lazy_exports

_EXPORTS = {
    "WorldSpec": "spec", "Box": "spec", "Cylinder": "spec", "PersonSpec": "spec",
    "WORLD_TABLE": "generators", "make_world": "generators", "world_params": "generators",
    "world_from_mjcf": "mjcf",
}
__all__ = sorted(_EXPORTS)
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
