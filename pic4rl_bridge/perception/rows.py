"""The vineyard's rows as the task and the row followers see them: centre lines and the row
being driven.

The vineyard task judges by a centre line, and the ``centerline`` baseline (its expert)
follows the same one: the world's lanes, or ``vineyard.centerline`` when the config gives one
(``centerlines``), and of those the lane nearest the start, oriented from it
(``row_centerline``).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from pic4rl_base.geometry import project
from pic4rl_sim.engine.geometry import polyline_length

from ..config import EnvConfig
from ..errors import ConfigError


def centerlines(config: EnvConfig,
                lanes: Sequence[Sequence[Sequence[float]]]) -> list[np.ndarray]:
    """The centre lines a vineyard env judges by: ``vineyard.centerline`` when the config gives
    one, else the world's ``lanes``; ``ConfigError`` when there are none or one is degenerate."""
    flat = config.vineyard.centerline
    chosen = [np.reshape(flat, (-1, 2))] if flat else list(lanes)
    out = [np.asarray(lane, dtype=np.float64).reshape(-1, 2) for lane in chosen]
    if not out:
        raise ConfigError("vineyard.centerline: [] is invalid when the world has no lanes; "
                          "expected x0, y0, x1, y1, ... or a vineyard world")
    for lane in out:
        if len(lane) < 2 or polyline_length(lane) <= 0:
            raise ConfigError(f"vineyard lane: {lane.tolist()!r} is invalid; expected two "
                              "or more points spanning a positive length")
    return out


def row_centerline(lanes: Sequence[np.ndarray], xy: Sequence[float]) -> np.ndarray:
    """The row being driven from ``xy``: the lane nearest it (n × 2, m), oriented from its end
    nearest ``xy``; the task's centre line and the centre-line follower's path."""
    start = np.asarray(xy, dtype=np.float64)
    lane = min(lanes, key=lambda line: abs(project(line, start)[1]))
    if np.hypot(*(lane[-1] - start)) < np.hypot(*(lane[0] - start)):
        lane = lane[::-1]
    return np.ascontiguousarray(lane)
