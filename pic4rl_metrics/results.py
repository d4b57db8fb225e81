"""Names of a result's columns: metrics (``registry.py``), the ids before them, the error.

Units are in the metric names. ``NaN`` means "cannot be computed from this bag" (no goal,
no scan, no footprint, ...), never zero.
"""

from __future__ import annotations

from .metrics import BUILTIN_COLUMNS
from .registry import METRICS, REGISTRY, EpisodeMetrics, Metric

__all__ = [
    "ERROR_COLUMN", "ID_COLUMNS", "METRICS", "METRIC_COLUMNS", "QUALITY_COLUMNS",
    "TABLE1_COLUMNS", "EpisodeMetrics", "Metric",
]

#: Columns of the paper's Table 1, in its order.
TABLE1_COLUMNS: tuple[str, ...] = (
    "success",
    "clearance_time_s",
    "heading_error_mean_rad",
    "path_length_m",
    "distance_path_ratio",
    "lin_vel_mean_mps",
    "ang_vel_std_radps",
    "lin_acc_max_mps2",
    "yaw_acc_max_radps2",
    "obstacle_dist_min_m",
    "obstacle_dist_mean_m",
)

#: Columns a result DataFrame holds besides the metrics: where the row came from.
ID_COLUMNS: tuple[str, ...] = ("bag", "agent", "task", "world", "run", "episode", "pose_topic")
#: Column holding the error message of a bag that could not be judged ("" when none).
ERROR_COLUMN = "error"

#: pic4rl's own metric columns, in table order.
METRIC_COLUMNS: tuple[str, ...] = BUILTIN_COLUMNS
#: pic4rl's trajectory-quality columns: tables average them over successful episodes.
QUALITY_COLUMNS: frozenset[str] = frozenset(n for n in BUILTIN_COLUMNS if REGISTRY.metrics[n].quality)
