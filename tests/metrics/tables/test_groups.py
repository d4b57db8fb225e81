"""Tables never pool tasks or world sets (issue 37.6): ``compare``, ``compare --paired`` and
the report's leaderboard and paired tables split the episodes by task and world set
(``tables.groups``), a column shows only where it is defined (BARN score in BARN worlds, full
runs instead of success for a task without a goal), and pairs are made within a group.

The bags (real rosbag2, written into a temporary directory): ``explorer`` drives two indoor
pairs (2/2 goals) and three BARN worlds (2/3), ``td3_lidar`` the same two indoor pairs only
(1/2), ``heading`` three person-monitoring runs without a goal (timeout, timeout, collision:
2/3 full runs), and ``teleop`` is a real log with no task, world, goal or outcome. Every track
is a straight drive at 1 m/s sampled every 0.1 s, so lengths and times are known by hand.
"""

from __future__ import annotations

import io
import json
import math
from html.parser import HTMLParser
from pathlib import Path

import pandas as pd
import pytest
from metrics_helpers import result_row

from pic4rl_base.errors import ConfigError
from pic4rl_metrics.cli import commands as cli
from pic4rl_metrics.tables.aggregate import aggregate
from pic4rl_metrics.tables.batch import compute
from pic4rl_metrics.tables.groups import parse_by, render_groups, split
from pic4rl_metrics.tables.results import ERROR_COLUMN, ID_COLUMNS, METRIC_COLUMNS, table_columns
from pic4rl_metrics.tables.text import render_comparison
from pic4rl_metrics.synthetic.synthetic import straight_line, write_episode_bag

EXACT = 1e-9
GOTO = "goToPose/lidar"


def _drive(root: Path, name: str, *, length_m: float, facts: dict[str, object],
           outcome: str | None, y: float = 0.0, goal: tuple[float, float] | None = None) -> None:
    """A straight drive of ``length_m`` at 1 m/s from (0, y) along +x."""
    track = straight_line(1.0, length_m, start=(0.0, y, 0.0))
    if goal is not None:
        facts = {**facts, "start": [0.0, y, 0.0], "goal": list(goal)}
    write_episode_bag(root / name, track, goal=goal, facts=facts, outcome=outcome)


@pytest.fixture(scope="module")
def mixed(tmp_path_factory: pytest.TempPathFactory) -> Path:
    root = tmp_path_factory.mktemp("groups") / "bags"
    for agent, ends in (("explorer", ("goal", "goal")), ("td3_lidar", ("goal", "timeout"))):
        for k, end in enumerate(ends):  # pair k: (0, k) -> (3, k); a timeout stops at 1.5 m
            facts = {"agent": agent, "task": GOTO, "world": "indoor:0", "run": "r"}
            _drive(root, f"{agent}_indoor{k}", length_m=3.0 if end == "goal" else 1.5,
                   facts=facts, outcome=end, y=float(k), goal=(3.0, float(k)))
    for variant, end in ((3, "goal"), (7, "collision"), (9, "goal")):
        facts = {"agent": "explorer", "task": "goToPose/depth", "world": f"barn:{variant}",
                 "reference_path_m": 3.0, "run": "r"}
        _drive(root, f"explorer_barn{variant}", length_m=3.0 if end == "goal" else 1.5,
               facts=facts, outcome=end, goal=(3.0, 0.0))
    for k, (end, length) in enumerate((("timeout", 2.0), ("collision", 1.0), ("timeout", 4.0))):
        facts = {"agent": "heading", "task": "personMonitoring", "world": "person:0"}
        _drive(root, f"heading_{k}", length_m=length, facts=facts, outcome=end)
    _drive(root, "teleop_log", length_m=2.0, facts={"agent": "teleop"}, outcome=None)
    return root


def _run(capsys: pytest.CaptureFixture[str], *argv: object) -> tuple[int, str, str]:
    code = cli.main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


def _by_group(records: list[dict[str, object]]) -> dict[tuple[object, ...], dict]:
    return {(r.get("task"), r.get("worlds"), r["agent"]): r for r in records}


