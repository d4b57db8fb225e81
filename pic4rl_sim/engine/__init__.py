"""The simulation without ROS: worlds and robots as data, the MuJoCo model built from them,
sensors by ray casting, start/goal sampling and shortest paths, and ``core.Engine`` stepping
it all. Importing a module here never loads rclpy."""
