"""``pic4rl-bench``'s ``table: barn`` and ``pic4rl-metrics compare --table barn`` are one
computation (``pic4rl_metrics.tables.protocol``): on the same bags, laid out as a suite's cells
lay them out, every cell of a row is the same in both, whether its agent is a plugin's, a ROS
stack's or a shipped one's name.

Bags: straight drives at 1 m/s (every 0.1 s) in BARN worlds with a 3 m reference path, so a
3 m drive to its goal scores 0.5 (BARN's clip: AT 2.9 s < 2 OT = 3 s) and a failure 0. An
``aborted`` episode (a plugin that raised) is out of the rates' n and counted in the row's n.
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from pic4rl_agents.suites import table as benchtable
from pic4rl_agents.suites.suite import Cell, PairSet, Suite
from pic4rl_metrics.cli import commands as cli
from pic4rl_metrics.synthetic.synthetic import straight_line, write_episode_bag

#: Per agent, per world variant: (outcome, length driven in m).
RUNS = {
    "gap_follower_plugin": ((0, "goal", 3.0), (6, "collision", 1.2), (12, "aborted", 0.5),
                            (18, "goal", 3.0)),
    "nav2_like_stack": ((0, "timeout", 2.0), (6, "goal", 3.0), (12, "goal", 3.0),
                        (18, "goal", 3.0)),
    "planner": ((0, "goal", 3.0), (6, "goal", 3.0), (12, "goal", 3.0), (18, "collision", 2.5)),
}
PAIRS = PairSet("episodes1_s0", episodes=1)


def _suite(root: Path) -> Suite:
    """Each agent on the world group barn:t (variants 0, 6, 12, 18), one bag per cell where
    a suite's cell writes it (``<bags>/<suite>/<cell>/<agent>/``)."""
    cells = []
    for agent, runs in RUNS.items():
        for variant, outcome, length in runs:
            cell = Cell(f"barn-{agent}-barn{variant}", "barn", agent, "env_barn.yaml",
                        world="barn", variant=variant, world_label="t", robot="jackal",
                        pairs=PAIRS)
            facts = {"agent": agent, "task": "goToPose/lidar", "world": f"barn:{variant}",
                     "start": [0.0, 0.0, 0.0], "goal": [3.0, 0.0], "reference_path_m": 3.0}
            if outcome == "aborted":  # as the env records it: a fact, and no outcome event
                facts.update(outcome=outcome, end_reason="plugin gap_follower_plugin raised")
            write_episode_bag(root / "s" / cell.name / agent / "episode_0000",
                              straight_line(1.0, length), goal=(3.0, 0.0), facts=facts,
                              outcome=None if outcome == "aborted" else outcome)
            cells.append(cell)
    return Suite("s", root / "suite.yaml", root, 0, tuple(cells), table="barn")


def test_bench_and_compare_give_the_same_barn_rows(capsys: pytest.CaptureFixture[str],
                                                   tmp_path: Path) -> None:
    suite = _suite(tmp_path)
    header, rows, bad = benchtable.build_rows(suite, {})
    assert bad == () and [r[1] for r in rows] == list(RUNS)
    assert cli.main(["compare", "--table", "barn", "--format", "json", str(suite.root)]) == 0
    out, err = capsys.readouterr()
    assert err.endswith("aborted by the recorder (plugin gap_follower_plugin raised): out of "
                        "the success rate\n") and len(err.splitlines()) == 1
    compared = {r["agent"]: r for r in json.loads(out)}
    assert list(compared) == list(RUNS)
    for row in rows:
        bench = dict(zip(header, row))
        assert bench["status"] == "ok" and bench["world"] == "barn:t"
        assert {c: bench[c] for c in header[5:-1]} == {
            c: v for c, v in compared[row[1]].items() if c != "agent"}
    # and by hand: the plugin's aborted episode is in n (4), out of the rates' n (3)
    plugin, stack = compared["gap_follower_plugin"], compared["nav2_like_stack"]
    assert [plugin[c] for c in ("n", "success", "success 95% CI", "collision", "timeout")] == [
        "4", "2/3", "[0.21, 0.94]", "1/3", "0/3"]
    assert [stack[c] for c in ("n", "success", "success 95% CI", "timeout",
                               "timeout 95% CI", "BARN score [-]")] == [
        "4", "3/4", "[0.30, 0.95]", "1/4", "[0.05, 0.70]", "0.38"]  # 3 × 0.5 / 4 = 0.375
    assert plugin["BARN score [-]"] == "0.33"  # (0.5 + 0 + 0.5) / 3: the aborted one is NaN
