"""Names of a result's columns: metrics (``registry.py``), the ids before them, the error.

Units are in the metric names. ``NaN`` means "cannot be computed from this bag" (no goal,
no scan, no footprint, ...), never zero.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from ..core.metrics import BUILTIN_COLUMNS
from ..core.registry import METRICS, REGISTRY, EpisodeMetrics, Metric

if TYPE_CHECKING:
    import pandas as pd

__all__ = [
    "ERROR_COLUMN", "ID_COLUMNS", "METRICS", "METRIC_COLUMNS", "QUALITY_COLUMNS",
    "ROW_COLUMNS", "TABLE1_COLUMNS", "EpisodeMetrics", "Metric", "table_columns",
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

#: The vineyard's columns: a comparison shows them after Table 1's when some episode has them.
ROW_COLUMNS: tuple[str, ...] = ("row_path_mae_m", "row_path_mse_m2")


def table_columns(table: pd.DataFrame) -> tuple[str, ...]:
    """Table 1's columns, then ``ROW_COLUMNS`` that hold a value in ``table`` (per episode,
    or aggregated: ``<metric>_mean``)."""
    def has(name: str) -> bool:
        return any(c in table.columns and table[c].notna().any() for c in (name, f"{name}_mean"))
    return TABLE1_COLUMNS + tuple(c for c in ROW_COLUMNS if has(c))


#: Columns a result DataFrame holds besides the metrics: where the row came from.
ID_COLUMNS: tuple[str, ...] = ("bag", "agent", "task", "world", "run", "episode", "pose_topic")
#: Column holding the error message of a bag that could not be judged ("" when none).
ERROR_COLUMN = "error"

#: pic4rl's own metric columns, in table order.
METRIC_COLUMNS: tuple[str, ...] = BUILTIN_COLUMNS
#: pic4rl's trajectory-quality columns: tables average them over successful episodes.
QUALITY_COLUMNS: frozenset[str] = frozenset(n for n in BUILTIN_COLUMNS if REGISTRY.metrics[n].quality)
