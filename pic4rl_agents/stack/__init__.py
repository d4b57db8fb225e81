"""A ROS 2 navigation stack as the agent: a user's command (any ROS 2 process: a plain rclpy
node, a launch file) started in the cell's ROS domain beside the sim node, given each
episode's goal on ``goal_pose`` (a ``geometry_msgs/PoseStamped``, as RViz's goal tool sends
it), driving ``cmd_vel``; the episode is judged and recorded by the env as any agent's.

``spec`` (``StackSpec``: the ``stack:`` key, checked when it is read),
``driver`` (the command's process group, the transport that relays the stack's commands, the
episode loop), ``cli`` (``pic4rl-run stack``).
"""
