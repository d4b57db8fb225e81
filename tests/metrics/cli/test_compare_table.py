"""``pic4rl-metrics compare --table barn``: BARN's protocol table (as ``pic4rl-bench``'s
``table: barn``) from bags alone, one row per agent whatever its name; episodes outside a BARN
world left out with a note, refused when none is left; every format; and the report's
leaderboard shows the same agent, counts, interval and score.

The bags (real rosbag2, in a temporary directory) are straight drives at 1 m/s sampled every
0.1 s, so every number is known by hand. BARN's time AT starts 0.1 m off the start: a 3 m
drive to its goal has AT = 2.9 s. Its score is OT / clip(AT, 2 OT, 8 OT), OT = the reference
path / 2 m/s: 0.5 for a 3 m reference (OT 1.5 s, AT clipped to 3 s), 0.5 / 2.9 for a 1 m one
(OT 0.5 s, AT inside [1, 4] s), 0 for a failure.

- ``my_gap_follower`` (a name this project never saw): goal (1 m reference), goal, collision,
  timeout: success 2/4, collision 1/4, timeout 1/4, score mean (0.5/2.9 + 0.5) / 4.
- ``dwa``: goal, goal, collision in BARN worlds (score mean 1/3) and one goal indoors.
"""

from __future__ import annotations

import csv
import io
import json
from html.parser import HTMLParser
from pathlib import Path

import pytest

from pic4rl_metrics.cli import commands as cli
from pic4rl_metrics.tables.aggregate import bootstrap_interval
from pic4rl_metrics.synthetic.synthetic import straight_line, write_episode_bag

GOTO = "goToPose/lidar"
#: Per bag: agent, world, reference path (m), outcome, length driven (m).
EPISODES = (
    ("my_gap_follower", "barn:0", 1.0, "goal", 3.0),
    ("my_gap_follower", "barn:6", 3.0, "goal", 3.0),
    ("my_gap_follower", "barn:12", 3.0, "collision", 1.5),
    ("my_gap_follower", "barn:18", 3.0, "timeout", 2.0),
    ("dwa", "barn:0", 3.0, "goal", 3.0),
    ("dwa", "barn:6", 3.0, "goal", 3.0),
    ("dwa", "barn:12", 3.0, "collision", 1.0),
    ("dwa", "indoor:0", None, "goal", 3.0),
)
#: Wilson 95 % intervals by hand: (p + z²/2n ± z √(p(1-p)/n + z²/4n²)) / (1 + z²/n), z = 1.96.
WILSON = {(2, 4): "[0.15, 0.85]", (1, 4): "[0.05, 0.70]", (2, 3): "[0.21, 0.94]",
          (1, 3): "[0.06, 0.79]", (0, 3): "[0.00, 0.56]"}
GAP_SCORES = (0.5 / 2.9, 0.5, 0.0, 0.0)
#: BARN's columns, as pic4rl-bench's ``table: barn`` prints them after its row keys.
BARN_HEADER = ["n", "success", "success 95% CI", "collision", "collision 95% CI", "timeout",
               "timeout 95% CI", "BARN time [s]", "BARN time 95% CI", "BARN score [-]",
               "BARN score 95% CI"]


@pytest.fixture(scope="module")
def bags(tmp_path_factory: pytest.TempPathFactory) -> Path:
    root = tmp_path_factory.mktemp("barn_table") / "bags"
    for k, (agent, world, reference, outcome, length) in enumerate(EPISODES):
        facts: dict[str, object] = {"agent": agent, "task": GOTO, "world": world, "run": "r",
                                    "start": [0.0, 0.0, 0.0], "goal": [3.0, 0.0]}
        if reference is not None:
            facts["reference_path_m"] = reference
        write_episode_bag(root / f"{agent}_{k}", straight_line(1.0, length), goal=(3.0, 0.0),
                          facts=facts, outcome=outcome)
    return root


def _run(capsys: pytest.CaptureFixture[str], *argv: object) -> tuple[int, str, str]:
    code = cli.main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


def _ci(values: tuple[float, ...]) -> str:
    return "[{:.2f}, {:.2f}]".format(*bootstrap_interval(values))


