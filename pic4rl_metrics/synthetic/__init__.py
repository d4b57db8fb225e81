"""Bags with known metrics, for tests and benchmarks: tracks and worlds with analytic answers
(``synthetic_tracks``) and people (``synthetic_crowd``), episode bags written from them
(``synthetic``) and a benchmark's bags, agents × pairs × runs at chosen success rates
(``synthetic_bench``). Test support, not a recorder.
"""

from __future__ import annotations

from pic4rl_base.lazy import lazy_exports

_HOMES = {
    "write_episode_bag": "synthetic", "write_long_bag": "synthetic", "write_benchmark":
    "synthetic_bench", "Track": "synthetic_tracks", "Obstacles": "synthetic_tracks",
    "straight_line": "synthetic_tracks", "circle": "synthetic_tracks", "from_waypoints":
    "synthetic_tracks", "standing": "synthetic_crowd",
}
__getattr__, __dir__ = lazy_exports(__name__, _HOMES, namespace=globals())
__all__ = sorted(_HOMES)
