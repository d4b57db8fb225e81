"""Gymnasium navigation env over ROS 2 and the navigation tasks (to be built: see the bridge issue)."""
