"""pic4rl_metrics: navigation metrics from rosbag2 bags alone.

Imports only rosbags, numpy, pandas, matplotlib (plus yaml and tqdm): judging real-robot bags
needs no ROS, MuJoCo or torch. Typical use::

    from pic4rl_metrics import compute
    frame = compute(["bags/run1"]).frame      # one row per bag, one column per metric
"""

from __future__ import annotations

from importlib import import_module
from typing import Any

#: Public name → the module that defines it, imported on first use (PEP 562): the sim imports
#: ``pic4rl_metrics.errors`` and ``pic4rl_metrics.geometry`` alone and must not pay for pandas
#: and rosbags.
_HOMES = {
    "BagResult": "batch", "MetricsResult": "batch", "compute": "batch", "judge_bag": "batch",
    "EpisodeFacts": "contract", "Outcome": "contract",
    "BagError": "errors", "ConfigError": "errors", "CorruptBagError": "errors",
    "EpisodeError": "errors",
    "MetricsError": "errors", "TopicError": "errors",
    "Footprint": "geometry", "Derived": "derived", "compute_metrics": "metrics",
    "read_episode": "reader",
    "METRICS": "registry", "REGISTRY": "registry", "Metric": "registry", "metric": "registry",
    "TABLE1_COLUMNS": "results", "EpisodeMetrics": "results", "Episode": "series",
    "TopicMap": "topics", "load_topic_map": "topics",
}


def __getattr__(name: str) -> Any:
    home = _HOMES.get(name)
    if home is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    if home == "registry":
        import_module(".metrics", __name__)  # the built-in metrics register on import
    value = getattr(import_module(f".{home}", __name__), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted({*globals(), *_HOMES})


__all__ = [
    "METRICS",
    "REGISTRY",
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
