"""A ROS 2 navigation stack as the agent: a user's command (any ROS 2 process: a plain rclpy
node, a launch file) started in the cell's ROS domain beside the sim node, given each
episode's goal on ``goal_pose`` (a ``geometry_msgs/PoseStamped``, as RViz's goal tool sends
it), driving ``cmd_vel``; the episode is judged and recorded by the env as any agent's.

``spec`` (``StackSpec``: the suite's ``stack:`` key, checked when it is read), ``process``
(starting, waiting for and stopping the command's process group), ``driver`` (the transport
that takes the stack's commands instead of sending its own, and the episode loop).
"""
