"""Reading bags: whatever a user names, opened as one stream of messages, read into an ``Episode``.

``inputs`` turns paths and globs into bags, ``bagfile`` opens any rosbag2 (any storage,
compressed, split) or ROS 1 bag, ``topics`` chooses the topics (the topic map), ``tf`` builds
poses from transform chains, ``reader`` reads one bag into an ``Episode`` (``core``). The one
bag writer (``bagwriter``: the recorder's and the synthetic bags') lives here too.
"""

from __future__ import annotations

from pic4rl_base.lazy import lazy_exports

_HOMES = {
    "OpenBag": "bagfile", "BagWriter": "bagwriter", "discover": "inputs", "read_episode":
    "reader", "TopicMap": "topics", "load_topic_map": "topics", "choose_topics": "topics",
    "chain_poses": "tf",
}
__getattr__, __dir__ = lazy_exports(__name__, _HOMES, namespace=globals())
__all__ = sorted(_HOMES)
