"""The math: an episode as data and the metrics computed from it, with no file, plot or CLI.

The ``Episode`` (``series``, its series' kinds in ``series_kinds``), the input roles that fill it
(``roles``), the time base (``timebase``), what no robot does (``plausibility``: implausible
speeds, a pose stream of two tracks) and per-scan summary (``scan_summary``), crop-lane
fits (``crop_rows``), math on series (``kinematics``), what metrics share (``derived``), the
metric registry (``registry``) and the built-in metrics (``metrics``, ``tasks.person``).
Imports nothing of ``bags``, ``tables``, ``viz`` or ``cli`` (``tests/test_architecture.py``).
"""

from __future__ import annotations

from importlib import import_module

from pic4rl_base.lazy import lazy_exports

_HOMES = {
    "Episode": "series", "PoseSeries": "series_kinds", "ScanSeries": "series_kinds",
    "CmdSeries": "series_kinds", "PointSeries": "series_kinds", "ROLE_TABLE": "roles", "Role":
    "roles", "Derived": "derived", "METRIC_TABLE": "registry", "METRICS": "registry", "Metric":
    "registry", "EpisodeMetrics": "registry", "metric": "registry", "compute_metrics":
    "metrics", "fit_lane": "crop_rows",
}


def _builtins_first(home: str) -> None:
    if home == "registry":
        import_module(".metrics", __name__)  # the built-in metrics register on import


__getattr__, __dir__ = lazy_exports(__name__, _HOMES, namespace=globals(), before=_builtins_first)
__all__ = sorted(_HOMES)