def test_an_agent_in_two_world_sets_gets_a_row_in_each(capsys, mixed: Path) -> None:
    code, out, err = _run(capsys, "compare", "--format", "json", mixed)
    assert code == 0, err
    rows = _by_group(json.loads(out))
    assert set(rows) == {("goToPose", "indoor", "explorer"), ("goToPose", "indoor", "td3_lidar"),
                         ("goToPose", "barn", "explorer"),
                         ("personMonitoring", "person", "heading"),
                         ("(unknown)", "(unknown)", "teleop")}
    # 5 episodes of the explorer are two rows, never "4/5"
    assert rows["goToPose", "indoor", "explorer"]["success"] == "2/2"
    assert rows["goToPose", "barn", "explorer"]["success"] == "2/3"
    assert rows["goToPose", "indoor", "td3_lidar"]["success"] == "1/2"
    # path over the successes: 3 m in each group
    assert rows["goToPose", "barn", "explorer"]["path_length_m"] == pytest.approx(3.0, abs=EXACT)


def test_a_task_without_a_goal_heads_with_its_full_runs(capsys, mixed: Path) -> None:
    code, out, _ = _run(capsys, "compare", "--format", "json", mixed)
    heading = _by_group(json.loads(out))["personMonitoring", "person", "heading"]
    assert heading["full_runs"] == "2/3" and "success" not in heading
    # trajectory columns over the full runs (2 m and 4 m), not the 1 m collision
    assert heading["path_length_m"] == pytest.approx(3.0, abs=EXACT)
    assert heading["n_averaged"] == 2
    code, out, _ = _run(capsys, "compare", mixed)
    person = out.split("== task personMonitoring, worlds person ==")[1].split("==")[0]
    assert "full runs" in person and "2/3" in person
    assert "success" not in person and "0/3" not in person
    assert "cum. heading" not in person  # needs a goal: not a column of this group


def test_text_tables_have_a_header_per_group_in_order(capsys, mixed: Path) -> None:
    code, out, _ = _run(capsys, "compare", mixed)
    heads = [line for line in out.splitlines() if line.startswith("== ")]
    # in order of first appearance: the bags are read in name order, explorer_barn3 first
    assert heads == ["== task goToPose, worlds barn ==", "== task goToPose, worlds indoor ==",
                     "== task personMonitoring, worlds person ==",
                     "== task (unknown), worlds (unknown) =="]
    code, out, _ = _run(capsys, "compare", "--format", "markdown", mixed)
    assert out.count("### task ") == 4
    code, out, _ = _run(capsys, "compare", "--format", "latex", mixed)
    assert out.count(r"\begin{table*}") == 4
    assert r"\caption{task goToPose, worlds barn}" in out


def test_csv_leads_each_row_with_its_group(capsys, mixed: Path) -> None:
    code, out, _ = _run(capsys, "compare", "--format", "csv", mixed)
    table = pd.read_csv(io.StringIO(out), dtype=str, keep_default_na=False)
    assert list(table.columns[:3]) == ["task", "worlds", "agent"]
    assert table[table["agent"] == "explorer"]["worlds"].tolist() == ["barn", "indoor"]
    person = table[table["agent"] == "heading"].iloc[0]
    assert person["full runs [n/total]"] == "2/3" and person["success [n/total]"] == ""


def test_an_explicit_by_puts_the_groups_in_the_rows(capsys, mixed: Path) -> None:
    code, out, _ = _run(capsys, "compare", "--by", "agent,task,world_set", "--format", "json",
                        mixed)
    rows = json.loads(out)
    names = [r["agent / task / world_set"] for r in rows]
    assert "explorer / goToPose/lidar / indoor" in names
    assert "explorer / goToPose/depth / barn" in names  # one flat table, no group keys
    assert all("worlds" not in r for r in rows)
    with pytest.raises(SystemExit) as exit_:
        cli.main(["compare", "--by", "agent,colour", str(mixed)])
    assert exit_.value.code == 2 and "--by 'colour' is not a row key" in capsys.readouterr().err


