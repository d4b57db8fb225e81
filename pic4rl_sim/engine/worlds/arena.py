"""What every world generator shares: the seed's check, and the walls around the arena."""

from __future__ import annotations

import numpy as np

from pic4rl_base.errors import require

from .spec import Box

WALL_THICKNESS_M = 0.1
WALL_HEIGHT_M = 1.0


def rng_for(seed: int) -> np.random.Generator:
    ok = isinstance(seed, int) and not isinstance(seed, bool) and seed >= 0
    require(ok, "world.seed", seed, "an integer >= 0")
    return np.random.default_rng(seed)


def walls(bounds: tuple[float, float, float, float]) -> list[Box]:
    """Four wall boxes just outside the free rectangle ``bounds``."""
    xmin, ymin, xmax, ymax = bounds
    t, cx, cy = WALL_THICKNESS_M, 0.5 * (xmin + xmax), 0.5 * (ymin + ymax)
    long_x, long_y = xmax - xmin + 2 * t, ymax - ymin
    return [Box(cx, ymin - t / 2, long_x, t, WALL_HEIGHT_M),
            Box(cx, ymax + t / 2, long_x, t, WALL_HEIGHT_M),
            Box(xmin - t / 2, cy, t, long_y, WALL_HEIGHT_M),
            Box(xmax + t / 2, cy, t, long_y, WALL_HEIGHT_M)]
