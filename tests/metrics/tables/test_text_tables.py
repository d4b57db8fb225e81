"""The text renderers (``tables.text``), on small hand-built result frames."""

from __future__ import annotations

import io
import json
import math

import pandas as pd
import pytest

from pic4rl_base.errors import ConfigError
from pic4rl_metrics.tables.aggregate import aggregate
from pic4rl_metrics.tables.layouts import FORMATS
from pic4rl_metrics.tables.results import TABLE1_COLUMNS
from pic4rl_metrics.tables.text import render_comparison, render_episodes

NAN = math.nan


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






@pytest.mark.parametrize("fmt", FORMATS)
def test_every_format_renders(episodes: pd.DataFrame, fmt: str) -> None:
    assert render_episodes(episodes, fmt).strip()
    assert render_comparison(aggregate(episodes), fmt).strip()


def test_bad_format_and_column_suggest(episodes: pd.DataFrame) -> None:
    with pytest.raises(ConfigError, match=r"format 'latx'.*did you mean 'latex'"):
        render_episodes(episodes, "latx")
    with pytest.raises(ConfigError, match=r"'path_lenght_m'.*did you mean 'path_length_m'"):
        render_comparison(aggregate(episodes), "table", columns=["path_lenght_m"])


def test_the_episode_view_shows_the_footprints_clearance_only_where_it_is_defined(
        episodes: pd.DataFrame) -> None:
    without = episodes.assign(footprint_clearance_min_m=math.nan)
    assert "min clearance" not in render_episodes(without, "table")
    with_footprint = episodes.assign(footprint_clearance_min_m=0.25)
    header, _, first = render_episodes(with_footprint, "markdown").splitlines()[:3]
    labels = [c.strip() for c in header.strip("|").split("|")]
    assert "min obst [m]" in labels
    column = labels.index("min clearance [m]")
    assert first.strip("|").split("|")[column].strip() == "0.25"