def test_parse_by_checks_each_column() -> None:
    assert parse_by("agent, world_set,agent") == ("agent", "world_set")
    with pytest.raises(ConfigError, match="did you mean 'world'"):
        parse_by("wrld")


def test_one_group_is_the_paper_table_as_before(mixed: Path) -> None:
    frame = compute(sorted(mixed.glob("*_indoor*"))).frame
    assert len(split(frame)) == 1
    columns = table_columns(frame)
    for fmt in ("table", "markdown", "csv", "latex", "json"):
        before = render_comparison(aggregate(frame), fmt, columns=columns)
        assert render_groups(frame, fmt, columns=table_columns) == before


def test_no_barn_columns_outside_barn_worlds_nor_for_a_log_without_goal(capsys,
                                                                        mixed: Path) -> None:
    code, out, _ = _run(capsys, "compute", "--format", "json", mixed)
    rows = {Path(r["bag"]).name: r for r in json.loads(out)}
    # BARN: OT = 3 m / 2 m/s = 1.5 s; AT = 3 s - 0.1 s (0.1 m off the start) < 2 OT: 1/2
    assert rows["explorer_barn3"]["barn_score"] == pytest.approx(0.5, abs=EXACT)
    assert rows["explorer_barn3"]["barn_time_s"] == pytest.approx(2.9, abs=EXACT)
    for name in ("explorer_indoor0", "td3_lidar_indoor1", "heading_0", "teleop_log"):
        assert rows[name]["barn_score"] is None and rows[name]["barn_time_s"] is None, name
    # no goal: no success either (person monitoring, the real log)
    assert rows["heading_0"]["success"] is None and rows["teleop_log"]["success"] is None


def test_paired_comparisons_stay_within_a_group(capsys, mixed: Path) -> None:
    code, out, err = _run(capsys, "compare", "--paired", "td3_lidar", "--format", "json", mixed)
    assert code == 0, err
    (only,) = json.loads(out)
    assert (only["task"], only["worlds"]) == ("goToPose", "indoor")
    assert (only["agent"], only["reference"]) == ("explorer", "td3_lidar")
    # the explorer's 3 BARN episodes are in another group: not unpaired, not compared
    assert only["couples"] == 2 and only["unpaired_agent"] == 0
    assert only["success"] == 1.0 and only["reference_success"] == 0.5
    code, out, _ = _run(capsys, "compare", "--paired", "heading", "--format", "json", mixed)
    assert json.loads(out) == []  # alone in its group: compared with nobody
    code, out, _ = _run(capsys, "compare", "--paired", "heading", mixed)
    assert "==" not in out.split("\n\n")[0]  # an empty table, under no group's header
    code, out, _ = _run(capsys, "compare", "--paired", "nobody", mixed)
    assert code == 2 and "'nobody': no episode of that agent" in out + _


class _Tables(HTMLParser):
    """Each table's rows by id, and the h3 headings."""

    def __init__(self) -> None:
        super().__init__()
        self.rows: dict[str, list[list[str]]] = {}
        self.h3: list[str] = []
        self._table: str | None = None
        self._cell: list[str] | None = None
        self._h3 = False

    def handle_starttag(self, tag: str, attrs: list[tuple[str, str | None]]) -> None:
        if tag == "table":
            self._table = str(dict(attrs).get("id"))
            self.rows[self._table] = []
        elif tag == "tr" and self._table:
            self.rows[self._table].append([])
        elif tag in ("td", "th") and self._table:
            self._cell = []
        elif tag == "h3":
            self._h3 = True
            self.h3.append("")

    def handle_endtag(self, tag: str) -> None:
        if tag in ("td", "th") and self._cell is not None and self._table:
            self.rows[self._table][-1].append("".join(self._cell).strip())
            self._cell = None
        elif tag == "table":
            self._table = None
        elif tag == "h3":
            self._h3 = False

    def handle_data(self, data: str) -> None:
        if self._cell is not None:
            self._cell.append(data)
        if self._h3:
            self.h3[-1] += data


