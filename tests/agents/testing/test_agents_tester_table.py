"""``pic4rl-test``'s printed table: episodes per outcome, the headline first, SPL where it
applies; a personMonitoring run (no goal: its normal end is the time budget) prints its full
runs, never "0/N goals" or a success rate: its bags carry no goal (the simulator's, which the
task does not use, is not recorded), so the metrics' rule (``groups.headline``) heads it with
full runs. Counts are checked against the bags' outcomes and against what the short episodes
force (5 steps: every episode times out)."""

from __future__ import annotations

import contextlib
import io
import json
import math
from pathlib import Path

import pandas as pd
from agents_helpers import CONFIG, LIDAR_TD3

from pic4rl_agents.testing import tester
from pic4rl_metrics.tables.aggregate import aggregate
from pic4rl_metrics.tables.batch import compute
from pic4rl_metrics.tables.results import TABLE1_COLUMNS


def run_main(argv: list[str]) -> tuple[int, str, str]:
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = tester.main(argv)
    return code, out.getvalue(), err.getvalue()


def outcomes(run: Path) -> list[str]:
    result = compute([run])
    assert not result.failed
    return [str(e.facts.outcome.value) for e in result.episodes]


def goals(run: Path) -> list[object]:
    """Each bag's goal as the metrics read it (facts, else the ``goal_pose`` topic)."""
    return [e.facts.goal for e in compute([run]).episodes]


def test_a_goto_table_counts_episodes_per_outcome_and_shows_spl(tmp_path: Path) -> None:
    code, out, err = run_main(["--baseline", "proportional", "--episodes", "3", "--format",
                               "json", "--bags", str(tmp_path), "--run", "g", "--no-progress",
                               "--env-kwargs", "episode_max_steps:5",
                               "--ros-args", "--params-file", str(LIDAR_TD3)])
    assert code == 0, err
    assert outcomes(tmp_path / "g") == ["timeout"] * 3
    row, = json.loads(out)
    assert (row["goals"], row["collisions"], row["timeouts"], row["aborted"]) == (0, 0, 3, 0)
    assert row["success"] == "0/3" and row["spl"] == 0.0  # SPL: 0 for every failed episode
    assert "proportional: 0/3 goals" in err
    markdown = (tmp_path / "g" / "table.md").read_text()
    assert markdown.startswith("| agent | goals [episodes] | collisions [episodes] | timeouts "
                               "[episodes] | aborted [episodes] | success [n/total] | SPL")


def test_a_person_table_heads_with_full_runs_not_goals(tmp_path: Path) -> None:
    code, out, err = run_main(["--baseline", "dwa_heading", "--episodes", "2", "--seed", "1000",
                               "--format", "json", "--bags", str(tmp_path), "--run", "p",
                               "--no-progress", "--env-kwargs", "episode_max_steps:5",
                               "--ros-args", "--params-file",
                               str(CONFIG / "env_person_omni.yaml")])
    assert code == 0, err
    ends = outcomes(tmp_path / "p")
    assert goals(tmp_path / "p") == [None, None]  # the sim's unused goal is not recorded
    row, = json.loads(out)
    assert row["full runs"] == ends.count("timeout") and row["collisions"] == ends.count(
        "collision") and row["full runs"] + row["collisions"] == 2
    assert "goals" not in row and "success" not in row and "spl" not in row
    assert row["full_runs"] == f"{ends.count('timeout')}/2"  # the metrics' headline column
    assert "heading_error_mean_rad" not in row  # a goal's column: not in a goal-less table
    assert row["lin_vel_mean_mps"] is not None  # averaged over every episode, none succeeds
    assert f"dwa_heading: {ends.count('timeout')}/2 full runs" in err
    assert "goals" not in err


def _episodes(outcomes: list[str], success: list[float]) -> pd.DataFrame:
    """Judged episodes of agent ``a``: Table 1's columns unknown but for success and SPL."""
    return pd.DataFrame({**{c: math.nan for c in TABLE1_COLUMNS}, "agent": "a",
                         "outcome": outcomes, "success": success,
                         "spl": [s * 0.5 for s in success], "error": ""})


def test_the_headline_is_the_metrics_rule_whatever_the_task_is_called() -> None:
    """Episodes without a goal (no success judged) head with full runs, k/n, and no goal's
    columns, by ``pic4rl_metrics``' rule (``groups.headline``), not by the task's name;
    episodes with one head with goals, named as the task names them."""
    nan = math.nan
    goal_less = aggregate(_episodes(["timeout", "collision", "timeout"], [nan] * 3), over="all")
    for task in ("personMonitoring", "goToPose"):
        row, = json.loads(tester.render_table(goal_less, task, "json", with_std=False))
        assert (row["full runs"], row["collisions"], row["aborted"], row["full_runs"]) == (
            2, 1, 0, "2/3")
        assert not {"goals", "timeouts", "success", "spl", "heading_error_mean_rad"} & set(row)
    goal = aggregate(_episodes(["goal", "collision", "timeout", "goal"], [1.0, 0.0, 0.0, 1.0]))
    row, = json.loads(tester.render_table(goal, "vineyard", "json", with_std=False))
    assert (row["row ends"], row["collisions"], row["timeouts"], row["success"]) == (
        2, 1, 1, "2/4")
    assert row["spl"] == 0.25 and "full_runs" not in row and "full runs" not in row
