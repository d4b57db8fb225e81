"""``config/suite_explore.yaml``: the learned frontier choice and the exploration baselines on
held-out worlds (none of the envs' training variants: indoor's, and the rooms house's held-out
layouts, none of which the frontier choice trained on), its demo cut, and a reduced copy (one
indoor world, one episode per row) run in process end to end into the explore table's coverage
columns, equal to the bags'."""

from __future__ import annotations

from pathlib import Path

import pytest
import yaml

from pic4rl_agents.suites import runner as bench
from pic4rl_agents.suites.suite import load_suite
from pic4rl_agents.training.frontier_choice import TRAIN_VARIANTS, VALIDATION_VARIANTS
from pic4rl_metrics import compute
from pic4rl_sim.engine.worlds.held_out import HELD_OUT

REPO = Path(__file__).resolve().parents[3]
SUITE = REPO / "config" / "suite_explore.yaml"
DEMO = REPO / "config" / "suite_explore_demo.yaml"
ROWS = ["frontier", "frontier_ppo", "random_walk"]


def _training_variants(name: str = "env_explore.yaml") -> set[int]:
    env = yaml.safe_load((REPO / "config" / name).read_text())
    text = env["nav_env"]["ros__parameters"]["episodes"]["world_variants"]
    low, high = (int(v) for v in text.split(":"))
    return set(range(low, high))


def test_the_suite_is_the_agent_and_both_baselines_on_held_out_worlds(tmp_path: Path) -> None:
    suite = load_suite(SUITE, bags_dir=tmp_path)
    assert suite.table == "explore" and len(suite.cells) == 3 * 5 + 3 * 20
    assert sorted({c.agent for c in suite.cells}) == ROWS
    indoor = {c.variant for c in suite.cells if c.world == "indoor"}
    assert indoor == {1000, 1001, 1002} and not indoor & _training_variants()
    assert {c.variant for c in suite.cells if c.world == "barn_like"} == {1000, 1001}
    house = {c.variant for c in suite.cells if c.world == "rooms"}
    assert house == set(range(1000, 1020)) and house <= set(HELD_OUT["rooms"].variants())
    assert not house & _training_variants("env_explore_rooms.yaml")
    assert not house & set(range(*map(int, TRAIN_VARIANTS.split(":"))))
    assert not house & set(range(VALIDATION_VARIANTS[0], VALIDATION_VARIANTS[1]))
    assert {c.pairs.episodes for c in suite.cells if c.world != "rooms"} == {2}
    assert {c.row["world"] for c in suite.cells} == {"indoor:heldout", "barn_like:fields",
                                                     "rooms:heldout"}


def test_the_demo_is_a_cut_of_the_suite(tmp_path: Path) -> None:
    full = {(c.agent, c.world, c.variant) for c in load_suite(SUITE, bags_dir=tmp_path).cells}
    demo = load_suite(DEMO, bags_dir=tmp_path)
    cut = {(c.agent, c.world, c.variant) for c in demo.cells}
    assert cut < full and sorted({a for a, _, _ in cut}) == ROWS
    assert {w for _, w, _ in cut} == {"indoor", "rooms"} and demo.table == "explore"


@pytest.mark.heavy
def test_a_reduced_suite_runs_in_process_into_the_coverage_columns(tmp_path: Path) -> None:
    data = yaml.safe_load(SUITE.read_text())
    task = data["tasks"][0]
    data["tasks"] = [task]  # not the house: 300 s episodes
    task.update(env=str(REPO / "config" / "env_explore.yaml"), pairs=[{"episodes": 1}],
                worlds=[{"world": "indoor", "label": "heldout", "variants": [1000]}])
    path = tmp_path / "suite.yaml"
    path.write_text(yaml.safe_dump(data))
    suite = load_suite(path, bags_dir=tmp_path / "bags")
    table = bench.bench_suite(suite, workers=2, local=True, progress=False)
    h = table.header
    assert h[6:12:2] == ("success", "collision", "timeout")
    assert h[12:22:2] == ("coverage [%]", "area seen [m²]", "time to 50 % seen [s]",
                          "time to 90 % seen [s]", "path per area seen [m/m²]")
    assert sorted(r[1] for r in table.rows) == ROWS
    for row in table.rows:
        cells = dict(zip(h, row))
        assert cells["status"] == "ok" and cells["n"] == "1"
        # every episode judged: reaching the coverage target is its goal, anything else not
        rates = [cells[r] for r in ("success", "collision", "timeout")]
        assert all(r in ("0/1", "1/1") for r in rates) and rates.count("1/1") == 1, rates
        bags = sorted(suite.root.glob(f"explore-{cells['agent']}-*/*/episode_*"))
        frame = compute(bags).frame
        assert len(frame) == 1 and (frame["error"] == "").all()
        coverage = float(frame["coverage_pct"].iloc[0])
        assert 0.0 < coverage <= 105.0  # up to the walls' faces: a few cells past the floor
        assert cells["coverage [%]"] == f"{coverage:.2f}"
        assert cells["area seen [m²]"] == f"{float(frame['area_seen_m2'].iloc[0]):.2f}"
    report = (suite.root / "report.html").read_text()
    assert 'id="sec-coverage"' in report and 'data-agent="frontier"' in report
