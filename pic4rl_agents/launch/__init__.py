"""Processes beside the agents: ``pic4rl-run`` (``run``: sims beside a trainer or tester), sim
nodes as child processes that die with their parent and the ROS domain a cell holds
(``simproc``), the ``--ros-args`` part of a command line (``rosargs``) and joining Ray
(``raycluster``)."""
