"""Readings: what a step's sensors give, the shared types every room of the bridge reads.

``frame`` (``SensorFrame``: one step's decoded pose, twist, goal and readings; ``ScanData``),
``sensor_table`` (the frame's sensors in one table: each reading's name, sim topic, sensor
kind, how its message decodes and how the in-process engine reads it; ``build_frame``, which
both transports call), ``decode`` (messages → numpy) and ``cdr`` (a step's messages read
straight from their CDR bytes), ``uwb_goal`` (the goal from the robot's UWB anchors' ranges
alone). They sit in the bottom room with ``pic4rl_bridge.settings``:
perception, control, baselines and tasks read frames; the transports make them
(``tests/bridge/test_layers.py``). Pure numpy; names are imported on first use.
"""

from __future__ import annotations

from pic4rl_base.lazy import lazy_exports

_EXPORTS = {
    "SensorFrame": "frame", "ScanData": "frame",
    "READING_TABLE": "sensor_table", "BY_NAME": "sensor_table", "FrameSensor": "sensor_table",
    "build_frame": "sensor_table",
}
__all__ = sorted(_EXPORTS)
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
