"""``config/suite_barn.yaml`` and its CI variant: the protocol's cells (world groups, one row
per agent), bad table and world-group keys named, and the CI suite run in process end to end
into BARN's table (rates with Wilson intervals, mean BARN time and score with bootstrap
intervals) from its bags alone."""

from __future__ import annotations

from pathlib import Path

import pandas as pd
import pytest
import yaml

from pic4rl_agents.suites import runner as bench
from pic4rl_agents.suites.suite import load_suite
from pic4rl_bridge.errors import ConfigError
from pic4rl_metrics import compute
from pic4rl_metrics.tables.aggregate import bootstrap_interval, wilson_interval

REPO = Path(__file__).resolve().parents[3]
SUITE, CI = REPO / "config" / "suite_barn.yaml", REPO / "config" / "suite_barn_ci.yaml"


def test_the_demo_is_the_agent_dwa_and_the_planner_on_5_test_worlds_over_ros(
        tmp_path: Path) -> None:
    """``make demo CASE=barn``'s suite: through the sim node, on test worlds only."""
    suite = load_suite(REPO / "config" / "suite_barn_demo.yaml", bags_dir=tmp_path)
    assert {c.transport for c in suite.cells} == {"ros"} and suite.table == "barn"
    assert sorted({c.agent for c in suite.cells}) == ["barn_td3_explorer", "dwa", "planner"]
    assert sorted({c.variant for c in suite.cells}) == [0, 60, 120, 180, 240]
    assert len(suite.cells) == 15 and {c.pairs.episodes for c in suite.cells} == {1}


def test_the_protocol_is_the_50_test_worlds_times_10_runs(tmp_path: Path) -> None:
    suite = load_suite(SUITE, bags_dir=tmp_path)
    assert suite.table == "barn"
    assert len(suite.cells) == 5 * 50  # the two learned agents and the three baselines
    for agent in ("barn_td3_explorer", "barn_td3_memory", "dwa", "planner", "explorer"):
        cells = [c for c in suite.cells if c.agent == agent]
        assert [c.variant for c in cells] == list(range(0, 300, 6))
        assert {c.pairs.episodes for c in cells} == {10} and {c.world for c in cells} == {"barn"}
        assert len({c.name for c in cells}) == 50
        assert {tuple(c.row.values()) for c in cells} == {
            ("barn", agent, "barn:test50", "jackal", "episodes10_s0")}  # one row per agent


@pytest.mark.bad_input
@pytest.mark.parametrize(("change", "message"), [
    ({"table": "barns"},
     "suite_barn_ci.yaml: table: 'barns' is invalid; expected paper or barn or explore or crowd"),
    ({"worlds": [{"world": "barn", "label": "x", "variants": [1, -2]}]},
     "tasks[0].worlds.variants: [1, -2] is invalid; expected a non-empty list of integers >= 0"),
    ({"worlds": [{"world": "barn", "variant": [1]}]},
     "tasks[0].worlds: unknown key 'variant'; did you mean 'variants'?"),
])
def test_bad_table_and_world_group_keys_are_named(tmp_path: Path, change: dict,
                                                  message: str) -> None:
    data = yaml.safe_load(CI.read_text())
    if "table" in change:
        data.update(change)
    else:
        data["tasks"][0].update(change)
    data["tasks"][0]["env"] = str(REPO / "config" / "env_barn.yaml")
    path = tmp_path / CI.name
    path.write_text(yaml.safe_dump(data))
    with pytest.raises(ConfigError) as err:
        load_suite(path)
    assert str(err.value).endswith(message)


@pytest.mark.heavy
def test_the_ci_suite_runs_in_process_into_barns_table(tmp_path: Path) -> None:
    suite = load_suite(CI, bags_dir=tmp_path)
    table = bench.bench_suite(suite, workers=2, local=True, progress=False)
    h = table.header
    assert h[5:] == ("n", "success", "success 95% CI", "collision", "collision 95% CI",
                     "timeout", "timeout 95% CI", "BARN time [s]", "BARN time 95% CI",
                     "BARN score [-]", "BARN score 95% CI", "status")
    assert [r[1] for r in table.rows] == ["dwa", "planner", "explorer"]
    for row in table.rows:
        cells = dict(zip(h, row))
        assert cells["status"] == "ok" and cells["world"] == "barn:ci3" and cells["n"] == "3"
        bags = sorted((suite.root).glob(f"barn-{cells['agent']}-*/*/episode_*"))
        frame = compute(bags).frame
        assert len(frame) == 3 and (frame["error"] == "").all()
        # each column is what the bags say
        for rate in ("success", "collision", "timeout"):
            k = int((frame["outcome"] == ("goal" if rate == "success" else rate)).sum())
            assert cells[rate] == f"{k}/3"
            assert cells[f"{rate} 95% CI"] == "[{:.2f}, {:.2f}]".format(*wilson_interval(k, 3))
        score = frame["barn_score"]
        assert cells["BARN score [-]"] == f"{score.mean():.2f}"
        assert cells["BARN score 95% CI"] == "[{:.2f}, {:.2f}]".format(
            *bootstrap_interval(score))
        assert ((score >= 0) & (score <= 0.5)).all()
        won = frame[frame["success"] == 1.0]["barn_time_s"]
        if len(won):
            assert cells["BARN time [s]"] == f"{won.mean():.2f}"
    text = (suite.root / "results.md").read_text()
    assert "BARN score" in text and (suite.root / "leaderboard_barn.md").is_file()
    csv = pd.read_csv(suite.root / "results.csv")
    assert list(csv["agent"]) == ["dwa", "planner", "explorer"]


def test_the_bootstrap_interval_brackets_the_mean_and_is_seeded() -> None:
    values = [0.0, 0.5, 0.5, 0.25, float("nan")]
    low, high = bootstrap_interval(values)
    assert low <= 0.3125 <= high and (low, high) == bootstrap_interval(values)
    assert bootstrap_interval([0.4, 0.4]) == (pytest.approx(0.4), pytest.approx(0.4))
    assert all(v != v for v in bootstrap_interval([float("nan")]))
