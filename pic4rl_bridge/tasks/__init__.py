"""Tasks: observation, reward and termination as pure functions of decoded sensor data.

``base`` (``Task``, ``EpisodeContext``, ``Judgement``, ``make_task``) and one module per task:
``goto``, ``person``, ``vineyard``. Their table (``TASK_TABLE``: each task's env ids, sensors,
reward scales, section and experts) is a setting, one room lower:
``pic4rl_bridge.settings.tasks``. Names are imported on first use.
"""

from __future__ import annotations

from pic4rl_base.lazy import lazy_exports

_EXPORTS = {
    "Task": "base", "EpisodeContext": "base", "Judgement": "base", "make_task": "base",
}
__all__ = sorted(_EXPORTS)
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
