"""Exploration metrics: the area the robot's scans have seen, judged from the bag alone.

The area seen over time is ``Derived.seen`` (``tasks.seen``: the scans integrated into a grid
of ``SEEN_RESOLUTION_M`` cells, for an episode whose ``task`` fact is an exploration); every
other episode gets NaN here, so a navigation table holds none of these columns (their
section, ``explore``, shows only where some episode has a value). A simulated
bag carries the world's free area (the ``free_area_m2`` fact) and gets a coverage percentage;
a real log gets the area in m² and its curve. Collisions are the ``collision_count`` every
episode with a footprint gets. Registered here in table order, imported by ``metrics``.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING

import numpy as np

from ..registry import metric
from .seen import SeenCurve

if TYPE_CHECKING:
    from ..derived import Derived

NAN = float("nan")


def _register(name: str, unit: str, label: str,
              stat: Callable[[SeenCurve, Derived], float], position: int) -> None:
    """Register a column at ``position`` in the comparison tables' ``explore`` section."""
    def value(d: Derived) -> float:
        curve = d.seen
        return NAN if curve is None else float(stat(curve, d))

    metric(name, unit=unit, label=label, needs=("scan",), table=("explore", position),
           _builtin=True)(value)


def _coverage(curve: SeenCurve, d: Derived) -> float:
    free = d.facts.free_area_m2
    return NAN if free is None else 100.0 * float(curve.area_m2[-1]) / free


def time_to(share: float) -> Callable[[SeenCurve, Derived], float]:
    """Seconds from the first pose to the first scan whose area seen reaches ``share`` of the
    world's free area (``free_area_m2``) when known, else of the episode's final area seen;
    NaN when it never does."""

    def stat(curve: SeenCurve, d: Derived) -> float:
        target = share * (d.facts.free_area_m2 or float(curve.area_m2[-1]))
        reached = np.flatnonzero(curve.area_m2 >= target)
        if not len(reached) or target <= 0:
            return NAN
        return (int(curve.t_ns[reached[0]]) - int(d.pose.t_ns[0])) * 1e-9

    return stat


def _path_per_area(curve: SeenCurve, d: Derived) -> float:
    area = float(curve.area_m2[-1])
    return d.path_m / area if area > 0 else NAN


_register("area_seen_m2", "m$^2$", "area seen", lambda c, d: c.area_m2[-1], 0)
_register("coverage_pct", "%", "coverage", _coverage, 1)
_register("time_to_50pct_s", "s", "time to 50 % seen", time_to(0.5), 2)
_register("time_to_90pct_s", "s", "time to 90 % seen", time_to(0.9), 3)
_register("path_per_area_seen_mpm2", "m/m$^2$", "path per area seen", _path_per_area, 4)
