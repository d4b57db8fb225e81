"""The walking person's varied parts: a speed per leg, and obstacles that hide it at corners.

A follower a few metres behind the person loses sight of it where the loop turns round an
obstacle on the inside of the corner (the line of sight cuts the corner), so the person
world puts ``occluders`` there. Both are drawn from the world's generator after its
obstacle field, so a world without them keeps the field its seed gave before.
"""

from __future__ import annotations

import numpy as np

from .worlds.spec import Box, Cylinder, clearance

OCCLUDER_HEIGHT_M = 1.0
#: Steps (m) by which an occluder is pushed further inside a corner until it is clear.
_OCCLUDER_STEP_M = 0.05
_OCCLUDER_TRIES = 40


def leg_speeds(rng: np.random.Generator, legs: int, speed_m_s: float,
               spread: float) -> tuple[float, ...]:
    """A speed (m/s) per leg, uniform in ``speed_m_s`` × [1 - spread, 1 + spread]; ``()``
    (every leg at ``speed_m_s``) when ``spread`` is 0 or the person stands."""
    if spread == 0 or speed_m_s == 0:
        return ()
    return tuple(float(v) for v in speed_m_s * rng.uniform(1 - spread, 1 + spread, legs))


def corner_occluders(rng: np.random.Generator, loop: np.ndarray, path_xy: np.ndarray,
                     count: int, *, keep_off_m: float,
                     sizes_m: tuple[float, float], half_size_m: float,
                     obstacles: tuple[tuple[Box, ...], tuple[Cylinder, ...]],
                     ) -> list[Cylinder]:
    """Up to ``count`` cylinders, each inside a different corner of ``loop`` (n × 2, m, the
    corners tried in a random order) on its bisector, as close to the corner as keeps
    ``keep_off_m`` from the walked path (``path_xy``, dense samples) and out of the other
    obstacles and the walls of the square arena of half side ``half_size_m`` (it may touch
    them: the robot's way is the person's, kept free). A corner with no such place gets
    none."""
    boxes, cylinders = obstacles
    placed: list[Cylinder] = []
    for i in rng.permutation(len(loop)):
        if len(placed) == count:
            break
        corner = loop[i]
        inward = ((loop[i - 1] - corner) / np.hypot(*(loop[i - 1] - corner))
                  + (loop[(i + 1) % len(loop)] - corner)
                  / np.hypot(*(loop[(i + 1) % len(loop)] - corner)))
        norm = float(np.hypot(*inward))
        if norm < 1e-6:  # a straight-through waypoint has no inside
            continue
        radius = 0.5 * float(rng.uniform(*sizes_m))
        for k in range(_OCCLUDER_TRIES):
            xy = corner + inward / norm * (keep_off_m + radius + k * _OCCLUDER_STEP_M)
            others = clearance(xy[None, :], boxes, (*cylinders, *placed))[0]
            if (np.hypot(*(path_xy - xy).T).min() >= keep_off_m + radius
                    and others >= radius and np.abs(xy).max() <= half_size_m - radius):
                placed.append(Cylinder(float(xy[0]), float(xy[1]), radius, OCCLUDER_HEIGHT_M))
                break
    return placed

