"""The bag contract: the names a recorder writes and the metrics read.

One rosbag2 per episode. Topics are recorded as on the wire (relative names resolve to
``/<name>``). Episode facts go to the metadata's ``custom_data`` (string values; structured
ones JSON-encoded) *and* to the ``episode/facts`` topic at the episode's start, so a bag whose
recorder was killed before writing ``metadata.yaml`` still carries them. The outcome is
published on ``episode/outcome`` when the episode ends, so its time is known.
"""

from __future__ import annotations

#: Default topics, as recorded by pic4rl's recorder (the sim node's names).
GROUND_TRUTH_TOPIC = "/ground_truth"
ODOM_TOPIC = "/odom"
SCAN_TOPIC = "/scan"
CMD_VEL_TOPIC = "/cmd_vel"
GOAL_TOPIC = "/goal_pose"
PERSON_TOPIC = "/person/pose"
CLOCK_TOPIC = "/clock"

#: ``std_msgs/msg/String`` whose ``data`` is a JSON object with the keys of ``FACT_KEYS``.
FACTS_TOPIC = "/episode/facts"
#: ``std_msgs/msg/String``; ``data`` is a JSON object ``{"outcome": "goal"|"collision"|"timeout",
#: "stamp_ns": <int, on the pose topic's header time base>}`` or just the outcome word.
OUTCOME_TOPIC = "/episode/outcome"

#: Keys of ``custom_data`` and of the facts JSON. Scalars are strings of numbers; ``start``
#: is ``[x, y, yaw]``, ``goal`` is ``[x, y]``, ``footprint`` is ``{"radius_m": r}`` or
#: ``{"length_m": l, "width_m": w}``, ``row_centerline`` is ``[[x, y], ...]`` (JSON).
FACT_KEYS = (
    "agent",
    "task",
    "world",
    "robot",
    "run",
    "episode",
    "seed",
    "footprint",
    "start",
    "goal",
    "goal_tolerance_m",
    "collision_tolerance_m",
    "safety_margin_m",
    "max_speed_mps",
    "row_centerline",
    "outcome",
)
