"""The agents: SB3 training (``pic4rl-train``), testing against the classical baselines
(``pic4rl-test``), Optuna tuning (``pic4rl-tune``), and ``pic4rl-run``, which starts the sims
beside a trainer or tester. DDPG, TD3, SAC and TQC carry the paper's ε-greedy exploration; PPO
explores through its own policy. docs/agents.md is the guide.
"""
