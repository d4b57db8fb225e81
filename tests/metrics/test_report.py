"""aggregate() and the text renderers, on small hand-built result frames."""

from __future__ import annotations

import io
import json
import math

import pandas as pd
import pytest

from pic4rl_metrics.aggregate import UNKNOWN_GROUP, aggregate
from pic4rl_metrics.errors import ConfigError
from pic4rl_metrics.report import FORMATS, render_comparison, render_episodes
from pic4rl_metrics.results import ERROR_COLUMN, ID_COLUMNS, METRIC_COLUMNS, TABLE1_COLUMNS

NAN = math.nan


def _row(bag: str, agent: object, run: object = "run1", error: str = "", **metrics: object):
    row: dict[str, object] = dict.fromkeys(ID_COLUMNS)
    row.update(bag=bag, agent=agent, task="goal", world="indoor", run=run, episode=1)
    row.update({m: NAN for m in METRIC_COLUMNS})
    row.update(outcome=None if error else "goal", n_poses=0 if error else 100, n_scans=50)
    row.update(metrics)
    row[ERROR_COLUMN] = error
    return row


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


# --- per-episode renderings -------------------------------------------------------------------


def test_episodes_json_round_trips_with_null(episodes: pd.DataFrame) -> None:
    records = json.loads(render_episodes(episodes, "json"))
    assert len(records) == len(episodes)
    assert set(records[0]) == set(episodes.columns)
    assert records[0]["clearance_time_s"] == 10.0 and records[0]["spl"] is None
    assert records[5]["path_length_m"] is None and records[3]["success"] is None
    assert records[4]["error"] == "BagError: truncated bag" and records[4]["outcome"] is None
    assert records[0]["n_poses"] == 100


def test_episodes_csv_parses_back_to_same_numbers(episodes: pd.DataFrame) -> None:
    back = pd.read_csv(io.StringIO(render_episodes(episodes, "csv")), keep_default_na=True)
    assert list(back.columns) == list(episodes.columns)
    for col in ("success", "clearance_time_s", "path_length_m", "spl", "n_poses"):
        pd.testing.assert_series_equal(
            back[col].astype(float), episodes[col].astype(float), check_names=False
        )


def test_episodes_table_is_short_and_readable(episodes: pd.DataFrame) -> None:
    text = render_episodes(episodes, "table")
    lines = text.splitlines()
    assert len(lines) == 3 + len(episodes)  # labels, units, rule, rows
    assert "run1/ep1" in text and "/bags/" not in text
    assert "ω std" in lines[0] and "[m/s²]" in lines[1]
    assert set(lines[2]) <= {"-", " "}
    assert "–" in lines[3 + 5] and "BagError: truncated bag" in lines[3 + 4]


def test_episodes_markdown_and_latex(episodes: pd.DataFrame) -> None:
    md = render_episodes(episodes, "markdown").splitlines()
    assert len(md) == 2 + len(episodes) and md[1].startswith("|:---|")
    tex = render_episodes(episodes, "latex")
    assert tex.startswith(r"\begin{tabular}{@{}c") and r"\toprule" in tex and r"\bottomrule" in tex
    assert r"run1/ep1 & goal & yes & 10.00" in tex


# --- comparison table ------------------------------------------------------------------------


def test_comparison_latex_like_the_paper(episodes: pd.DataFrame) -> None:
    tex = render_comparison(aggregate(episodes, over="all"), "latex", caption="Average metrics.",
                            label="tab:navigation-metrics")
    lines = tex.splitlines()
    assert lines[0] == r"\begin{table*}[ht]" and lines[-1] == r"\end{table*}"
    assert r"\caption{Average metrics.}" in lines and r"\label{tab:navigation-metrics}" in lines
    assert r"\begin{tabular}{@{}" + "c" * 12 + "@{}}" in lines
    top = lines.index(r"\toprule")
    assert lines[top + 1].startswith(" & success & time & cum. heading & path & dist/path")
    assert lines[top + 2].startswith(" & [n/total] & [s] & [rad] & [m] & [m/m] & [m/s]")
    assert lines[top + 3] == r"\midrule"
    td3, sac = lines[top + 4], lines[top + 5]
    assert td3.startswith(r"td3\_lidar & 2/3 & 20.00 & -- & 5.50 & -- & 0.30 & ")
    assert sac.startswith(r"sac\%depth & 1/1 & 13.00 & ")
    assert lines[top + 6] == r"\bottomrule"
    assert "--over all" in lines[-2] and "every judged episode" in lines[-2]  # the footnote


