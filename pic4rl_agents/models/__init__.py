"""What an agent is: the algorithm table (each algorithm's SB3 class, off-policy flag, tune
sampler and keyword groups), their SB3 classes with atomic saves and the paper's ε-greedy,
a new model from a ``TrainConfig`` (``new_model``) or a saved one (``load_model``), and the
networks (``DepthGoalExtractor``). Only ``algorithm_table`` is light; the rest load torch.
"""

from pic4rl_base.lazy import homes_of, lazy_exports

_HOMES = homes_of({
    "algorithm_table": ("ALGORITHM_TABLE", "AlgorithmEntry"),
    "algorithms": ("ALGORITHMS", "algorithm_class", "check_spaces", "describe_space",
                   "load_model", "new_model"),
    "action_noise": ("EpsilonGreedy", "epsilon_at"),
    "extractors": ("DepthGoalExtractor",),
})
__all__ = sorted(_HOMES)
__getattr__, __dir__ = lazy_exports(__name__, _HOMES)
