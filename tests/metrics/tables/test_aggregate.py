"""``aggregate``: per-agent means, stds and success counts of small hand-built result frames."""

from __future__ import annotations

import json
import math

import pandas as pd
import pytest
from metrics_helpers import result_row as _row

from pic4rl_base.errors import ConfigError
from pic4rl_metrics.tables.aggregate import UNKNOWN_GROUP, aggregate
from pic4rl_metrics.tables.results import ERROR_COLUMN
from pic4rl_metrics.tables.text import render_comparison

NAN = math.nan


# --- aggregate ------------------------------------------------------------------------------


def test_aggregate_means_and_sample_stds(episodes: pd.DataFrame) -> None:
    agg = aggregate(episodes, over="all")
    td3, sac = agg.loc["td3_lidar"], agg.loc["sac%depth"]
    assert td3["clearance_time_s_mean"] == pytest.approx(20.0)
    assert td3["clearance_time_s_std"] == pytest.approx(10.0)  # ddof=1 of 10, 20, 30
    assert td3["path_length_m_mean"] == pytest.approx(5.5)  # NaN skipped
    assert td3["path_length_m_std"] == pytest.approx(math.sqrt(0.5))
    assert sac["clearance_time_s_mean"] == pytest.approx(13.0)  # error row's 1000 left out
    assert sac["clearance_time_s_std"] == pytest.approx(math.sqrt(2.0))
    assert sac["success_mean"] == pytest.approx(1.0)
    assert math.isnan(td3["spl_mean"]) and math.isnan(td3["spl_std"])
    assert "outcome_mean" not in agg.columns and "n_poses_mean" in agg.columns


def test_aggregate_success_counts(episodes: pd.DataFrame) -> None:
    agg = aggregate(episodes)
    assert agg.loc["td3_lidar", "success"] == "2/3"
    assert agg.loc["sac%depth", "success"] == "1/1"  # unknown outcome is not judged
    assert agg.loc["td3_lidar", ["n_episodes", "n_judged", "n_success"]].tolist() == [3, 3, 2]
    assert agg.loc["sac%depth", ["n_episodes", "n_judged", "n_success"]].tolist() == [2, 1, 1]


def test_aggregate_excludes_and_counts_error_rows(episodes: pd.DataFrame) -> None:
    agg = aggregate(episodes)
    assert agg["n_failed"].to_dict() == {"td3_lidar": 0, "sac%depth": 1}
    only_failed = aggregate(episodes[episodes[ERROR_COLUMN] != ""])
    assert only_failed.loc["sac%depth", "n_episodes"] == 0
    assert only_failed.loc["sac%depth", "success"] == "–"
    assert math.isnan(only_failed.loc["sac%depth", "clearance_time_s_mean"])


def test_aggregate_keeps_first_appearance_order(episodes: pd.DataFrame) -> None:
    assert list(aggregate(episodes).index) == ["td3_lidar", "sac%depth"]
    assert list(aggregate(episodes.iloc[::-1]).index) == ["td3_lidar", "sac%depth"]
    assert list(aggregate(episodes.iloc[1:]).index) == ["sac%depth", "td3_lidar"]
    assert aggregate(episodes).index.name == "agent"


def test_aggregate_single_episode_has_nan_std() -> None:
    df = pd.DataFrame([_row("/b/x/ep", "a", success=1.0, clearance_time_s=7.0)])
    agg = aggregate(df)
    assert agg.loc["a", "clearance_time_s_mean"] == 7.0
    assert math.isnan(agg.loc["a", "clearance_time_s_std"])


def test_aggregate_missing_agent_falls_back_to_run_then_unknown() -> None:
    df = pd.DataFrame(
        [
            _row("/real/a", None, run="lab_2024", success=1.0),
            _row("/real/b", NAN, run="lab_2024", success=0.0),
            _row("/real/c", None, run=None, success=1.0),
            _row("/sim/d", "td3", success=1.0),
        ]
    )
    agg = aggregate(df)
    assert list(agg.index) == ["lab_2024", UNKNOWN_GROUP, "td3"]
    assert agg.loc["lab_2024", "success"] == "1/2"


def test_aggregate_by_several_columns(episodes: pd.DataFrame) -> None:
    episodes.loc[episodes.index[-1], "world"] = "outdoor"
    agg = aggregate(episodes, by=["agent", "world"])
    assert agg.index.names == ["agent", "world"]
    assert list(agg.index) == [
        ("td3_lidar", "indoor"), ("sac%depth", "indoor"), ("td3_lidar", "outdoor"),
    ]
    assert agg.loc[("td3_lidar", "indoor"), "success"] == "2/2"


def test_aggregate_unknown_column_suggests(episodes: pd.DataFrame) -> None:
    with pytest.raises(ConfigError, match=r"by='agnet'.*did you mean 'agent'"):
        aggregate(episodes, by="agnet")


