"""The agents: SB3 training (``pic4rl-train``), testing against the classical baselines
(``pic4rl-test``), Optuna tuning (``pic4rl-tune``), benchmark suites (``pic4rl-bench``), and
``pic4rl-run``, which starts the sims beside a trainer or tester. DDPG, TD3, SAC and TQC carry
the paper's ε-greedy exploration; PPO explores through its own policy. docs/agents.md is the
guide.

One room a sub-package: ``models`` (the algorithms and networks), ``training``, ``testing``,
``tune``, ``suites`` (``pic4rl-bench``) and ``stack`` (``pic4rl-run stack``); what they share
stands here: the trainer's configuration (``config``), command-line overrides and
``--ros-args``, a run directory's layout (``rundir``), sim processes (``simproc``) and
``pic4rl-run`` (``run``), joining Ray.
"""