def test_the_report_has_a_leaderboard_and_paired_table_per_group(mixed: Path,
                                                                 tmp_path: Path) -> None:
    out = tmp_path / "report.html"
    assert cli.main(["report", str(mixed), "--out", str(out)]) == 0
    page = _Tables()
    page.feed(out.read_text())
    boards = [v for k, v in page.rows.items() if k.startswith("leaderboard")]
    heads = ["task goToPose, worlds barn", "task goToPose, worlds indoor",
             "task personMonitoring, worlds person"]
    # a heading per table, in their order (the goal-less real log has a section of its own)
    assert page.h3[:3] == heads and len(boards) == 3
    barn, indoor, person = boards
    assert {r[0]: r[2].split(" ")[0] for r in indoor[1:]} == {"explorer": "2/2",
                                                              "td3_lidar": "1/2"}
    assert [(r[0], r[1], r[2].split(" ")[0]) for r in barn[1:]] == [("explorer", "3", "2/3")]
    assert not any("BARN score" in h for h in indoor[0])
    assert any(h.startswith("BARN score") for h in barn[0])
    assert person[0][2] == "full runs" and person[1][2].startswith("2/3")
    assert not any(h.startswith("SPL") for h in person[0])
    paired = {k: v for k, v in page.rows.items() if k.startswith("paired")}
    assert list(paired) == ["paired-2"]  # the one group with two agents: the second
    (row,) = paired["paired-2"][1:]
    assert row[:4] == ["explorer", "td3_lidar", "2", "2"] and row[4] == "0 + 0"
    assert math.isfinite(float(row[11]))


def test_full_runs_by_hand() -> None:
    """A group without a goal: full runs = timeouts over the runs that ended (an aborted one is
    out of n); quality means over the full runs; a goal group keeps its success rate."""
    nan = math.nan
    rows = [result_row(f"/b/p{k}", "heading", task="personMonitoring", world="person:0",
                       outcome=end, success=nan, path_length_m=length)
            for k, (end, length) in enumerate((("timeout", 2.0), ("timeout", 4.0),
                                               ("collision", 1.0), ("aborted", 9.0)))]
    rows.append(result_row("/b/g", "planner", outcome="timeout", success=0.0, path_length_m=5.0))
    frame = pd.DataFrame(rows, columns=[*ID_COLUMNS, *METRIC_COLUMNS, ERROR_COLUMN])
    person, goto = split(frame)
    agg = aggregate(frame.loc[list(person.rows)])
    row = agg.loc["heading"]
    assert (row["full_runs"], row["n_full_runs"], row["n_ran"]) == ("2/3", 2, 3)
    assert row["success"] == "–" and row["n_aborted"] == 1
    assert row["path_length_m_mean"] == pytest.approx(3.0) and row["n_averaged"] == 2
    planner = aggregate(frame.loc[list(goto.rows)]).loc["planner"]
    assert (planner["success"], planner["full_runs"], planner["n_full_runs"]) == ("0/1", "–", 0)
    assert person.label == "task personMonitoring, worlds person"
    assert goto.label == "task goal, worlds indoor"


@pytest.mark.parametrize(("world", "expected"), [
    ("barn:12", "barn"), ("indoor:0", "indoor"), ("barn_like:3", "barn_like"),
    ("maps/room.xml", "maps/room.xml"), ("barn:ci3", "barn:ci3"), ("", None), (None, None)])
def test_the_world_set_of_a_world_fact(world: str | None, expected: str | None) -> None:
    from pic4rl_metrics.contract import world_set

    assert world_set(world) == expected


@pytest.mark.parametrize(("task", "expected"), [
    ("goToPose/lidar", "goToPose"), ("goToPose/depth", "goToPose"),
    ("personMonitoring", "personMonitoring"), ("", None), (None, None)])
def test_the_task_of_a_task_fact(task: str | None, expected: str | None) -> None:
    from pic4rl_metrics.contract import task_name

    assert task_name(task) == expected
