"""pic4rl_metrics: navigation metrics from rosbag2 bags alone.

Imports only rosbags, numpy, pandas, matplotlib (plus yaml and tqdm): judging real-robot bags
needs no ROS, MuJoCo or torch. Typical use::

    from pic4rl_metrics import compute
    frame = compute(["bags/run1"]).frame      # one row per bag, one column per metric
"""

from __future__ import annotations

from .batch import BagResult, MetricsResult, compute, judge_bag
from .contract import EpisodeFacts, Outcome
from .errors import BagError, ConfigError, EpisodeError, MetricsError, TopicError
from .geometry import Footprint
from .derived import Derived
from .metrics import compute_metrics
from .reader import read_episode
from .registry import METRICS, REGISTRY, Metric, metric
from .results import TABLE1_COLUMNS, EpisodeMetrics
from .series import Episode
from .topics import TopicMap, load_topic_map

__all__ = [
    "METRICS",
    "REGISTRY",
    "TABLE1_COLUMNS",
    "BagError",
    "BagResult",
    "Derived",
    "ConfigError",
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
