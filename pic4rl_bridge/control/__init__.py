"""Control laws that the tasks and the baselines share, one layer above perception.

``actions`` (the normalised 2-D action ↔ a planar command: ``planar_command``,
``normalized_action``, ``planar_action_space``), ``pursuit`` (the pursuit law that the
privileged planner and the mapless explorer follow their plans with: ``pursuit_command``),
``following`` (the person follower's heading law: ``heading_rate``) and ``plugin`` (the
public policy plugin protocol: ``Policy``, ``TaskInfo``). They import settings,
shared types and perception only, never a baseline, task, transport or the env
(``tests/bridge/test_layers.py``). Names are imported on first use.
"""

from __future__ import annotations

from pic4rl_base.lazy import lazy_exports

_EXPORTS = {
    "planar_command": "actions", "normalized_action": "actions",
    "planar_action_space": "actions",
    "pursuit_command": "pursuit",
    "heading_rate": "following",
    "Policy": "plugin", "PolicyFailure": "plugin", "TaskInfo": "plugin",
    "check_policy": "plugin", "command_of": "plugin",
}
__all__ = sorted(_EXPORTS)
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
