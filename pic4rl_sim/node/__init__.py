"""The ROS 2 node ``sim`` (``sim_node``) and the messages it fills (``messages``): the only
modules of pic4rl_sim that import rclpy. ``python -m pic4rl_sim.node`` runs the node."""
