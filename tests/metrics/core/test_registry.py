"""The metric registry: a metric registered from this test module (nothing installed) gets
its column, a missing input gives NaN with a warning, a plugin arrives through the
``pic4rl.metrics`` entry point, and ``--metrics`` (or the topic map) selects columns."""

from __future__ import annotations

import io
import math
from collections.abc import Iterator
from importlib.metadata import EntryPoint
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

import pic4rl_metrics.core.registry as registry_module
from pic4rl_metrics import METRIC_TABLE, ConfigError, Derived, Metric, compute, metric
from pic4rl_metrics.cli.commands import main
from pic4rl_metrics.core.registry import Registry
from pic4rl_metrics.tables.results import METRIC_COLUMNS
from pic4rl_metrics.synthetic.synthetic import straight_line, write_episode_bag

LINE = straight_line(0.5, 4.0)  # x = 0, 0.05, ..., 2 m: mean x is 1 m


def mean_x(d: Derived) -> float:
    """Mean x of the poses (m): 1 m on LINE."""
    return float(np.mean(d.pose.x))


#: What a user's package would point its entry point at.
PLUGIN = Metric("plugin_path_twice_m", "m", "path × 2", lambda d: 2 * d.path_m, builtin=False)


@pytest.fixture
def user_metrics() -> Iterator[None]:
    """Registers three metrics the way a user does, and removes them afterwards."""
    metric("mean_x_m", unit="m", label="mean x", needs=("pose",), quality=True)(mean_x)
    metric("person_far_m", unit="m", needs=("person",))(lambda d: 1.0)
    metric("broken_m", unit="m")(lambda d: 1 / 0)
    yield
    for name in ("mean_x_m", "person_far_m", "broken_m"):
        METRIC_TABLE.remove(name)


@pytest.fixture
def bag(tmp_path: Path) -> Path:
    return write_episode_bag(tmp_path / "line", LINE, goal=(2.0, 0.0), outcome="goal")


def test_a_registered_metric_gets_its_column(user_metrics: None, bag: Path) -> None:
    result = compute([bag])
    row = result.frame.iloc[0]
    assert list(result.frame.columns[-5:]) == ["mean_x_m", "person_far_m", "broken_m", "error",
                                               "warnings"]
    assert row["mean_x_m"] == pytest.approx(1.0, abs=1e-12)
    assert row["path_length_m"] == pytest.approx(2.0, abs=1e-9)  # ours are unchanged
    # missing input and a metric that raises: NaN with a warning, never a crash
    assert math.isnan(row["person_far_m"]) and math.isnan(row["broken_m"])
    assert "no person in this bag: person_far_m NaN" in row["warnings"]
    assert "metric 'broken_m' failed: ZeroDivisionError" in row["warnings"]
    assert row["error"] == ""


def test_registered_metrics_reach_worker_processes(user_metrics: None, tmp_path: Path) -> None:
    bags = [write_episode_bag(tmp_path / f"b{i}", LINE) for i in range(3)]
    frame = compute(bags, jobs=2, metrics=["mean_x_m"]).frame
    assert frame["mean_x_m"].tolist() == pytest.approx([1.0] * 3, abs=1e-12)


def test_metrics_selects_columns_and_keeps_outcome_and_success(bag: Path) -> None:
    frame = compute([bag], metrics=["spl", "path_length_m"]).frame
    metric_cols = [c for c in frame.columns if c in METRIC_TABLE.metrics]
    assert metric_cols == ["outcome", "success", "path_length_m", "spl"]  # registry order
    assert frame.iloc[0]["spl"] == pytest.approx(1.0, abs=1e-9)


def test_a_missing_input_of_a_named_builtin_is_warned(bag: Path) -> None:
    """Asked for by name, a NaN says why; by default the documented NaN stays quiet."""
    named = compute([bag], metrics=["collision_count"]).results[0]
    assert "no footprint, scan in this bag: collision_count NaN" in named.warnings
    assert compute([bag]).results[0].warnings == ()


def test_unknown_and_duplicate_names_are_refused() -> None:
    with pytest.raises(ConfigError, match=r"'path_lenght_m' is not a metric; did you mean 'path_length_m'"):
        METRIC_TABLE.select(["path_lenght_m"])
    with pytest.raises(ConfigError, match="'spl' is registered already"):
        metric("spl", unit="-")(mean_x)
    with pytest.raises(ConfigError, match="one of pic4rl's own"):
        METRIC_TABLE.remove("spl")
    with pytest.raises(ConfigError, match=r"unknown inputs \['map'\]"):
        Metric("m", "m", "m", mean_x, needs=frozenset({"map"}))


