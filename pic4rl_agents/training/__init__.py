"""``pic4rl-train`` and what it trains with: the ``Trainer`` (``train``) and its command line
(``args``), the vectorised envs (``envs``), the curriculum, the SB3 callbacks (checkpoints,
seeded evaluations, stops), the progress bar, imitation from an expert, the reward and
evaluation curves (``python -m pic4rl_agents.training.curves``), the run's ``summary.yaml``
and the evaluations' videos.
"""

from pic4rl_base.lazy import homes_of, lazy_exports

_HOMES = homes_of({
    "train": ("Trainer", "main"),
    "args": ("build_parser", "resolve"),
    "envs": ("env_namespace", "eval_env_config", "make_vec_env"),
    "curriculum": ("Curriculum",),
    "callbacks": ("Checkpoints", "RewardCurveCallback", "SeededEvalCallback", "StopWhenSet",
                  "WallClockLimit"),
    "progress": ("ProgressCallback", "binding_budget"),
    "summary": ("session_summary",),
    "imitation": ("EXPERTS", "DecayingCloning", "Imitation", "make_expert"),
    "curves": ("episode_table", "eval_curves", "save_eval_curves", "save_reward_curve"),
    "videos": ("EvalVideoCallback",),
})
__all__ = sorted(_HOMES)
__getattr__, __dir__ = lazy_exports(__name__, _HOMES)
