"""The simulation without ROS: robots as data (``robot_specs``) and worlds (the ``worlds``
sub-package), the MuJoCo model built from them, sensors by ray casting, start/goal sampling and
shortest paths, and ``core.Engine`` stepping it all. Importing a module here never loads
rclpy; names are imported on first use, so importing the package loads no MuJoCo."""

from __future__ import annotations

from pic4rl_base.lazy import lazy_exports

_EXPORTS = {
    "Engine": "core", "StepResult": "core", "limit_command": "core",
    "EngineConfig": "engine_config", "Twist2D": "geometry",
    "Drive": "robot_specs", "RobotSpec": "robot_specs", "load_robot": "robot_specs",
    "SENSOR_TABLE": "sensors", "sample_start_goal": "sampling",
}
__all__ = sorted(_EXPORTS)
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
