"""``config/suite_crowd.yaml`` (issue 41 items 5 and 6): the shipped TD3-LiDAR agent, the agent
trained among people, DWA, the planner, the predictive planner and ORCA on the paper's 5 indoor
pairs among 10 people with held-out seeds, and a cut-down suite run in process (the agent
trained among people from its checkpoint, and ORCA) whose bags carry the social metrics into
the suite's table (``table: crowd``) and the report's leaderboard."""

from __future__ import annotations

import re
from pathlib import Path

import pytest
import yaml

from pic4rl_agents.suites import runner as bench
from pic4rl_agents.suites.suite import load_suite
from pic4rl_base import params_file
from pic4rl_metrics import compute

REPO = Path(__file__).resolve().parents[3]
SUITE = REPO / "config" / "suite_crowd.yaml"
DEMO = REPO / "config" / "suite_crowd_demo.yaml"


def test_the_suite_is_six_agents_among_ten_people_on_held_out_seeds(tmp_path: Path) -> None:
    suite = load_suite(SUITE, bags_dir=tmp_path)
    assert suite.table == "crowd" and len(suite.cells) == 6 * 4
    assert {c.agent for c in suite.cells} == {"td3_lidar", "crowd_td3_history", "dwa",
                                              "planner", "predictive", "orca"}
    assert {c.seed for c in suite.cells} == {1000, 1001, 1002, 1003}
    assert {c.pairs.label for c in suite.cells} == {"paper"}
    env = Path(suite.cells[0].env)
    sim = params_file.node_section(params_file.read(env), "sim", source=env)
    assert sim["crowd.count"] == 10 and sim["world"] == "indoor"
    demo = load_suite(DEMO, bags_dir=tmp_path)
    assert {c.agent for c in demo.cells} == {"td3_lidar", "dwa", "orca"}
    assert {c.env for c in demo.cells} == {str(env)}


@pytest.mark.heavy
def test_two_episodes_each_run_in_process_into_the_social_columns(tmp_path: Path) -> None:
    data = yaml.safe_load(SUITE.read_text())
    data["retries"] = 0
    task = data["tasks"][0]
    task["env"] = str(REPO / "config" / "env_crowd.yaml")
    task["agents"] = {"crowd_td3_history": str(REPO / "checkpoints" / "crowd_td3_history")}
    task["baselines"] = ["orca"]
    task["pairs"] = [{"random": 2, "kind": "paper", "seed": 0}]
    task["repetitions"] = 1
    path = tmp_path / SUITE.name
    path.write_text(yaml.safe_dump(data))
    suite = load_suite(path, bags_dir=tmp_path / "bags")
    table = bench.bench_suite(suite, workers=1, local=True, progress=False)
    rows = {row[1]: dict(zip(table.header, row)) for row in table.rows}
    # the agent trained among people loads from its checkpoint with its trained observation
    assert sorted(rows) == ["crowd_td3_history", "orca"]
    assert rows["crowd_td3_history"]["status"] == "ok" and rows["crowd_td3_history"]["n"] == "2"
    cells = rows["orca"]
    assert cells["status"] == "ok" and cells["n"] == "2"
    # the suite's table carries the social columns, read from these bags (not 0 for want of
    # people: ten walk in the indoor world, so someone comes within the social zone)
    assert float(cells["social zone time [s]"]) > 0
    assert float(cells["social zone entries [count]"]) > 0
    assert cells["min person distance [m]"] is not None
    frame = compute(sorted(suite.root.glob("crowd-orca-*/*/episode_*"))).frame
    assert len(frame) == 2 and (frame["error"] == "").all()
    assert frame["people_dist_min_m"].notna().all() and (frame["people_dist_min_m"] > 0).all()
    assert (frame["personal_intrusion_time_s"] >= 0).all()
    board = re.search(r'<table id="leaderboard".*?</table>',
                      (suite.root / "report.html").read_text(), re.DOTALL)
    assert board is not None and "min person distance [m]" in board.group(0)
