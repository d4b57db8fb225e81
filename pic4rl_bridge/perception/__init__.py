"""Perception: what the tasks and baselines make of a frame's readings.

``collision`` (scan and depth image → points, the footprint's clearance, the step's safety),
``observations`` (the encoders: LiDAR sectors, the depth image, the target in polar
coordinates, and their spaces), ``sensor_parts`` (each observable sensor's part: its
readings, observation and obstacle points), ``occupancy`` (the rolling occupancy grid of the robot's
own scans: the memory observation's and the explorer's, whose plan on it is a planner's:
``pic4rl_bridge.baselines.explorer_plan``), ``rows`` (the vineyard's centre lines, the
row being driven), ``frontiers`` (the explore task's seen grid and frontiers) and ``movers``
(moving obstacles tracked from the scan against a known map). Pure numpy; names are imported
on first use.
"""

from __future__ import annotations

from pic4rl_base.lazy import lazy_exports

_EXPORTS = {
    "assess": "collision", "Safety": "collision", "sensed_points": "collision",
    "obstacle_distance": "collision", "depth_points": "collision", "depth_scan": "collision",
    "lidar_sectors": "observations", "depth_observation": "observations",
    "depth_space": "observations", "target_polar": "observations",
    "clipped_action": "observations",
    "SensorPart": "sensor_parts", "observable": "sensor_parts",
    "OccupancyGrid": "occupancy", "sensed_scans": "occupancy",
    "centerlines": "rows", "row_centerline": "rows",
    "MoverTracker": "movers",
}
__all__ = sorted(_EXPORTS)
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
