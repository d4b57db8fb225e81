"""Tasks: observation, reward and termination as pure functions of decoded sensor data.

``registry`` (``TASKS``: each task's env ids, sensors, reward scales, section and baselines;
``TaskName``, ``task_spec``), ``base`` (``Task``, ``EpisodeContext``, ``Judgement``,
``make_task``) and one module per task: ``goto``, ``person``, ``vineyard``. Names are imported
on first use: the env's ``config`` reads ``registry`` before the tasks, which read the config,
exist.
"""

from __future__ import annotations

from pic4rl_metrics.lazy import lazy_exports

_EXPORTS = {
    "TASKS": "registry", "TaskSpec": "registry", "TaskName": "registry",
    "task_spec": "registry", "env_ids": "registry",
    "Task": "base", "EpisodeContext": "base", "Judgement": "base", "make_task": "base",
}
__all__ = sorted(_EXPORTS)
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
