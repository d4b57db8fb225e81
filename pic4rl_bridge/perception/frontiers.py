"""What a robot has seen, and region growing on boolean grids (pure numpy): a scan integrated
into the seen grid from its beams as the metrics place a bag's (``scan_beams``), the world's floor
connected to a start, which the explore task counts as the free area to cover, and the
frontiers of what a robot has seen (Yamauchi 1997: known free cells next to unknown ones),
which the frontier baseline drives to.

One routine grows a region one ring of cells at a time (``grow``); the frontier search stops at
the first ring that touches a frontier, so the frontier it returns is the nearest by grid
steps through known free space, the "nearest reachable frontier".
"""

from __future__ import annotations

import math

import numpy as np

from pic4rl_base.geometry import Pose2D
from pic4rl_base.seen_area import SeenGrid, beam_reach

from ..readings.frame import ScanData


def neighbours(mask: np.ndarray, *, diagonal: bool) -> np.ndarray:
    """The cells next to a cell of ``mask`` (4-connected, or 8 with ``diagonal``), ``mask``'s
    own included; nothing wraps round the edges."""
    out = mask.copy()
    out[1:, :] |= mask[:-1, :]
    out[:-1, :] |= mask[1:, :]
    out[:, 1:] |= mask[:, :-1]
    out[:, :-1] |= mask[:, 1:]
    if diagonal:
        out[1:, 1:] |= mask[:-1, :-1]
        out[1:, :-1] |= mask[:-1, 1:]
        out[:-1, 1:] |= mask[1:, :-1]
        out[:-1, :-1] |= mask[1:, 1:]
    return out


def grow(region: np.ndarray, allowed: np.ndarray, *, diagonal: bool = False,
         stop: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Grow ``region`` through ``allowed`` cells a ring at a time until it stops growing or,
    with ``stop``, a ring's neighbours touch a ``stop`` cell. (the region, the ``stop`` cells
    touched: none when it stopped growing first)."""
    region = region & allowed
    touched = np.zeros_like(region)
    while True:
        if stop is not None:
            touched = neighbours(region, diagonal=diagonal) & stop
            if touched.any():
                return region, touched
        bigger = neighbours(region, diagonal=diagonal) & allowed
        if np.array_equal(bigger, region):
            return region, touched
        region = bigger


def component(free: np.ndarray, cell: tuple[int, int]) -> np.ndarray:
    """The 4-connected region of ``free`` holding ``cell`` (row, column), or, when that cell
    is not free, holding the free cell nearest it; all False when nothing is free."""
    row, col = cell
    if not free[row, col]:
        rows, cols = np.nonzero(free)
        if not len(rows):
            return np.zeros_like(free)
        nearest = int(np.argmin((rows - row) ** 2 + (cols - col) ** 2))
        row, col = int(rows[nearest]), int(cols[nearest])
    seed = np.zeros_like(free)
    seed[row, col] = True
    return grow(seed, free)[0]


def frontier_cells(seen: np.ndarray, occupied: np.ndarray) -> np.ndarray:
    """Known free cells (seen, not occupied nor next to an occupied cell) with an unseen
    4-neighbour: the border between what was seen and the unknown. The grid's edge counts
    as unseen."""
    padded = np.pad(~seen, 1, constant_values=True)
    unknown_near = neighbours(padded, diagonal=False)[1:-1, 1:-1]
    return seen & ~neighbours(occupied, diagonal=True) & unknown_near


def scan_beams(scan: ScanData, pose: Pose2D) -> tuple[float, float, float, np.ndarray,
                                                      np.ndarray]:
    """``scan`` taken at ``pose`` as ``SeenGrid.add`` takes it, placed as the metrics place a
    bag's scan: the sensor's x, y and heading (its mount applied), each beam's bearing and
    reach (``beam_reach``)."""
    reach = beam_reach(scan.ranges, scan.range_min_m, scan.range_max_m)
    c, s = math.cos(pose.yaw), math.sin(pose.yaw)
    m = scan.mount
    x, y = pose.x + c * m.x - s * m.y, pose.y + s * m.x + c * m.y
    return x, y, pose.yaw + m.yaw, scan.angles(), reach


def integrate_scan(grid: SeenGrid, scan: ScanData, pose: Pose2D) -> int:
    """Add ``scan`` taken at ``pose`` to ``grid`` (``scan_beams``); the cells added."""
    return grid.add(*scan_beams(scan, pose))
