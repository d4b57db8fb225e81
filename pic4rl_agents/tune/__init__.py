"""``pic4rl-tune``: hyperparameter search with Optuna (``search``), its search space
(``space``: RL Zoo's samplers, light: the algorithm table names them), a study's settings and
seeding (``settings``) and the summary written after every trial (``summary``).
"""

from pic4rl_base.lazy import homes_of, lazy_exports

_HOMES = homes_of({
    "search": ("create_study", "main", "objective", "optimize"),
    "space": ("Fixing", "sample_off_policy", "sample_ppo", "sample_td3"),
    "settings": ("TrialSeeded", "TuneSettings"),
    "summary": ("trials_table", "write_summary"),
})
__all__ = sorted(_HOMES)
__getattr__, __dir__ = lazy_exports(__name__, _HOMES)
