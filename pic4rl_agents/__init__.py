"""The agents: SB3 training (``pic4rl-train``), testing against the classical baselines
(``pic4rl-test``), Optuna tuning (``pic4rl-tune``), benchmark suites (``pic4rl-bench``), and
``pic4rl-run``, which starts the sims beside a trainer or tester. DDPG, TD3, SAC and TQC carry
the paper's ε-greedy exploration; PPO explores through its own policy. docs/agents.md is the
guide.

One room a sub-package: ``models`` (the algorithms and networks), ``training``, ``testing``,
``tune``, ``suites`` (``pic4rl-bench``) and ``stack`` (``pic4rl-run stack``); what they share
has two rooms of its own: ``runs`` (a run's configuration, overrides, directory and console)
and ``launch`` (``pic4rl-run``, sim processes, ``--ros-args``, joining Ray). ``extractors``
stays here, the import path saved depth models name.
"""
