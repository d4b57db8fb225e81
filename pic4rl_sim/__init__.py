"""The MuJoCo simulation, in two parts kept apart: ``engine`` (worlds, robots, sensors,
stepping; mujoco and numpy, no ROS) and ``node`` (the ROS 2 node ``sim`` that publishes the
engine's state). ``params`` (the ``sim:`` parameters) and ``interfaces`` (the node's topics
and services) are pure data shared by both sides and by the bridge's transports."""