def test_each_agent_is_a_row_with_wilson_intervals_and_the_barn_score(capsys,
                                                                      bags: Path) -> None:
    code, out, err = _run(capsys, "compare", "--table", "barn", "--format", "json", bags)
    assert code == 0, err
    rows = {r["agent"]: r for r in json.loads(out)}
    assert list(rows) == ["dwa", "my_gap_follower"]  # bag order: dwa_4 sorts first
    assert list(rows["dwa"]) == ["agent", *BARN_HEADER]
    gap, dwa = rows["my_gap_follower"], rows["dwa"]
    assert [gap[c] for c in BARN_HEADER[:7]] == [
        "4", "2/4", WILSON[2, 4], "1/4", WILSON[1, 4], "1/4", WILSON[1, 4]]
    assert [dwa[c] for c in BARN_HEADER[:7]] == [
        "3", "2/3", WILSON[2, 3], "1/3", WILSON[1, 3], "0/3", WILSON[0, 3]]
    # BARN time over the successes (2.9 s each); the score over every judged episode
    assert (gap["BARN time [s]"], gap["BARN time 95% CI"]) == ("2.90", "[2.90, 2.90]")
    assert gap["BARN score [-]"] == "0.17"  # (0.1724 + 0.5 + 0 + 0) / 4 = 0.1681
    # bootstrap of the means of 4 draws: all four 0 (p 1/16 > 2.5 %) gives 0; the top 2.5 %
    # lies among the means with three 0.5 (three 0.5 and one 0: 1.5/4, p 1/32; above: 1/51)
    assert gap["BARN score 95% CI"] == _ci(GAP_SCORES) == "[0.00, 0.38]"
    assert (dwa["BARN time [s]"], dwa["BARN score [-]"]) == ("2.90", "0.33")
    # three draws of (0.5, 0.5, 0): all 0 has p 1/27, all 0.5 p 8/27: both > 2.5 %
    assert dwa["BARN score 95% CI"] == "[0.00, 0.50]"
    note, = err.splitlines()
    assert note.startswith("note: compare --table barn: left out 1 of 8 episode(s), not in a "
                           "BARN world (a world fact 'barn:<n>' or a reference_path_m fact): ")
    assert note.endswith("dwa_7")


def test_any_agent_name_given_on_the_command_line_is_a_row(capsys, bags: Path) -> None:
    """A ROS stack's real log named by ``--agent``: one more row, the same numbers."""
    code, out, err = _run(capsys, "compare", "--table", "barn", "--format", "json",
                          "--agent", "lab_planner_stack", *sorted(bags.glob("dwa_[456]")))
    assert code == 0 and err == ""
    (row,) = json.loads(out)
    assert row["agent"] == "lab_planner_stack"
    assert [row[c] for c in ("n", "success", "success 95% CI", "BARN score [-]")] == [
        "3", "2/3", WILSON[2, 3], "0.33"]


def test_every_format_holds_the_same_cells(capsys, bags: Path) -> None:
    _, out, _ = _run(capsys, "compare", "--table", "barn", "--format", "json", bags)
    want = {r["agent"]: r for r in json.loads(out)}
    _, out, _ = _run(capsys, "compare", "--table", "barn", "--format", "csv", bags)
    got = {r["agent"]: r for r in csv.DictReader(io.StringIO(out))}
    assert got == want  # no missing cell here: CSV's "" never stands in for a null
    _, out, _ = _run(capsys, "compare", "--table", "barn", "--format", "markdown", bags)
    lines = out.splitlines()
    assert lines[0] == "| " + " | ".join(["agent", *BARN_HEADER]) + " |"
    assert lines[2].split(" | ")[:3] == ["| dwa", "3", "2/3"]
    _, out, _ = _run(capsys, "compare", "--table", "barn", "--format", "latex", bags)
    assert out.startswith(r"\begin{tabular}") and r"\end{tabular}" in out
    gap = next(line for line in out.splitlines() if line.startswith("my"))
    assert gap.startswith(r"my\_gap\_follower & 4 & 2/4 & [0.15, 0.85] & 1/4")
    _, out, _ = _run(capsys, "compare", "--table", "barn", bags)
    assert out.splitlines()[0].split()[:3] == ["agent", "n", "success"]
    assert any(line.split()[:3] == ["my_gap_follower", "4", "2/4"] for line in out.splitlines())


def test_a_task_and_world_set_per_row_with_by(capsys, bags: Path) -> None:
    code, out, _ = _run(capsys, "compare", "--table", "barn", "--by", "agent,world_set",
                        "--format", "csv", bags)
    assert code == 0
    rows = list(csv.DictReader(io.StringIO(out)))
    assert [(r["agent"], r["world_set"], r["n"]) for r in rows] == [
        ("dwa", "barn", "3"), ("my_gap_follower", "barn", "4")]


@pytest.mark.bad_input
def test_no_barn_episode_is_refused_in_one_line(capsys, bags: Path) -> None:
    code, out, err = _run(capsys, "compare", "--table", "barn", bags / "dwa_7")
    assert code == 2 and out == ""
    assert err == (f"pic4rl-metrics: compare --table barn: none of the 1 episode(s) is in a "
                   f"BARN world (a world fact 'barn:<n>' or a reference_path_m fact): "
                   f"{bags / 'dwa_7'}\n")


