"""pic4rl_bridge: the Gymnasium navigation env over ROS 2 (or in process), its tasks, and
episode recording to rosbag2 as a wrapper any env can be wrapped in.

Importing the package registers the envs by string entry point and imports nothing heavy
(no rclpy, no MuJoCo): ``gymnasium.make("pic4rl/GoToPoseLidar-v0", config="config/x.yaml")``.
"""

from __future__ import annotations

from gymnasium.envs.registration import register, registry

from .settings.tasks import env_ids

#: ``NavEnv``, in ``RecordEpisodes`` when its ``record.enabled`` (``pic4rl_bridge.recording``).
_ENTRY_POINT = "pic4rl_bridge.recording:make_env"
#: id → its task and sensor, and sim parameters for keys a config's sim section leaves unset
#: (each task's entry in ``pic4rl_bridge.settings.tasks.TASKS``).
ENV_IDS = env_ids()

for _id, _kwargs in ENV_IDS.items():
    if _id not in registry:
        register(id=_id, entry_point=_ENTRY_POINT, kwargs=_kwargs, nondeterministic=False)
