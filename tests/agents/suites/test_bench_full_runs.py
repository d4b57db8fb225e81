"""``pic4rl-bench``'s table heads a task without a goal (person monitoring) with its full runs,
k/n with its Wilson interval, as the metrics' tables do (``groups.headline``), not with "–"
for success; its leaderboard ranks by them and leaves SPL out; a goal task's row, header and
leaderboard stay as they were. Episodes are synthetic rows with known outcomes, so every count
is known by hand."""

from __future__ import annotations

import math
from pathlib import Path

import pandas as pd
import pytest
import yaml

from pic4rl_agents.suites import table as benchtable
from pic4rl_agents.suites.suite import Suite, load_suite
from pic4rl_metrics.tables.aggregate import wilson_interval

REPO = Path(__file__).resolve().parents[3]
NAN = math.nan


def _suite(tmp_path: Path, *, person: bool = True) -> Suite:
    """goto (proportional, indoor:0) and, with ``person``, person (dwa_heading on person:101
    and person:102): three table rows."""
    (tmp_path / "env.yaml").write_text(yaml.safe_dump({
        "sim": {"ros__parameters": {"robot": "jackal", "world": "indoor", "world_variant": 0}},
        "nav_env": {"ros__parameters": {"task": "goToPose", "sensor": "lidar",
                                        "episode_max_steps": 30}}}))
    tasks = [{"name": "goto", "env": "env.yaml", "baselines": ["proportional"],
              "pairs": [{"episodes": 3}]}]
    if person:
        tasks.append({"name": "person", "env": str(REPO / "config" / "env_person_omni.yaml"),
                      "baselines": ["dwa_heading"], "worlds": ["person:101", "person:102"],
                      "pairs": [{"episodes": 5}]})
    (tmp_path / "suite.yaml").write_text(yaml.safe_dump({"suite": "s", "bags": "bags",
                                                         "tasks": tasks}))
    return load_suite(tmp_path / "suite.yaml")


#: Per row (by world): each episode's (outcome, success, SPL, mean speed).
EPISODES = {
    "indoor:0": [("goal", 1.0, 0.8, 0.3), ("collision", 0.0, 0.0, 0.1),
                 ("goal", 1.0, 0.6, 0.5)],
    # full runs 3 of the 5 that ran: speed averaged over the full runs, (0.2+0.4+0.6)/3
    "person:101": [("timeout", NAN, NAN, 0.2), ("timeout", NAN, NAN, 0.4),
                   ("collision", NAN, NAN, 9.0), ("timeout", NAN, NAN, 0.6),
                   ("diverged", NAN, NAN, 9.0)],
    "person:102": [("timeout", NAN, NAN, 0.5)] * 4,
}


def _judged(suite: Suite) -> tuple[pd.DataFrame, tuple[str, ...], None]:
    rows = [{**cell.row, "bag": f"{cell.name}/e{k}", "outcome": outcome, "success": success,
             "spl": spl, "lin_vel_mean_mps": speed, "error": ""}
            for cell in suite.cells
            for k, (outcome, success, spl, speed) in enumerate(EPISODES[cell.row["world"]])]
    return pd.DataFrame(rows), (), None


def _ci(k: int, n: int) -> str:
    low, high = wilson_interval(k, n)
    return f"[{low:.2f}, {high:.2f}]"


def test_a_person_row_heads_with_its_full_runs_and_a_goal_row_with_success(
        tmp_path: Path) -> None:
    suite = _suite(tmp_path)
    header, rows, _ = benchtable.build_rows(suite, {}, _judged(suite))
    assert header[5:10] == ("n", "success", "success 95% CI", "full runs", "full runs 95% CI")
    cell = {(r[2], c): r[header.index(c)] for r in rows for c in header}
    speed, spl = "v mean [m/s]", "SPL [-]"
    assert [cell["indoor:0", c] for c in ("n", "success", "success 95% CI", "full runs",
                                          "full runs 95% CI", spl, speed)] == [
        "3", "2/3", _ci(2, 3), None, None, "0.47", "0.40"]  # speed: the 2 successes'
    assert [cell["person:101", c] for c in ("n", "success", "success 95% CI", "full runs",
                                            "full runs 95% CI", spl, speed)] == [
        "5", None, None, "3/5", _ci(3, 5), None, "0.40"]  # speed: the 3 full runs'
    assert [cell["person:102", c] for c in ("full runs", "full runs 95% CI")] == [
        "4/4", _ci(4, 4)]
    assert {r[-1] for r in rows} == {"ok"}


def test_a_person_leaderboard_ranks_by_full_runs_without_spl(tmp_path: Path) -> None:
    suite = _suite(tmp_path)
    header, rows, _ = benchtable.build_rows(suite, {}, _judged(suite))
    boards = benchtable.leaderboards(header, rows)
    person = boards["person"].splitlines()
    assert [c.strip() for c in person[0].split("|")[1:-1]] == [
        "rank", "agent", "world", "robot", "pairs", "n", "full runs", "full runs 95% CI",
        "status"]
    assert [[c.strip() for c in line.split("|")[1:-1]][:7] for line in person[2:]] == [
        ["1", "dwa_heading", "person:102", "omni", "episodes5_s0", "4", "4/4"],
        ["2", "dwa_heading", "person:101", "omni", "episodes5_s0", "5", "3/5"]]
    goto = boards["goto"].splitlines()
    assert [c.strip() for c in goto[0].split("|")[1:-1]] == [
        "rank", "agent", "world", "robot", "pairs", "n", "success", "success 95% CI", "SPL",
        "status"]
    assert [c.strip() for c in goto[2].split("|")[1:-1]] == [
        "1", "proportional", "indoor:0", "jackal", "episodes3_s0", "3", "2/3", _ci(2, 3),
        "0.47", "ok"]
    fig = benchtable.success_figure("person", header, rows)  # bars: the full-run rates
    assert [round(b.get_width(), 6) for b in fig.axes[0].patches] == [0.6, 1.0]
    assert fig.axes[0].get_xlabel().startswith("full-run rate")


def test_a_goal_only_suite_keeps_its_columns(tmp_path: Path) -> None:
    suite = _suite(tmp_path, person=False)
    header, rows, _ = benchtable.build_rows(suite, {}, _judged(suite))
    assert header == benchtable._header(benchtable.LAYOUTS["paper"])
    assert "full runs" not in header and "full runs 95% CI" not in header
    (row,) = rows
    assert row[5:8] == ["3", "2/3", _ci(2, 3)]


@pytest.mark.parametrize("person", [True, False])
def test_a_failed_row_keeps_the_tables_width(tmp_path: Path, person: bool) -> None:
    suite = _suite(tmp_path, person=person)
    judged = _judged(suite)
    frame = judged[0][judged[0]["world"] != "indoor:0"]  # the goto cell judged nothing
    header, rows, _ = benchtable.build_rows(suite, {suite.cells[0].name: "boom"},
                                            (frame, (), None))
    assert all(len(r) == len(header) for r in rows)
    assert rows[0][5] == "0" and rows[0][-1].endswith(": boom")
