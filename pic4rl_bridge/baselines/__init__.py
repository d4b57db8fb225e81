"""Baselines: the classical controllers ``pic4rl-test --baseline NAME`` runs like an agent,
and imitation's experts.

``registry`` (``BASELINES``, which task each drives, ``make_baseline``; the proportional
controller), ``config`` (the ``baselines:`` section: their settings), ``dwa`` (the Dynamic
Window Approach), ``planner`` (the privileged planner and its pursuit law), ``explorer`` (the
mapless explorer), ``follow`` (the person follower's heading law) and ``row_followers`` (the
vineyard's ``centerline`` and ``row_follower``). Names are imported on first use: the env's
``config`` reads ``config`` here before the controllers, which read the env's config, exist.
"""

from __future__ import annotations

from pic4rl_metrics.lazy import lazy_exports

_EXPORTS = {
    "Baseline": "registry", "BASELINES": "registry", "BASELINE_TASKS": "registry",
    "make_baseline": "registry", "check_fits": "registry",
    "BaselinesConfig": "config", "DwaConfig": "config", "PlannerConfig": "config",
    "ExplorerConfig": "config",
    "DwaController": "dwa", "PlannerController": "planner", "ExplorerController": "explorer",
    "HeadingController": "follow", "CenterlineFollower": "row_followers",
    "RowFollower": "row_followers",
}
__all__ = sorted(_EXPORTS)
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
