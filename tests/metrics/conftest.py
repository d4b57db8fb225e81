"""Fixtures shared by the metrics' tests."""

from __future__ import annotations

import math

import pandas as pd
import pytest
from metrics_helpers import result_row as _row

from pic4rl_metrics.tables.results import ERROR_COLUMN, ID_COLUMNS, METRIC_COLUMNS

NAN = math.nan


@pytest.fixture
def episodes() -> pd.DataFrame:
    """td3_lidar: 3 good (2 successes), one NaN path; sac%depth: 2 good (1 judged), 1 error."""
    rows = [
        _row("/bags/run1/ep1", "td3_lidar", success=1.0, clearance_time_s=10.0,
             path_length_m=5.0, lin_vel_mean_mps=0.5, obstacle_dist_min_m=0.3),
        _row("/bags/run1/ep2", "sac%depth", success=1.0, clearance_time_s=12.0,
             path_length_m=4.0, lin_vel_mean_mps=0.4, obstacle_dist_min_m=0.6),
        _row("/bags/run1/ep3", "td3_lidar", success=1.0, clearance_time_s=20.0,
             path_length_m=6.0, lin_vel_mean_mps=0.3, obstacle_dist_min_m=0.5),
        _row("/bags/run1/ep4", "sac%depth", success=NAN, clearance_time_s=14.0,
             path_length_m=6.0, lin_vel_mean_mps=0.2, obstacle_dist_min_m=0.4, outcome="unknown"),
        _row("/bags/run1/ep5", "sac%depth", error="BagError: truncated bag",
             clearance_time_s=1000.0),
        _row("/bags/run1/ep6", "td3_lidar", success=0.0, clearance_time_s=30.0,
             path_length_m=NAN, lin_vel_mean_mps=0.1, obstacle_dist_min_m=0.2,
             outcome="collision"),
    ]
    return pd.DataFrame(rows, columns=[*ID_COLUMNS, *METRIC_COLUMNS, ERROR_COLUMN])


@pytest.fixture(scope="session")
def bench_bags(tmp_path_factory: pytest.TempPathFactory):
    """A synthetic benchmark's real bags: 3 agents (dwa 50 %, planner 95 %, td3 80 % success)
    × 4 start–goal pairs × 2 runs, under ``<root>/run<r>/<agent>/episode_NNNN``."""
    from pic4rl_metrics.synthetic.synthetic_bench import write_benchmark

    root = tmp_path_factory.mktemp("bench") / "bags"
    write_benchmark(root, {"td3": 0.8, "dwa": 0.5, "planner": 0.95}, pairs=4, runs=2)
    return root
