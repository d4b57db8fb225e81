"""``pic4rl-bench``: benchmark suites of agents and baselines (not the speed scripts of
``benchmarks/``): the suite file and its cells (``suite``), one resumable cell (``cell``), the
cells on a process pool or Ray and the command (``runner``), and the suite's table,
leaderboards and report from its bags (``table``).
"""

from pic4rl_base.lazy import homes_of, lazy_exports

_HOMES = homes_of({
    "suite": ("Cell", "PairSet", "Suite", "load_suite"),
    "cell": ("drive_cell",),
    "runner": ("bench_suite", "main"),
    "table": ("SuiteTable", "write_results"),
})
__all__ = sorted(_HOMES)
__getattr__, __dir__ = lazy_exports(__name__, _HOMES)
