"""Names of a result's columns: metrics (``registry.py``), the ids before them, the error.

Units are in the metric names. ``NaN`` means "cannot be computed from this bag" (no goal,
no scan, no footprint, ...), never zero.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from ..core.metrics import BUILTIN_COLUMNS
from ..core.registry import METRICS, METRIC_TABLE, TABLE_SECTIONS, EpisodeMetrics, Metric

if TYPE_CHECKING:
    import pandas as pd

__all__ = [
    "ERROR_COLUMN", "ID_COLUMNS", "METRICS", "METRIC_COLUMNS", "QUALITY_COLUMNS",
    "ROW_COLUMNS", "TABLE1_COLUMNS", "EpisodeMetrics", "Metric", "table_columns",
]

#: Columns of the paper's Table 1, in its order (each metric's ``table`` placement).
TABLE1_COLUMNS: tuple[str, ...] = METRIC_TABLE.table("paper")
#: The vineyard's columns: a comparison shows them after Table 1's when some episode has them.
ROW_COLUMNS: tuple[str, ...] = METRIC_TABLE.table("row")


def table_columns(table: pd.DataFrame) -> tuple[str, ...]:
    """The columns of the comparison tables' sections, in order (``TABLE_SECTIONS``): those of
    a section shown always, the others' when they hold a value in ``table`` (per episode, or
    aggregated: ``<metric>_mean``); a plugin's placed metric joins its section."""
    def has(name: str) -> bool:
        return any(c in table.columns and table[c].notna().any() for c in (name, f"{name}_mean"))
    return tuple(c for section, always in TABLE_SECTIONS.items() for c in METRIC_TABLE.table(section)
                 if always or has(c))


#: Columns a result DataFrame holds besides the metrics: where the row came from.
ID_COLUMNS: tuple[str, ...] = ("bag", "agent", "task", "world", "run", "episode", "pose_topic")
#: Column holding the error message of a bag that could not be judged ("" when none).
ERROR_COLUMN = "error"

#: pic4rl's own metric columns, in table order.
METRIC_COLUMNS: tuple[str, ...] = BUILTIN_COLUMNS
#: pic4rl's trajectory-quality columns: tables average them over successful episodes.
QUALITY_COLUMNS: frozenset[str] = frozenset(n for n in BUILTIN_COLUMNS if METRIC_TABLE.metrics[n].quality)
