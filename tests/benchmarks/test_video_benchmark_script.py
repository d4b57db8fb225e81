"""``benchmarks/video_throughput.py`` runs end to end and ends with its figures.

Only the shape of the output is checked, never a speed: timings belong to the benchmark.
"""

from __future__ import annotations

import math

import pytest
from bench_helpers import read_results, run_benchmark

VIDEO = ("video_episode_s", "video_render_s", "video_realtime_factor",
         "video_matplotlib_per_frame_s", "video_vs_matplotlib_ratio")
ENV = ("env_step_us", "env_render_hook_ns", "env_render_hook_overhead",
       "env_render_tracking_overhead", "env_render_every_step_overhead")
BEFORE = ("env_steps_per_s_before_render", "env_steps_per_s_render_off",
          "env_render_off_overhead")


def test_the_benchmark_ends_with_one_result_line_per_figure() -> None:
    done = run_benchmark("video_throughput.py", "--episode-s", "3", "--repeat", "1",
                         "--steps", "50", "--rounds", "1")
    try:
        results = read_results(done.stdout, (*VIDEO, *ENV, *BEFORE))
    except AssertionError:  # no git history to compare against: the last three are absent
        results = read_results(done.stdout, (*VIDEO, *ENV))
    assert results["video_episode_s"] == 3
    assert results["video_realtime_factor"] == pytest.approx(3 / results["video_render_s"],
                                                             rel=0.01)
    assert all(math.isfinite(v) for v in results.values())
    assert results["env_step_us"] > 0 and results["env_render_hook_ns"] > 0
