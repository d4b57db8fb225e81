"""Baselines: the classical controllers ``pic4rl-test --baseline NAME`` runs like an agent,
and imitation's experts.

``registry`` (``BASELINES``, which task each drives, ``make_baseline``, ``make_expert``; the
proportional controller), ``dwa`` (the Dynamic Window Approach), ``planner`` (the privileged
planner), ``explorer`` (the mapless explorer) with ``explorer_plan`` (its plan on the grid of
its own scans, which ``goal_input: explorer`` points along too), ``follow`` (the person
follower's DWA and heading controller) and ``row_followers`` (the vineyard's ``centerline``
and ``row_follower``). Their settings (the ``baselines:`` section) are one room lower,
``pic4rl_bridge.settings.baselines``; the laws they share with the tasks are in
``pic4rl_bridge.control``. Names are imported on first use.
"""

from __future__ import annotations

from pic4rl_base.lazy import lazy_exports

_EXPORTS = {
    "Baseline": "registry", "BASELINES": "registry", "BASELINE_TASKS": "registry",
    "make_baseline": "registry", "check_fits": "registry", "make_expert": "registry",
    "EXPERT_BASELINES": "registry",
    "DwaController": "dwa", "PlannerController": "planner", "ExplorerController": "explorer",
    "ExplorerPlan": "explorer_plan", "HeadingController": "follow",
    "CenterlineFollower": "row_followers", "RowFollower": "row_followers",
}
__all__ = sorted(_EXPORTS)
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
