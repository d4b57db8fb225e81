"""``config/suite_dynbarn.yaml``: the agents trained on training scenes, DWA, the planner and the
predictive planner on the dynamic BARN's 60 test scenes with BARN's table, and a cut-down
suite run in process into that table, its BARN score from the bags (the dynbarn world's
reference path marks it as BARN's)."""

from __future__ import annotations

from pathlib import Path

import pytest
import yaml

from pic4rl_agents.suites import runner as bench
from pic4rl_agents.suites.suite import load_suite
from pic4rl_metrics import compute
from pic4rl_sim.engine.worlds.dynbarn import TEST_SCENES

REPO = Path(__file__).resolve().parents[3]
SUITE = REPO / "config" / "suite_dynbarn.yaml"


def test_the_suite_is_two_agents_and_three_baselines_on_the_60_test_scenes(tmp_path: Path) -> None:
    suite = load_suite(SUITE, bags_dir=tmp_path)
    assert suite.table == "barn" and len(suite.cells) == 5 * 60
    for agent in ("dynbarn_td3_history", "dynbarn_td3_predictive", "dwa", "planner",
                  "predictive"):
        cells = [c for c in suite.cells if c.agent == agent]
        assert tuple(c.variant for c in cells) == TEST_SCENES
        assert {c.world for c in cells} == {"dynbarn"} and {c.pairs.episodes for c in cells} == {3}
        assert {tuple(c.row.values()) for c in cells} == {
            ("dynbarn", agent, "dynbarn:test60", "jackal", "episodes3_s0")}


@pytest.mark.heavy
def test_two_scenes_run_in_process_into_barns_table(tmp_path: Path) -> None:
    data = yaml.safe_load(SUITE.read_text())
    data["retries"] = 0
    task = data["tasks"][0]
    task["env"] = str(REPO / "config" / "env_barn.yaml")
    task["agents"] = {name: str((SUITE.parent / where).resolve())
                      for name, where in task["agents"].items()}
    task["worlds"] = [{"world": "dynbarn", "label": "two", "variants": list(TEST_SCENES[:2])}]
    task["pairs"] = [{"episodes": 1}]
    path = tmp_path / SUITE.name
    path.write_text(yaml.safe_dump(data))
    suite = load_suite(path, bags_dir=tmp_path / "bags")
    table = bench.bench_suite(suite, workers=2, local=True, progress=False)
    assert sorted(r[1] for r in table.rows) == ["dwa", "dynbarn_td3_history", "dynbarn_td3_predictive",
                                               "planner", "predictive"]
    for row in table.rows:
        cells = dict(zip(table.header, row))
        assert cells["status"] == "ok" and cells["world"] == "dynbarn:two" and cells["n"] == "2"
        frame = compute(sorted(suite.root.glob(f"dynbarn-{cells['agent']}-*/*/episode_*"))).frame
        assert len(frame) == 2 and (frame["error"] == "").all()
        score = frame["barn_score"]
        assert score.notna().all() and ((score >= 0) & (score <= 0.5)).all()
        assert cells["BARN score [-]"] == f"{score.mean():.2f}"
