"""A grid path pulled taut: the cell path of ``paths.PathPlanner``'s search shortened by line of
sight, its bends slid coarse to fine towards their neighbours' line while both segments stay
free, and bends round rounded corners cut into short arcs. This removes the 8-connected grid's
bias (up to 8 % on a straight line at 22.5°); the taut path bends within about one cell of the
true shortest path's bends.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence

import numpy as np

#: Which segments ``a[i]``-``b[i]`` (n x 2 each, m) are free: ``PathPlanner.visible``.
Visible = Callable[[np.ndarray, np.ndarray], np.ndarray]

_SLIDE_SCALES = (4.0, 1.0, 0.25)  # cells: bends move coarse to fine
_ARC_ROUNDS = 3  # bends cut in two around rounded corners: up to 8 segments per arc
_ARC_TURN = math.radians(5.0)
_RELAX_PASSES = 40  # per scale; a bend moves at most this many steps
_OFFSETS = np.array([(math.cos(a), math.sin(a)) for a in np.arange(8) * math.pi / 4])


def pull_taut(pts: np.ndarray, visible: Visible, *, corner_radius_m: float,
              step_m: float) -> np.ndarray:
    """The polyline ``pts`` (k x 2, m) made taut: each vertex joined to the farthest one it
    sees, then each bend slid towards the line of its neighbours while both segments stay
    free (``visible(a, b)``: which segments a[i]-b[i] are free), a bend round a corner cut
    into an arc of ``corner_radius_m``; bends move in steps of ``step_m`` (the grid's cell)."""
    keep = [0]
    while keep[-1] < len(pts) - 1:
        i = keep[-1]
        later = np.unique(np.r_[np.arange(i + 1, len(pts), max(1, (len(pts) - i) // 48)),
                                len(pts) - 1])
        seen = later[visible(pts[i], pts[later])]
        keep.append(int(seen[-1]) if len(seen) else i + 1)
    path = _relax(pts[keep], _SLIDE_SCALES, visible, step_m)
    for _ in range(_ARC_ROUNDS):
        # A bend around a rounded corner: cut it into two, which then slide onto the arc.
        a, v, b = path[:-2], path[1:-1], path[2:]
        u = (v - a) / np.maximum(np.hypot(*(v - a).T), 1e-12)[:, None]
        w = (b - v) / np.maximum(np.hypot(*(b - v).T), 1e-12)[:, None]
        turn = np.arccos(np.clip((u * w).sum(axis=1), -1.0, 1.0))
        d = np.minimum(0.5 * np.minimum(np.hypot(*(v - a).T), np.hypot(*(b - v).T)),
                       corner_radius_m * np.tan(0.5 * turn))
        cut = np.zeros(len(v), dtype=bool)
        for _ in range(4):  # a chord outside the arc: halve the cut until free
            todo = ~cut & (turn > _ARC_TURN)
            if not todo.any():
                break
            free = np.zeros_like(cut)
            free[todo] = visible(v[todo] - u[todo] * d[todo, None],
                                      v[todo] + w[todo] * d[todo, None])
            cut |= free
            d = np.where(cut, d, 0.5 * d)
        if not cut.any():
            break
        pieces = [path[:1]]
        for i in range(len(v)):
            pieces.append(np.array([v[i] - u[i] * d[i], v[i] + w[i] * d[i]]) if cut[i]
                          else v[i:i + 1])
        pieces.append(path[-1:])
        path = _relax(np.vstack(pieces), _SLIDE_SCALES[-2:], visible, step_m)
    return path

def _relax(path: np.ndarray, scales: Sequence[float], visible: Visible,
           step_m: float) -> np.ndarray:
    """Bends moved, coarse steps to fine, where that shortens the path and keeps both
    their segments free (every other bend at once); a bend whose neighbours see each
    other is dropped."""
    path = path.copy()
    for scale in scales:
        for _ in range(_RELAX_PASSES):
            moved = False
            for parity in (1, 2):
                i = np.arange(parity, len(path) - 1, 2)
                if not len(i):
                    continue
                a, v, b = path[i - 1], path[i], path[i + 1]
                # Around the compass, and along each segment (which keeps that one free),
                # one and three steps.
                la, lb = np.hypot(*(v - a).T), np.hypot(*(b - v).T)
                la, lb = np.maximum(la, 1e-12), np.maximum(lb, 1e-12)
                dirs = np.concatenate([np.broadcast_to(_OFFSETS, (len(i), 8, 2)),
                                       ((a - v) / la[:, None])[:, None],
                                       ((b - v) / lb[:, None])[:, None]], axis=1)
                step = scale * step_m
                trial = v[:, None] + np.concatenate([step * dirs, 3 * step * dirs], axis=1)
                total = (np.hypot(*(trial - a[:, None]).transpose(2, 0, 1))
                         + np.hypot(*(trial - b[:, None]).transpose(2, 0, 1)))
                n, k = np.nonzero(total < (la + lb - 1e-9)[:, None])
                # One call: whether a sees b (the bend can go), then the trials' segments.
                ends = np.concatenate([b, trial[n, k], trial[n, k]])
                seen = visible(np.concatenate([a, a[n], b[n]]), ends)
                straight = seen[:len(i)]
                if straight.any():  # a straight segment needs no bend
                    path = np.delete(path, i[straight], axis=0)
                    moved = True
                    break
                ok = seen[len(i):len(i) + len(n)] & seen[len(i) + len(n):]
                if not ok.any():
                    continue
                best = np.full(total.shape, np.inf)
                best[n[ok], k[ok]] = total[n[ok], k[ok]]
                pick = np.argmin(best, axis=1)
                go = np.isfinite(best[np.arange(len(i)), pick])
                path[i[go]] = trial[np.flatnonzero(go), pick[go]]
                moved = True
            if not moved:
                break
    return path
