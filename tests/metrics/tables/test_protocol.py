"""``tables.protocol``: a benchmark protocol's cells from a result frame (rows as ``compute``
makes them, outcomes and scores known by hand): the rates' Wilson intervals, a task without a
goal heading with its full runs, error rows counted apart, and one table per task and world
set, as ``compare`` lays them out."""

from __future__ import annotations

import json
import math

import pandas as pd
from metrics_helpers import result_row

from pic4rl_metrics.tables.protocol import LAYOUTS, header, protocol_cells, render_protocol

NAN = math.nan
#: Wilson 95 % intervals by hand (z = 1.96), two decimals.
WILSON = {(2, 3): "[0.21, 0.94]", (1, 2): "[0.09, 0.91]"}


def _frame(*rows: dict[str, object]) -> pd.DataFrame:
    return pd.DataFrame(list(rows))


def _episode(agent: str, outcome: str, *, task: str = "goToPose/lidar", world: str = "barn:1",
             score: float = NAN, **metrics: object) -> dict[str, object]:
    success = {"goal": 1.0, "collision": 0.0, "timeout": 0.0}.get(outcome, NAN)
    if task == "personMonitoring":
        success = NAN
    row = result_row(f"/bags/{agent}/{len(metrics)}", agent, success=success, barn_score=score,
                     **metrics)
    row.update(outcome=outcome, task=task, world=world)
    return row


def test_a_task_without_a_goal_heads_with_its_full_runs() -> None:
    frame = _frame(*(_episode("heading", end, task="personMonitoring", world="person:0")
                     for end in ("timeout", "timeout", "collision")))
    columns, cells = protocol_cells(frame, ["agent"], LAYOUTS["paper"])
    assert columns[:5] == ("n", "success", "success 95% CI", "full runs", "full runs 95% CI")
    assert cells[("heading",)][:5] == ["3", None, None, "2/3", WILSON[2, 3]]


def test_an_unreadable_bag_is_out_of_n_and_of_every_rate() -> None:
    frame = _frame(_episode("dwa", "goal", score=0.5, barn_time_s=2.9),
                   _episode("dwa", "collision", score=0.0),
                   {**result_row("/bags/dwa/bad", "dwa", error="BagError: truncated"),
                    "world": "barn:2"})
    columns, cells = protocol_cells(frame, ["agent"], LAYOUTS["barn"])
    assert columns == header(LAYOUTS["barn"])
    row = dict(zip(columns, cells[("dwa",)]))
    assert [row[c] for c in ("n", "success", "success 95% CI", "collision", "timeout")] == [
        "2", "1/2", WILSON[1, 2], "1/2", "0/2"]
    assert (row["BARN score [-]"], row["BARN time [s]"]) == ("0.25", "2.90")


def test_each_task_is_a_table_of_its_own() -> None:
    frame = _frame(_episode("dwa", "goal", score=0.5), _episode("dwa", "collision", score=0.0),
                   _episode("dwa", "goal", task="vineyard", score=0.4))
    records = json.loads(render_protocol(frame, "json", LAYOUTS["barn"]))
    assert [(r["task"], r["worlds"], r["agent"], r["n"], r["success"], r["BARN score [-]"])
            for r in records] == [("goToPose", "barn", "dwa", "2", "1/2", "0.25"),
                                  ("vineyard", "barn", "dwa", "1", "1/1", "0.40")]
    text = render_protocol(frame, "markdown", LAYOUTS["barn"])
    assert "### task goToPose, worlds barn\n" in text and "### task vineyard, worlds barn\n" in text
    flat = json.loads(render_protocol(frame, "json", LAYOUTS["barn"], by=("agent", "task")))
    assert [(r["agent"], r["task"], r["success"]) for r in flat] == [
        ("dwa", "goToPose/lidar", "1/2"), ("dwa", "vineyard", "1/1")]


def test_no_episode_gives_the_header_alone() -> None:
    text = render_protocol(pd.DataFrame(columns=["agent", "success"]), "csv", LAYOUTS["barn"])
    assert text == ",".join(["agent", *header(LAYOUTS["barn"])]) + "\n"
