"""A user's task, its entry in pic4rl's task table: escape, get 1 m away from where the
episode starts without touching anything, seen through the LiDAR. The entry names its code by
string (``escape:build``), as pic4rl's own entries do, so that the table loads without it; the
``pic4rl.tasks`` entry point of ``pyproject.toml`` beside it names ``SPEC``."""

from dataclasses import dataclass

from pic4rl_base.schema import param
from pic4rl_bridge.settings.tasks import CommonReward, EnvId, TaskSpec


@dataclass(frozen=True)
class EscapeReward(CommonReward):
    away: float = param(10.0, doc="escape: times the gain in distance from the start (m)")
    escaped: float = param(100.0, doc="escape: getting 1 m away from the start")


SPEC = TaskSpec("escape", (EnvId("places/Escape-v0", "lidar"),), sensors=("lidar",),
                reward=EscapeReward, build="escape:build")
