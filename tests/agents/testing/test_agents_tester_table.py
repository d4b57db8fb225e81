"""``pic4rl-test``'s printed table: episodes per outcome, the task's own headline first, SPL
where it applies; a personMonitoring run (no goal: its normal end is the time budget) prints
its full runs, never "0/N goals" or a success rate. Counts are checked against the bags'
outcomes and against what the short episodes force (5 steps: every episode times out)."""

from __future__ import annotations

import contextlib
import io
import json
from pathlib import Path

from agents_helpers import CONFIG, LIDAR_TD3

from pic4rl_agents.testing import tester
from pic4rl_metrics.tables.batch import compute


def run_main(argv: list[str]) -> tuple[int, str, str]:
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = tester.main(argv)
    return code, out.getvalue(), err.getvalue()


def outcomes(run: Path) -> list[str]:
    result = compute([run])
    assert not result.failed
    return [str(e.facts.outcome.value) for e in result.episodes]


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
    row, = json.loads(out)
    assert row["full runs"] == ends.count("timeout") and row["collisions"] == ends.count(
        "collision") and row["full runs"] + row["collisions"] == 2
    assert "goals" not in row and "success" not in row and "spl" not in row
    assert row["lin_vel_mean_mps"] is not None  # averaged over every episode, none succeeds
    assert f"dwa_heading: {ends.count('timeout')}/2 full runs" in err
    assert "goals" not in err
