"""The engine's real-time factor, timed the one way the engine benchmarks share: ``Engine.step``
+ ``Engine.scan`` per control step (what the in-process transport does), a slow turn, several
engines interleaved, the best of ``repeat`` runs of each."""

from __future__ import annotations

import time
from collections.abc import Mapping

from pic4rl_sim.engine.core import Engine
from pic4rl_sim.engine.geometry import Twist2D


def rtf(engine: Engine, steps: int) -> float:
    """Simulated seconds per wall second over ``steps`` control steps (a slow turn)."""
    command = Twist2D(0.3, 0.0, 0.2)
    start = time.perf_counter()
    for _ in range(steps):
        engine.step(command)
        engine.scan()
    return steps * engine.config.control_dt_s / (time.perf_counter() - start)


def best_rtf(engines: Mapping[str, Engine], steps: int, repeat: int) -> dict[str, float]:
    """Each engine's best real-time factor over ``repeat`` interleaved runs, each from a reset
    with seed 0."""
    best = dict.fromkeys(engines, 0.0)
    for _ in range(repeat):
        for name, engine in engines.items():
            engine.reset(seed=0)
            best[name] = max(best[name], rtf(engine, steps))
    return best
