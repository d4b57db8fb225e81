"""Result tables: bags judged into one row each, and what is computed and printed from those rows.

``batch`` judges many bags (``compute``), ``results`` names the columns, ``aggregate`` and
``paired`` compute per-agent and paired statistics, ``groups`` keeps tasks and world sets
apart (a table per group), ``protocol`` lays out a benchmark protocol's table (BARN's, the
paper's; ``compare --table`` and ``pic4rl-bench``), ``text`` and ``layouts`` render tables as
text, markdown, CSV, LaTeX or JSON.
"""

from __future__ import annotations

from pic4rl_base.lazy import lazy_exports

_HOMES = {
    "compute": "batch", "judge_bag": "batch", "BagResult": "batch", "MetricsResult":
    "batch", "aggregate": "aggregate", "TABLE1_COLUMNS": "results", "ROW_COLUMNS":
    "results", "METRIC_COLUMNS": "results", "paired_table": "paired", "render_paired":
    "paired", "grouped_paired": "paired", "render_groups": "groups", "render_episodes":
    "text", "render_comparison": "text", "FORMATS": "layouts", "LAYOUTS": "protocol",
    "protocol_cells": "protocol", "render_protocol": "protocol",
}
__getattr__, __dir__ = lazy_exports(__name__, _HOMES, namespace=globals())
__all__ = sorted(_HOMES)
