"""The goal from UWB ranges alone (``goal_input: uwb``): why a robot needs no odometry, no map
and no goal pose to point at a tag.

Anchors mounted on the robot (``uwb.anchors_on_robot``, at one height) each range to the tag
at the goal, as a person-following robot's anchors range to the person's tag. Seen from a tag
farther than the anchors' spread, anchor ``a_i`` (base frame) reads ``r_i ≈ R - a_i · w``:
``R`` the range from the base's origin, ``w`` the unit vector toward the tag projected on the
floor. Three or more anchors give ``R`` and ``w`` by linear least squares from that step's
ranges alone: the bearing is ``w``'s angle, the distance on the floor ``sqrt(R² - dz²)`` with
``dz`` the tag's height above the anchors (both the sensor's spec). The bearing's noise is the
ranges' divided by the anchors' spread (0.1 m over ±0.25 m: about 12°, ``docs/sensors.md``);
trilateration on squared ranges instead multiplies it by the distance. A lost range (``+inf``,
a dropout or beyond the maximum) is left out and shows in the mask; with fewer than three (or
collinear) anchors left, the bearing reads 0 and the distance the nearest range received
(``inf`` with none).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from pic4rl_base.errors import ConfigError
from pic4rl_sim.engine.sensor_kinds import uwb

#: The fewest anchors whose ranges give a position in the plane.
MIN_ANCHORS = 3


class UwbGoal:
    """The goal part's estimate from the robot's anchors at ``anchors_xy_m`` (base frame, in
    name order ``a0``, ``a1``, ...)."""

    def __init__(self, anchors_xy_m: Sequence[tuple[float, float]], dz_m: float = 0.0) -> None:
        self.anchors = np.asarray(anchors_xy_m, dtype=float).reshape(-1, 2)
        self.dz_m = dz_m
        #: The frame's readings it needs, in the anchors' order.
        self.readings = tuple(uwb.reading_name(f"a{i}") for i in range(len(self.anchors)))

    @classmethod
    def of(cls, specs: Mapping[str, Any]) -> UwbGoal:
        """The estimate for a robot whose sensor specs are ``specs`` (``RobotInfo.specs``);
        a one-line error unless it carries at least ``MIN_ANCHORS`` anchors on it."""
        spec = specs.get(uwb.NAME)
        if spec is None or not spec.anchors_on_robot or len(spec.anchors) < MIN_ANCHORS:
            raise ConfigError(f"goal_input: uwb needs the robot's UWB anchors: expected "
                             f"uwb.enabled, uwb.anchors_on_robot true and {MIN_ANCHORS}+ "
                             f"anchors in uwb.anchors_xy_m (got {spec and spec.anchors_xy_m})")
        return cls([(x, y) for x, y, _ in spec.anchors],
                   spec.goal_tag_height_m - spec.anchor_height_m)

    def ranges(self, readings: Mapping[str, Any]) -> np.ndarray:
        """The anchors' ranges (m) in ``readings`` (a frame's), ``inf`` where lost."""
        missing = [name for name in self.readings if name not in readings]
        if missing:
            raise ValueError(f"goToPose (goal_input uwb): the frame has no {missing[0]} (topic "
                             f"uwb/{missing[0][len(uwb.NAME) + 1:]}); expected a range per anchor")
        return np.array([float(readings[name]) for name in self.readings])

    def estimate(self, ranges: np.ndarray) -> tuple[float, float, np.ndarray]:
        """(distance m, bearing rad, mask): the tag in the base frame from ``ranges``; the
        mask is 1 for each range received, 0 for each lost."""
        received = np.isfinite(ranges) & (ranges >= 0)
        mask = received.astype(np.float32)
        a, r = self.anchors[received], ranges[received]
        if len(r) >= MIN_ANCHORS:
            design = np.column_stack((np.ones(len(r)), -a))  # r_i = R - a_i · w
            (far, wx, wy), _, rank, _ = np.linalg.lstsq(design, r, rcond=None)
            if rank == 3:
                return (math.sqrt(max(far * far - self.dz_m * self.dz_m, 0.0)),
                        math.atan2(wy, wx), mask)
        return (float(r.min()) if len(r) else math.inf), 0.0, mask