def test_comparison_with_std(episodes: pd.DataFrame) -> None:
    agg = aggregate(episodes, over="all")
    assert "20.00 ± 10.00" in render_comparison(agg, "table", with_std=True)
    assert r"20.00 $\pm$ 10.00" in render_comparison(agg, "latex", with_std=True)
    rec = json.loads(render_comparison(agg, "json", with_std=True))[0]
    assert rec["clearance_time_s_std"] == pytest.approx(10.0)


def test_comparison_markdown_one_line_per_agent(episodes: pd.DataFrame) -> None:
    lines = render_comparison(aggregate(episodes, over="all"), "markdown").splitlines()
    assert len(lines) == 2 + 2 + 2  # header, rule, two agents, blank, footnote
    assert lines[-1].startswith("All columns: mean over every judged episode")
    assert sum(bool(line) and set(line) <= set("|:-") for line in lines) == 1
    assert lines[0].startswith("| agent | success [n/total] | time [s] |")
    assert lines[2].startswith("| td3_lidar | 2/3 | 20.00 | – | 5.50 |")
    assert lines[3].startswith("| sac%depth | 1/1 | 13.00 |")


def test_comparison_csv_and_json_parse_back(episodes: pd.DataFrame) -> None:
    agg = aggregate(episodes, over="all")
    back = pd.read_csv(io.StringIO(render_comparison(agg, "csv")))
    assert list(back["agent"]) == ["td3_lidar", "sac%depth"]
    assert back["time [s]"].tolist() == [20.0, 13.0]
    assert back["success [n/total]"].tolist() == ["2/3", "1/1"]
    assert back["cum. heading [rad]"].isna().all()
    assert back["over"].tolist() == ["all", "all"] and back["n_averaged"].tolist() == [3, 2]
    records = json.loads(render_comparison(agg, "json"))
    assert [r["agent"] for r in records] == ["td3_lidar", "sac%depth"]
    assert records[0]["path_length_m"] == pytest.approx(5.5)
    assert records[0]["heading_error_mean_rad"] is None
    assert set(records[0]) == {"agent", *TABLE1_COLUMNS, "over", "n_averaged"}


def test_comparison_nothing_judged(episodes: pd.DataFrame) -> None:
    agg = aggregate(episodes[episodes["agent"] == "sac%depth"].assign(success=NAN), over="all")
    assert agg.loc["sac%depth", "success"] == "–"
    assert "| sac%depth | – | 13.00 |" in render_comparison(agg, "markdown")
    assert render_comparison(agg, "csv").splitlines()[1].startswith("sac%depth,,13.00,")
    assert json.loads(render_comparison(agg, "json"))[0]["success"] is None


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


@pytest.mark.parametrize("fmt", FORMATS)
def test_every_format_renders(episodes: pd.DataFrame, fmt: str) -> None:
    assert render_episodes(episodes, fmt).strip()
    assert render_comparison(aggregate(episodes), fmt).strip()


def test_bad_format_and_column_suggest(episodes: pd.DataFrame) -> None:
    with pytest.raises(ConfigError, match=r"format 'latx'.*did you mean 'latex'"):
        render_episodes(episodes, "latx")
    with pytest.raises(ConfigError, match=r"'path_lenght_m'.*did you mean 'path_length_m'"):
        render_comparison(aggregate(episodes), "table", columns=["path_lenght_m"])
