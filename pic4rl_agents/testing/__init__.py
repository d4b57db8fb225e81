"""``pic4rl-test``: what a test is (``plan``: a ``TestPlan``, the agents and baselines it
names, each with its test env), doing it (``tester``: every agent drives the same episodes
into bags, then one metrics table from the bags; ``drive_and_judge`` from Python) and what
drives an episode (``policies``: a model, a baseline, a policy plugin or a TorchScript file).
"""

from pic4rl_base.lazy import homes_of, lazy_exports

_HOMES = homes_of({
    "plan": ("AgentSpec", "DEFAULT_PAIRS", "TestPlan", "resolve_agents"),
    "tester": ("TestResult", "drive_agent", "drive_and_judge", "main"),
    "policies": ("Driver", "is_plugin", "load_plugin"),
})
__all__ = sorted(_HOMES)
__getattr__, __dir__ = lazy_exports(__name__, _HOMES)
