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
#: ``std_msgs/msg/String``; ``data`` is a JSON object ``{"outcome": "goal"|"collision"|"timeout"|"diverged",
#: "stamp_ns": <int, on the pose topic's header time base>}`` or just the outcome word.
OUTCOME_TOPIC = "/episode/outcome"
#: ``tf2_msgs/msg/TFMessage``: a real bag's static transforms, where the LiDAR's mount is read
#: when the facts carry no ``scan_mount``.
TF_STATIC_TOPIC = "/tf_static"

#: Keys of ``custom_data`` and of the facts JSON. Scalars are strings of numbers; ``start``
#: is ``[x, y, yaw]``, ``goal`` is ``[x, y]``, ``footprint`` is ``{"radius_m": r}`` or
#: ``{"length_m": l, "width_m": w}``, ``row_centerline`` is ``[[x, y], ...]`` (JSON).
#: ``shortest_path_m`` is the shortest collision-free start-goal path of a simulated episode and
#: ``straight_line_m`` the straight start-goal distance (m); ``scan_mount`` is the LiDAR's pose
#: in the base frame, ``{"x_m": x, "y_m": y, "yaw_rad": yaw}``.
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
    "shortest_path_m",
    "straight_line_m",
    "scan_mount",
    "outcome",
)
