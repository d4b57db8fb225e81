"""pic4rl_metrics: navigation metrics from rosbag2 bags alone.

Imports only rosbags, numpy, pandas, matplotlib (plus yaml and tqdm): judging real-robot bags
needs no ROS, MuJoCo or torch. Typical use::

    from pic4rl_metrics import compute
    frame = compute(["bags/run1"]).frame      # one row per bag, one column per metric
"""

from __future__ import annotations

from importlib import import_module

from pic4rl_base.lazy import lazy_exports

#: Public name → the module that defines (or, for the base's ``Footprint``, carries) it,
#: imported on first use (PEP 562): ``import pic4rl_metrics`` for its errors alone must not pay
#: for pandas and rosbags.
_HOMES = {
    "BagResult": "tables.batch", "MetricsResult": "tables.batch", "compute": "tables.batch",
    "judge_bag": "tables.batch",
    "EpisodeFacts": "contract", "Outcome": "contract",
    "BagError": "errors", "ConfigError": "errors", "CorruptBagError": "errors",
    "EpisodeError": "errors",
    "MetricsError": "errors", "TopicError": "errors",
    "Footprint": "contract", "Derived": "core.derived", "compute_metrics": "core.metrics",
    "read_episode": "bags.reader",
    "METRICS": "core.registry", "METRIC_TABLE": "core.registry", "Metric": "core.registry",
    "metric": "core.registry",
    "TABLE1_COLUMNS": "tables.results", "EpisodeMetrics": "tables.results",
    "Episode": "core.series",
    "TopicMap": "bags.topics", "load_topic_map": "bags.topics",
}


def _builtins_first(home: str) -> None:
    if home == "core.registry":
        import_module(".core.metrics", __name__)  # the built-in metrics register on import


__getattr__, __dir__ = lazy_exports(__name__, _HOMES, namespace=globals(), before=_builtins_first)

__all__ = [
    "METRICS",
    "METRIC_TABLE",
    "TABLE1_COLUMNS",
    "BagError",
    "BagResult",
    "Derived",
    "ConfigError",
    "CorruptBagError",
    "Episode",
    "EpisodeError",
    "EpisodeFacts",
    "EpisodeMetrics",
    "Footprint",
    "Metric",
    "MetricsError",
    "MetricsResult",
    "Outcome",
    "TopicError",
    "TopicMap",
    "compute",
    "compute_metrics",
    "judge_bag",
    "load_topic_map",
    "metric",
    "read_episode",
]
