"""Settings: the bridge's tables and sections that every room above reads, at the bottom.

``tasks`` (``TASK_TABLE``: each task's env ids, sensors, reward scales, section and experts;
``TaskName``, ``SensorName``, ``task_spec``, ``env_ids``, the tasks' sections),
``observations`` (each sensor's observation section: ``lidar:``, ``depth:``, ``memory:``) and
``baselines`` (the ``baselines:`` section: ``BaselinesConfig`` and each baseline's settings).
Pure dataclasses over ``pic4rl_base.schema``: they import the bridge's ``errors`` and nothing
above (``tests/bridge/test_layers.py``), so ``pic4rl_bridge.config`` builds the env's
configuration from them before any task or baseline exists. Names are imported on first use.
"""

from __future__ import annotations

from pic4rl_base.lazy import lazy_exports

_EXPORTS = {
    "TASK_TABLE": "tasks", "TaskSpec": "tasks", "TaskName": "tasks", "SensorName": "tasks",
    "task_spec": "tasks", "env_ids": "tasks", "EXPERT_TASKS": "tasks",
    "BaselinesConfig": "baselines", "DwaConfig": "baselines", "PlannerConfig": "baselines",
    "ExplorerConfig": "baselines",
    "LidarObsConfig": "observations", "DepthObsConfig": "observations",
    "MemoryObsConfig": "observations",
}
__all__ = sorted(_EXPORTS)
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
