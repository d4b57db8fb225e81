"""Frontier choice: the frontier explorer with its next target chosen among candidates, by a
learned policy (``pic4rl_agents.training.frontier_choice``) or by any rule given the features.

Yamauchi's explorer (``exploration.FrontierExplorer``) drives to the nearest reachable frontier
cell, so it hops along a frontier a few decimetres at a time and crosses the house for a pocket
it left behind. ``ChoosingExplorer`` keeps its grids, its arrival rule, its plan and its pursuit
law, and whenever a new target is due offers up to ``CHOICES`` candidates: the reachable frontier
cells, nearest first by 8-connected steps through the cells clear of the inflated obstacles,
each taking the frontier within ``GROUP_M`` of it (its group) out of the running, so a
candidate stands for a stretch of frontier of its own. A candidate is given as ``FEATURES`` numbers, all in [-1, 1]: present
(1, else every number 0), steps away (m, / ``FAR_M``), straight-line distance (/ ``FAR_M``),
the cosine and sine of its bearing from the heading, the frontier within ``GROUP_M`` (m, /
``FRONTIER_NORM_M``, at most 1) and the share of the cells within ``UNKNOWN_M`` not seen yet;
then ``GLOBALS``: the area seen (m², / ``AREA_NORM_M2``, at most 1) and the reachable frontier
(m, / ``TOTAL_NORM_M``, at most 1). Everything comes from the robot's own scans and pose.

A candidate's target is placed as the explorer places its own beside its group of frontier
cells, so always choosing the first is nearly the explorer. A choice the plan finds no way to is given up,
as the explorer gives up its own, and the nearest candidate left is taken.
"""

from __future__ import annotations

import math

import numpy as np

from ..perception.frontiers import neighbours
from ..readings.frame import SensorFrame
from .exploration import _BAN_M, FRONTIER_CELL_M, FrontierExplorer, FrontierGrids, stand_beside

CHOICES = 6  # candidates offered
FEATURES = 7  # numbers per candidate
GLOBALS = 2  # numbers after the candidates'
GROUP_M = 1.0  # frontier this near a candidate is not offered as another
UNKNOWN_M = 1.5  # the disc whose unseen share is a candidate's feature
FAR_M = 20.0
FRONTIER_NORM_M = 4.0
AREA_NORM_M2 = 300.0
TOTAL_NORM_M = 50.0
#: The observation's length: the candidates' features, then the globals.
OBSERVATION_SIZE = CHOICES * FEATURES + GLOBALS


def frontier_steps(g: FrontierGrids) -> tuple[np.ndarray, np.ndarray]:
    """(the region reached from the robot's start cells through the clear cells, each
    frontier cell's steps from the robot: the ring at which the region first touches it, -1
    where it never does)."""
    allowed = g.clear | g.start
    region = g.start & allowed
    steps = np.full(region.shape, -1, dtype=np.int32)
    ring = 0
    while True:
        touched = neighbours(region, diagonal=True) & g.frontier & (steps < 0)
        steps[touched] = ring + 1
        bigger = neighbours(region, diagonal=True) & allowed
        if np.array_equal(bigger, region):
            return region, steps
        region, ring = bigger, ring + 1


class ChoosingExplorer(FrontierExplorer):
    """The frontier explorer whose targets are chosen (see the module's docstring): ``due``
    observes a frame and gives the candidates' features when a new target is due, ``drive``
    steers, to the candidate chosen when one is given."""

    def reset(self) -> None:
        super().reset()
        self.candidates: list[tuple[tuple[float, float], tuple[float, float]]] = []
        self._choice: int | None = None

    def due(self, frame: SensorFrame) -> np.ndarray | None:
        """Integrate ``frame``; the observation (``OBSERVATION_SIZE`` float32) when a new
        target is due (the explorer's arrival rule), else ``None``."""
        self.observe(frame)
        if not self._arrived(frame):
            return None
        self.candidates, observation = self.offer(frame)
        return observation

    def drive(self, frame: SensorFrame, choice: int | None) -> tuple[float, float]:
        """(v, ω) (m/s, rad/s): to candidate ``choice`` of the last offer when given (one
        beyond the offer: the nearest), else on to the target held."""
        self._choice = None if choice is None else int(choice)
        return self.steer(frame, choice is not None)

    def pick(self, frame: SensorFrame) -> tuple[tuple[float, float],
                                                tuple[float, float]] | None:
        left = [c for c in self.candidates
                if all(math.hypot(c[0][0] - bx, c[0][1] - by) > _BAN_M for bx, by in self._banned)]
        choice, self._choice = self._choice, None
        if choice is not None and 0 <= choice < len(self.candidates) and (
                self.candidates[choice] in left):
            return self.candidates[choice]
        return left[0] if left else None

    def offer(self, frame: SensorFrame) -> tuple[list[tuple[tuple[float, float],
                                                             tuple[float, float]]], np.ndarray]:
        """The candidates (target, frontier cell) nearest first, and the observation."""
        g = self.search_grids(frame)
        region, steps = frontier_steps(g)
        reach = steps >= 0
        gx, gy = g.gx.ravel(), g.gy.ravel()
        flat_steps, avail = steps.ravel(), reach.ravel().copy()
        seen_or_wall = (g.seen | g.occupied).ravel()
        candidates, rows = [], []
        pose = frame.pose
        while len(candidates) < CHOICES and avail.any():
            i = int(np.flatnonzero(avail)[np.argmin(flat_steps[avail])])
            fx, fy = float(gx[i]), float(gy[i])
            d = np.hypot(gx - fx, gy - fy)
            group = avail & (d <= GROUP_M)  # the frontier it stands for, no other's
            avail &= d > GROUP_M
            disc = d <= UNKNOWN_M
            candidates.append(stand_beside(g, region, group.reshape(region.shape)))
            bearing = math.atan2(fy - pose.y, fx - pose.x) - pose.yaw
            rows.append([1.0, min(flat_steps[i] * FRONTIER_CELL_M / FAR_M, 1.0),
                         min(math.hypot(fx - pose.x, fy - pose.y) / FAR_M, 1.0),
                         math.cos(bearing), math.sin(bearing),
                         min(np.count_nonzero(group) * FRONTIER_CELL_M / FRONTIER_NORM_M, 1.0),
                         float(np.count_nonzero(disc & ~seen_or_wall)) / np.count_nonzero(disc)])
        observation = np.zeros(OBSERVATION_SIZE, dtype=np.float32)
        if rows:
            observation[:len(rows) * FEATURES] = np.asarray(rows, dtype=np.float32).ravel()
        observation[-2] = min(self.seen.area_m2 / AREA_NORM_M2, 1.0)
        observation[-1] = min(np.count_nonzero(reach) * FRONTIER_CELL_M / TOTAL_NORM_M, 1.0)
        return candidates, observation