def test_aggregate_averages_trajectory_quality_over_successes_by_default(
    episodes: pd.DataFrame,
) -> None:
    """td3_lidar: two successes (10 s, 5 m; 20 s, 6 m) and a collision (30 s, no path): the
    trajectory columns average the two successes, success, collisions and SPL all three."""
    mixed = episodes.assign(spl=[0.8, 0.9, 0.6, NAN, NAN, 0.0], collision_count=[0, 0, 0, 0, 0, 1])
    agg = aggregate(mixed)
    td3 = agg.loc["td3_lidar"]
    assert td3["success"] == "2/3" and td3["n_success"] == 2 and td3["n_collision"] == 1
    assert td3["n_timeout"] == 0 and td3["n_diverged"] == 0
    assert td3["over"] == "success" and td3["n_averaged"] == 2
    assert td3["clearance_time_s_mean"] == pytest.approx(15.0)
    assert td3["clearance_time_s_std"] == pytest.approx(math.sqrt(50.0))
    assert td3["path_length_m_mean"] == pytest.approx(5.5)
    assert td3["lin_vel_mean_mps_mean"] == pytest.approx(0.4)
    assert td3["obstacle_dist_min_m_mean"] == pytest.approx(0.4)
    assert td3["spl_mean"] == pytest.approx((0.8 + 0.6 + 0.0) / 3)  # over all three
    assert td3["collision_count_mean"] == pytest.approx(1 / 3)
    everything = aggregate(mixed, over="all").loc["td3_lidar"]
    assert everything["clearance_time_s_mean"] == pytest.approx(20.0)
    assert everything["n_averaged"] == 3 and everything["spl_mean"] == td3["spl_mean"]
    sac = agg.loc["sac%depth"]  # one success, one unknown: only the success is averaged
    assert sac["n_averaged"] == 1 and sac["clearance_time_s_mean"] == pytest.approx(12.0)
    table = render_comparison(agg, "table")
    assert "time, cum. heading, path, dist/path, v mean" in table
    assert "successful episodes only (n = 2, 1)" in table and "--over all" in table
    assert "| td3_lidar | 2/3 | 15.00 |" in render_comparison(agg, "markdown")
    with pytest.raises(ConfigError, match="over='some'"):
        aggregate(mixed, over="some")


def test_aggregate_counts_diverged_episodes_apart(episodes: pd.DataFrame) -> None:
    """A diverged episode is no success and no collision: counted in n_diverged, judged."""
    diverged = episodes.assign(
        outcome=["goal", "goal", "diverged", "unknown", None, "collision"],
        success=[1.0, 1.0, 0.0, NAN, NAN, 0.0],
    )
    td3 = aggregate(diverged).loc["td3_lidar"]
    assert td3["success"] == "1/3" and td3["n_diverged"] == 1 and td3["n_collision"] == 1
    assert td3["n_averaged"] == 1 and td3["clearance_time_s_mean"] == pytest.approx(10.0)


def test_aborted_episodes_are_counted_apart_and_out_of_the_success_rate(
        episodes: pd.DataFrame) -> None:
    """Cut short with no outcome: in n_aborted, not judged, unless count_aborted."""
    cut = episodes.assign(
        outcome=["goal", "timeout", "aborted", "unknown", None, "collision"],
        success=[1.0, 0.0, NAN, NAN, NAN, 0.0],
    )
    td3 = aggregate(cut).loc["td3_lidar"]
    assert td3["success"] == "1/2" and td3["n_aborted"] == 1 and td3["n_collision"] == 1
    counted = aggregate(cut, count_aborted=True).loc["td3_lidar"]
    assert counted["success"] == "1/3" and counted["n_aborted"] == 1
    assert counted["success_mean"] == pytest.approx(1 / 3)
    text = render_comparison(aggregate(cut), "markdown")
    assert ("Aborted (cut short: no outcome recorded, or a sensor went silent): n = 1, 0"
            in text)


# --- Wilson interval --------------------------------------------------------------------------


@pytest.mark.parametrize(("k", "n", "low", "high"), [
    (8, 10, 0.4901624715, 0.9433178485),  # statsmodels proportion_confint(8, 10, method="wilson")
    (0, 5, 0.0, 0.4344824648),
    (5, 5, 0.5655175352, 1.0),
    (1, 2, 0.0945312057, 0.9054687943),
])
def test_wilson_interval_matches_the_score_interval(k: int, n: int, low: float,
                                                     high: float) -> None:
    from pic4rl_metrics.tables.aggregate import wilson_interval

    got = wilson_interval(k, n)
    assert got == pytest.approx((low, high), abs=1e-9)
    # by hand: the score interval's bounds solve |p - p_hat| = z sqrt(p (1 - p) / n)
    z = 1.959963984540054
    for p in got:
        if 0.0 < p < 1.0:
            assert abs(p - k / n) == pytest.approx(z * math.sqrt(p * (1 - p) / n), abs=1e-9)


def test_wilson_interval_of_nothing_is_nan() -> None:
    from pic4rl_metrics.tables.aggregate import wilson_interval

    assert all(math.isnan(v) for v in wilson_interval(0, 0))


def test_collisions_count_the_episodes_with_a_collision(episodes: pd.DataFrame) -> None:
    """Collision events 0, 3, 1 (td3_lidar) and 2, 0 (sac%depth): the comparison's
    collisions are the episodes with one (2 and 1), not the mean events per episode (4/3);
    the outcome counts shown first are episode counts."""
    counted = episodes.assign(collision_count=[0, 2, 3, 0, NAN, 1])  # in row order
    agg = aggregate(counted)
    assert agg.loc["td3_lidar", "collision_count_episodes"] == 2
    assert agg.loc["td3_lidar", "collision_count_mean"] == pytest.approx(4 / 3)
    assert agg.loc["sac%depth", "collision_count_episodes"] == 1
    counts = {"n_success": "goals", "n_collision": "collisions", "n_timeout": "timeouts"}
    text = render_comparison(agg, "markdown", columns=["success", "collision_count"],
                             counts=counts)
    header, _, td3, sac = text.splitlines()[:4]
    assert header.startswith("| agent | goals [episodes] | collisions [episodes] | timeouts "
                             "[episodes] | success [n/total] | collisions [episodes] |")
    assert td3 == "| td3_lidar | 2 | 1 | 0 | 2/3 | 2 |"
    records = json.loads(render_comparison(agg, "json", columns=["collision_count"],
                                           counts=counts))
    assert records[0] == {"agent": "td3_lidar", "goals": 2, "collisions": 1, "timeouts": 0,
                          "collision_count": 2}
