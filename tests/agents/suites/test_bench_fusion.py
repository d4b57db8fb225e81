"""``config/suite_fusion.yaml`` (the fusion study, docs/results.md#fusion) and its demo cut:
each row observes the sensors its name says, through the agent's own trained config and the
baselines' env; the test layouts are never the agents' training or evaluation layouts."""

from __future__ import annotations

from pathlib import Path

from pic4rl_agents.runs.config import load_run_config
from pic4rl_agents.suites.suite import load_suite
from pic4rl_bridge.episodes import parse_variants

REPO = Path(__file__).resolve().parents[3]
OBSERVED = {"lidar": ("lidar",), "depth": ("depth",), "fused": ("lidar", "depth")}


def test_each_row_observes_its_sensors_on_held_out_layouts(tmp_path: Path) -> None:
    suite = load_suite(REPO / "config" / "suite_fusion.yaml", bags_dir=tmp_path)
    assert suite.table == "barn" and len(suite.cells) == 7 * 20
    tested = {c.variant for c in suite.cells}
    assert tested == set(range(20)) and {c.world for c in suite.cells} == {"clutter3d"}
    for task, sensors in OBSERVED.items():
        agent = f"fusion_{task}"
        run = load_run_config([REPO / "checkpoints" / agent / "config.yaml"])
        assert run.env.observed == sensors, agent
        assert run.env.goal_input == "explorer", agent
        trained = set(parse_variants(run.env.episodes.world_variants))
        evaluated = set(parse_variants(run.train.eval.world_variants))
        assert trained and evaluated and not (trained | evaluated) & tested, agent
        cells = [c for c in suite.cells if c.row["task"] == task]
        assert {c.agent for c in cells} >= {agent, "explorer"}
        assert {(c.pairs.random, c.pairs.kind, c.pairs.seed) for c in cells} == {(5, "paper", 2026)}


def test_the_demo_runs_every_agent_and_the_fused_explorer_through_the_sim_node(
        tmp_path: Path) -> None:
    suite = load_suite(REPO / "config" / "suite_fusion_demo.yaml", bags_dir=tmp_path)
    assert {c.transport for c in suite.cells} == {"ros"}
    assert sorted({c.agent for c in suite.cells}) == [
        "explorer", "fusion_depth", "fusion_fused", "fusion_lidar"]
    assert {c.variant for c in suite.cells} == set(range(5))
