"""pic4rl_bridge: the Gymnasium navigation env over ROS 2 (or in process), its tasks, and
episode recording to rosbag2.

Importing the package registers the envs by string entry point and imports nothing heavy
(no rclpy, no MuJoCo): ``gymnasium.make("pic4rl/GoToPoseLidar-v0", config="config/x.yaml")``.
"""

from __future__ import annotations

from gymnasium.envs.registration import register, registry

_ENTRY_POINT = "pic4rl_bridge.env:NavEnv"
#: id → its task and sensor, and sim parameters for keys a config's sim section leaves unset.
ENV_IDS = {
    "pic4rl/GoToPoseLidar-v0": {"task": "goToPose", "sensor": "lidar"},
    "pic4rl/GoToPoseDepth-v0": {"task": "goToPose", "sensor": "depth",
                                "sim_defaults": {"depth.enabled": True}},
    "pic4rl/Vineyard-v0": {"task": "vineyard", "sensor": "depth",
                           "sim_defaults": {"world": "vineyard", "depth.enabled": True}},
    "pic4rl/PersonMonitoring-v0": {"task": "personMonitoring", "sensor": "lidar",
                                   "sim_defaults": {"robot": "omni", "world": "person"}},
}

for _id, _kwargs in ENV_IDS.items():
    if _id not in registry:
        register(id=_id, entry_point=_ENTRY_POINT, kwargs=_kwargs, nondeterministic=False)