def test_a_plugin_arrives_through_the_entry_point_group(
    monkeypatch: pytest.MonkeyPatch, bag: Path
) -> None:
    """What ``pip install`` of a user's package declares, without installing it: one entry
    point names a ``Metric``, one a module that fails to import (reported, not fatal)."""
    points = [
        EntryPoint("twice", f"{__name__}:PLUGIN", registry_module.ENTRY_POINT_GROUP),
        EntryPoint("broken", "no_such_package_xyz.metrics", registry_module.ENTRY_POINT_GROUP),
    ]
    asked: list[str] = []

    def fake_entry_points(*, group: str) -> list[EntryPoint]:
        asked.append(group)
        return points

    monkeypatch.setattr(registry_module, "entry_points", fake_entry_points)
    fresh = Registry()
    fresh.load_plugins()
    assert asked == ["pic4rl.metrics"]
    assert list(fresh.metrics) == ["plugin_path_twice_m"]
    assert "no_such_package_xyz" in fresh.plugin_errors[0]
    # through the process-wide registry, as compute() loads it
    monkeypatch.setattr(METRIC_TABLE, "_plugins_loaded", False)
    monkeypatch.setattr(METRIC_TABLE, "plugin_errors", [])
    try:
        row = compute([bag]).frame.iloc[0]
        assert row["plugin_path_twice_m"] == pytest.approx(4.0, abs=1e-9)
    finally:
        METRIC_TABLE.remove("plugin_path_twice_m")


def test_the_cli_selects_metrics(
    user_metrics: None, bag: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["compute", "--metrics", "path_length_m,mean_x_m", "--format", "csv", str(bag)]) == 0
    back = pd.read_csv(io.StringIO(capsys.readouterr().out))
    assert [c for c in back.columns if c in METRIC_TABLE.metrics] == [
        "outcome", "success", "path_length_m", "mean_x_m",
    ]
    assert main(["compare", "--metrics", "mean_x_m", "--format", "markdown", str(bag)]) == 0
    out = capsys.readouterr().out
    assert out.startswith("| agent | success [n/total] | mean x [m] |")
    assert "mean x: mean over the row's successful episodes only (n = 1)" in out
    assert main(["compute", "--metrics", "spll", str(bag)]) == 2
    assert "did you mean 'spl'" in capsys.readouterr().err


def test_the_topic_map_selects_metrics(bag: Path, tmp_path: Path) -> None:
    topic_map = tmp_path / "map.yaml"
    topic_map.write_text("metrics: [path_length_m]\n")
    assert main(["compute", "--topic-map", str(topic_map), "--format", "csv",
                 "--out", str(tmp_path / "out.csv"), str(bag)]) == 0
    back = pd.read_csv(tmp_path / "out.csv")
    assert [c for c in back.columns if c in METRIC_TABLE.metrics] == ["outcome", "success", "path_length_m"]


def test_every_builtin_metric_is_documented() -> None:
    """docs/metrics.md's per-episode table names every one of our columns, and no other."""
    doc = (Path(__file__).resolve().parents[3] / "docs" / "metrics.md").read_text()
    table = doc.split("## Per-episode metrics", 1)[1].split("\n\n", 2)[1]
    named = set()
    for line in table.splitlines()[2:]:
        cell = line.split("|")[1]
        first = None
        for part in cell.split("`")[1::2]:
            name = part if not part.startswith("_") else f"{first.rsplit('_', 2)[0]}{part}"
            first = first or part
            named.add(name)
    assert named == set(METRIC_COLUMNS)


def test_a_metric_s_table_placement_is_in_its_registry_entry() -> None:
    from pic4rl_metrics.tables.results import ROW_COLUMNS, TABLE1_COLUMNS, table_columns
    assert TABLE1_COLUMNS == (
        "success", "clearance_time_s", "heading_error_mean_rad", "path_length_m",
        "distance_path_ratio", "lin_vel_mean_mps", "ang_vel_std_radps", "lin_acc_max_mps2",
        "yaw_acc_max_radps2", "obstacle_dist_min_m", "obstacle_dist_mean_m")
    assert ROW_COLUMNS == ("row_path_mae_m", "row_path_mse_m2")
    # a user's metric placed first among the rows' columns joins the table when it has values
    metric("row_width_m", unit="m", table=("row", -1))(lambda d: 1.0)
    try:
        frame = pd.DataFrame({"row_width_m": [0.8], "row_path_mae_m": [math.nan]})
        assert table_columns(frame) == (*TABLE1_COLUMNS, "row_width_m")
        assert METRIC_TABLE.table("row") == ("row_width_m", *ROW_COLUMNS)
    finally:
        METRIC_TABLE.remove("row_width_m")


@pytest.mark.bad_input
def test_a_table_section_that_does_not_exist_is_refused() -> None:
    with pytest.raises(ConfigError, match=r"metric 'x_m': table section 'table2' is none of "
                                          r"\['explore', 'paper', 'row', 'social'\]"):
        Metric("x_m", "m", "x", lambda d: 0.0, table=("table2", 0))
