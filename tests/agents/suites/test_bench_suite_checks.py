"""``pic4rl-bench`` checks a suite whole when it reads it: every world and variant (built as a
cell builds it), robot, pairs file and agent path, in one line and exit code 2 before any cell
runs; and a row whose cell failed is never ranked on the leaderboard."""

from __future__ import annotations

from pathlib import Path

import pytest
import yaml

from pic4rl_agents.suites import runner as bench
from pic4rl_agents.suites import table as benchtable
from pic4rl_agents.suites.suite import load_suite
from pic4rl_sim.engine.worlds.generators import WORLD_TABLE

REPO = Path(__file__).resolve().parents[3]


def _suite(tmp_path: Path, **task: object) -> Path:
    (tmp_path / "env.yaml").write_text(yaml.safe_dump({
        "sim": {"ros__parameters": {"robot": "jackal", "world": "indoor", "world_variant": 0}},
        "nav_env": {"ros__parameters": {"task": "goToPose", "sensor": "lidar",
                                        "episode_max_steps": 30}}}))
    (tmp_path / "suite.yaml").write_text(yaml.safe_dump({
        "suite": "s", "bags": "bags",
        "tasks": [{"name": "goto", "env": "env.yaml", "baselines": ["dwa"],
                   "pairs": [{"episodes": 1}], **task}]}))
    return tmp_path / "suite.yaml"


BARN_300 = ("tasks[0].worlds: barn:300: sim parameters: world_variant: 300 is invalid; "
            "expected a BARN world index in [0, 299] (world: barn)")


@pytest.mark.bad_input
@pytest.mark.parametrize(("task", "message"), [
    ({"worlds": ["barn:300"]}, BARN_300),
    ({"worlds": ["barnx:3"]}, "tasks[0].worlds: barnx:3: sim parameters: world: 'barnx' is "
     f"invalid; expected a generator ({', '.join(WORLD_TABLE)}) or a path ending in .xml; "
     "did you mean 'barn'?"),
    # a group's good variant does not hide its bad one
    ({"worlds": [{"world": "barn", "variants": [0, 300], "label": "t"}]}, BARN_300),
    ({"worlds": ["indoor:1", "missing.xml"]}, "tasks[0].worlds: missing.xml: sim parameters: "),
    ({"robots": ["jackall"]}, "tasks[0].robots: jackall: sim parameters: robot: unknown key "
     "'jackall'; did you mean 'jackal'?"),
    ({"pairs": [{"file": "bad.json"}]}, "tasks[0].pairs: file_bad: "),
    ({"pairs": [{"file": "nope.json"}]}, "tasks[0].pairs.file: 'nope.json' is invalid; "
     "expected an existing file or directory"),
    ({"agents": {"a": "nowhere"}}, "tasks[0].agents.a: 'nowhere' is invalid; expected an "
     "existing file or directory"),
    ({"agents": {"a": "empty"}}, "tasks[0].agents.a: --agent "),
    # an agent on a robot of the task it was not trained on
    ({"agents": {"td3": str(REPO / "checkpoints" / "td3_lidar")}, "robots": ["jackal", "burger"]},
     "tasks[0].agents.td3: --agent "),
])
def test_a_bad_suite_exits_2_in_one_line_before_any_cell(
        tmp_path: Path, capsys: pytest.CaptureFixture, task: dict, message: str) -> None:
    (tmp_path / "bad.json").write_text('{"goals": 3}')
    (tmp_path / "empty").mkdir()
    path = _suite(tmp_path, **task)
    assert bench.main([str(path), "--local", "--workers", "1", "--no-progress"]) == 2
    out, err = capsys.readouterr()
    line, = err.splitlines()
    assert line.startswith(f"pic4rl-bench: {path}: {message}"), line
    assert out == ""
    assert not (tmp_path / "bags").exists()  # no cell ran, not even the bags folder


def test_a_suites_good_worlds_and_robots_pass(tmp_path: Path) -> None:
    suite = load_suite(_suite(tmp_path, worlds=["indoor:3", "barn:299", {
        "world": "barn", "variants": [0, 6], "label": "t"}], robots=["jackal", "burger"]))
    assert len(suite.cells) == 4 * 2
    assert {c.row["world"] for c in suite.cells} == {"indoor:3", "barn:299", "barn:t"}


def test_a_failed_cell_never_ranks(tmp_path: Path) -> None:
    """The group row barn:t whose variant-0 cell reached its goal (1/1) while its variant-300
    cell failed ranks below a complete row that reached nothing (0/1)."""
    header = benchtable._header(benchtable.LAYOUTS["barn"])
    width = len(header)

    def row(agent: str, success: str, score: str, status: str) -> list[str | None]:
        cells: list[str | None] = [None] * width
        cells[:6] = ["barn", agent, "barn:t", "jackal", "episodes1_s0", "1"]
        cells[header.index("success")] = success
        cells[header.index("BARN score [-]")] = score
        cells[-1] = status
        return cells

    rows = [row("planner", "1/1", "0.40", "failed: barn-planner-barn300: ConfigError: x"),
            row("dwa", "0/1", "0.00", "ok"), row("explorer", "1/1", "0.30", "ok")]
    board = benchtable.leaderboards(header, rows, benchtable.LAYOUTS["barn"])["barn"]
    lines = board.splitlines()[2:]
    assert [line.split("|")[1:3] for line in lines] == [
        [" 1 ", " explorer "], [" 2 ", " dwa "], [" failed ", " planner "]]


@pytest.mark.parametrize("path", sorted((REPO / "config").glob("suite_*.yaml")),
                         ids=lambda p: p.stem)
def test_each_shipped_suite_writes_into_the_checkouts_bags(path: Path) -> None:
    """A shipped suite's bags go to the checkout's ``bags/`` (ignored by git), not beside the
    suite file (``config/bags/``, tracked)."""
    assert load_suite(path).bags_dir.resolve() == REPO / "bags"
