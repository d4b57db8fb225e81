"""MuJoCo simulation engine and the ROS 2 ``sim`` node (to be built: see the sim issue)."""
