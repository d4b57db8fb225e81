"""The simulation without ROS: robots as data (``robot_specs``) and worlds (the ``worlds``
sub-package), the MuJoCo model built from them, sensors by ray casting, start/goal sampling and
shortest paths, and ``core.Engine`` stepping it all. Importing a module here never loads
rclpy; importing this package loads nothing (its modules are imported by name)."""