@pytest.mark.bad_input
@pytest.mark.parametrize(("option", "named"), [
    (("--paired", "dwa"), "--paired"), (("--with-std",), "--with-std"),
    (("--over", "all"), "--over all")])
def test_another_tables_option_is_refused_before_any_bag(capsys, tmp_path: Path,
                                                         option: tuple[str, ...],
                                                         named: str) -> None:
    code, out, err = _run(capsys, "compare", "--table", "barn", *option, tmp_path / "none")
    assert code == 2 and out == ""
    assert err == (f"pic4rl-metrics: compare --table barn: {named} is not an option of a "
                   "protocol's table (its columns are fixed, as pic4rl-bench's)\n")


def test_the_layouts_columns_are_computed_whatever_metrics_names(capsys, bags: Path) -> None:
    code, out, _ = _run(capsys, "compare", "--table", "barn", "--metrics", "path_length_m",
                        "--format", "json", bags / "dwa_4", bags / "dwa_6")
    assert code == 0
    (row,) = json.loads(out)
    assert (row["success"], row["BARN score [-]"], row["BARN time [s]"]) == ("1/2", "0.25",
                                                                             "2.90")


def test_a_reference_path_fact_makes_a_barn_episode_anywhere(capsys, tmp_path: Path) -> None:
    """The metrics' own test (their ``barn_world`` input): a lab's BARN-like world with its
    reference path is judged; a world without either is left out."""
    for name, world, reference in (("lab", "lab:3", 3.0), ("office", "office:1", None)):
        facts: dict[str, object] = {"agent": "stack", "task": GOTO, "world": world}
        if reference is not None:
            facts["reference_path_m"] = reference
        write_episode_bag(tmp_path / name, straight_line(1.0, 3.0), goal=(3.0, 0.0),
                          facts=facts, outcome="goal")
    code, out, err = _run(capsys, "compare", "--table", "barn", "--format", "json", tmp_path)
    assert code == 0
    (row,) = json.loads(out)
    assert (row["agent"], row["n"], row["BARN score [-]"]) == ("stack", "1", "0.50")
    assert "left out 1 of 2 episode(s)" in err and err.rstrip().endswith("office")


def test_the_paper_table_as_the_bench_prints_it(capsys, bags: Path) -> None:
    code, out, _ = _run(capsys, "compare", "--table", "paper", "--format", "json",
                        *sorted(bags.glob("dwa_*")))
    assert code == 0  # the paper's table takes every world: one group per world set
    rows = {r["worlds"]: r for r in json.loads(out)}
    assert [rows["indoor"][c] for c in ("agent", "n", "success", "success 95% CI")] == [
        "dwa", "1", "1/1", "[0.21, 1.00]"]
    assert list(rows["barn"])[:6] == ["task", "worlds", "agent", "n", "success",
                                      "success 95% CI"]
    assert rows["barn"]["SPL [-]"] is not None and "BARN score [-]" not in rows["barn"]


class _Leaderboards(HTMLParser):
    """The cells of each leaderboard table's rows, in page order."""

    def __init__(self) -> None:
        super().__init__()
        self.boards: list[list[list[str]]] = []
        self._in = False

    def handle_starttag(self, tag: str, attrs: list[tuple[str, str | None]]) -> None:
        if tag == "table":
            self._in = str(dict(attrs).get("id")).startswith("leaderboard")
            if self._in:
                self.boards.append([])
        elif tag == "tr" and self._in:
            self.boards[-1].append([])
        elif tag in ("td", "th") and self._in:
            self.boards[-1][-1].append("")

    def handle_endtag(self, tag: str) -> None:
        if tag == "table":
            self._in = False

    def handle_data(self, data: str) -> None:
        if self._in and self.boards[-1] and self.boards[-1][-1]:
            self.boards[-1][-1][-1] += data.strip()


def test_the_report_shows_an_agent_never_seen_as_one_more_row(bags: Path,
                                                               tmp_path: Path) -> None:
    out = tmp_path / "report.html"
    assert cli.main(["report", str(bags), "--out", str(out)]) == 0
    page = _Leaderboards()
    page.feed(out.read_text())
    barn = page.boards[0]  # the BARN group's (the indoor episode has a table of its own)
    rows = {r[0]: r for r in barn[1:]}
    assert sorted(rows) == ["dwa", "my_gap_follower"]
    # the same counts, interval and score as compare --table barn, in the report's own words
    assert [rows["my_gap_follower"][c] for c in (1, 2, 3, 7)] == ["4", "2/4 (50%)", "[15, 85]%",
                                                                "0.17"]
    assert [rows["dwa"][c] for c in (1, 2, 3, 7)] == ["3", "2/3 (67%)", "[21, 94]%", "0.33"]
