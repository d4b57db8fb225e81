"""``pic4rl-metrics report``: the HTML page built from real bags — what it holds, that it needs
no network, and its bad inputs. The page in a real browser: ``test_report_browser.py``.
"""

from __future__ import annotations

import base64
import hashlib
import re
import shutil
from pathlib import Path

import pytest

from pic4rl_metrics.cli import commands as cli
from pic4rl_metrics.tables.aggregate import wilson_interval
from report_page import Page as _Page


def _run(capsys: pytest.CaptureFixture[str], *args: object) -> tuple[int, str, str]:
    code = cli.main([str(a) for a in args])
    captured = capsys.readouterr()
    return code, captured.out, captured.err


@pytest.fixture(scope="module")
def page(bench_bags: Path, tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, _Page]:
    out = tmp_path_factory.mktemp("report") / "report.html"
    assert cli.main(["report", str(bench_bags), "--out", str(out), "--reference", "dwa"]) == 0
    parsed = _Page()
    parsed.feed(out.read_text())
    return out, parsed


def test_the_page_holds_its_sections_in_order(page: tuple[Path, _Page]) -> None:
    _, p = page
    assert p.h2 == ["Leaderboard", "Paired comparisons", "How each agent fails",
                    "Start–goal pairs", "Episodes", "Unreadable bags", "Inputs"]


def test_the_page_needs_no_network(page: tuple[Path, _Page]) -> None:
    out, p = page
    text = out.read_text()
    assert p.external == []
    assert not re.search(r"""(src|href)=["']?(https?:)?//""", text)
    assert "@import" not in text and "url(" not in text
    assert p.images and all(src.startswith("data:image/png;base64,") for src in p.images)
    assert all(base64.b64decode(src.partition(",")[2])[:8] == b"\x89PNG\r\n\x1a\n"
               for src in p.images)


def test_the_leaderboard_is_the_aggregate_with_wilson_intervals(
        page: tuple[Path, _Page], bench_bags: Path, capsys) -> None:
    _, p = page
    header, *rows = p.rows["leaderboard"]
    assert header[:4] == ["agent", "episodes", "success", "Wilson 95% CI"]
    code, out, _ = _run(capsys, "compare", "--format", "csv", bench_bags)
    assert code == 0
    table = {line.split(",")[0]: line.split(",")[1] for line in out.splitlines()[1:]}
    for row in rows:
        k, n = (int(v) for v in row[2].split(" ")[0].split("/"))
        assert f"{k}/{n}" == table[row[0]]
        low, high = wilson_interval(k, n)
        assert row[3] == f"[{100 * low:.0f}, {100 * high:.0f}]%"
    rates = [int(r[2].split("/")[0]) / int(r[2].split("/")[1].split(" ")[0]) for r in rows]
    assert rates == sorted(rates, reverse=True)


def test_paired_rows_compare_with_the_reference(page: tuple[Path, _Page]) -> None:
    _, p = page
    header, *rows = p.rows["paired"]
    assert header[:2] == ["agent", "reference"] and header[-1] == "verdict"
    assert sorted((r[0], r[1]) for r in rows) == [("planner", "dwa"), ("td3", "dwa")]
    assert all(r[3] == "8" for r in rows)  # 4 pairs × 2 runs, every episode matched


def test_every_episode_has_a_row_linking_its_bag(page: tuple[Path, _Page],
                                                 bench_bags: Path) -> None:
    out, p = page
    header, *rows = p.rows["episodes"]
    assert len(rows) == 24
    bags = [href for cls, href in p.links if cls == "bag"]
    assert len(bags) == 24
    assert all((out.parent / href).resolve().is_dir() for href in bags)
    assert {(out.parent / h).resolve() for h in bags} == {
        b.parent.resolve() for b in bench_bags.rglob("metadata.yaml")}


def test_a_video_beside_a_bag_is_linked(bench_bags: Path, tmp_path: Path, capsys) -> None:
    bags = tmp_path / "bags"
    shutil.copytree(bench_bags / "run0" / "dwa", bags / "dwa")
    (bags / "dwa" / "episode_0001.mp4").write_bytes(b"not really a video")
    (bags / "config.yaml").write_text("agent: dwa\n")  # the run's config, as the recorder's
    out = tmp_path / "out" / "report.html"
    out.parent.mkdir()
    code, _, _ = _run(capsys, "report", bags, "--out", out)
    assert code == 0
    p = _Page()
    p.feed(out.read_text())
    assert [h for cls, h in p.links if cls == "video"] == ["../bags/dwa/episode_0001.mp4"]
    inputs = dict(row for row in p.rows["inputs"][1:])
    digest = hashlib.sha256(b"agent: dwa\n").hexdigest()[:12]
    assert inputs[f"config {bags / 'config.yaml'}"] == digest


@pytest.mark.bad_input
def test_a_bad_bag_is_listed_and_exit_1(bench_bags: Path, tmp_path: Path, capsys) -> None:
    bags = tmp_path / "bags"
    shutil.copytree(bench_bags / "run0" / "td3", bags / "td3")
    broken = bags / "td3" / "episode_0009"
    broken.mkdir()
    (broken / "metadata.yaml").write_text("not: [a bag")
    out = tmp_path / "report.html"
    code, out_text, err = _run(capsys, "report", bags, "--out", out)
    assert code == 1 and out_text == "" and out.is_file()
    assert "1 of 5 bag(s) failed" in err
    p = _Page()
    p.feed(out.read_text())
    (bag, error), = p.rows["errors"][1:]
    assert bag == str(broken) and "metadata" in error.lower()
    assert sum(1 for r in p.rows["episodes"][1:] if r[-1]) == 1


@pytest.mark.bad_input
def test_an_empty_input_is_one_line_exit_2(tmp_path: Path, capsys) -> None:
    (tmp_path / "empty").mkdir()
    code, out, err = _run(capsys, "report", tmp_path / "empty", "--out", tmp_path / "r.html")
    assert code == 2 and out == ""
    assert err.strip().splitlines() == [
        f"pic4rl-metrics: report: no bag in {tmp_path / 'empty'}; expected rosbag2 "
        "directories, .db3/.mcap or .bag files, or folders of them"]
    assert not (tmp_path / "r.html").exists()


@pytest.mark.bad_input
def test_an_existing_out_is_refused_without_force(bench_bags: Path, tmp_path: Path,
                                                  capsys) -> None:
    out = tmp_path / "report.html"
    out.write_text("the user's page")
    code, _, err = _run(capsys, "report", bench_bags / "run0" / "dwa", "--out", out)
    assert code == 2
    assert err.strip().splitlines() == [
        f"pic4rl-metrics: --out {str(out)!r} exists; pass --force to replace it"]
    assert out.read_text() == "the user's page"
    code, _, _ = _run(capsys, "report", bench_bags / "run0" / "dwa", "--out", out, "--force")
    assert code == 0 and out.read_text().startswith("<!DOCTYPE html>")


def test_bags_without_a_pair_are_counted_and_drawn_in_no_pair(tmp_path: Path, capsys) -> None:
    """Two agents' bags with no start or goal in their facts (as a real robot's log): no
    couple, each counted as unpaired, and the pairs' section says why it is empty."""
    from pic4rl_metrics.synthetic.synthetic import straight_line, write_episode_bag

    for agent in ("a", "b"):
        write_episode_bag(tmp_path / "bags" / agent, straight_line(0.5, 4.0),
                          facts={"agent": agent}, outcome="timeout")
    out = tmp_path / "report.html"
    code, _, _ = _run(capsys, "report", tmp_path / "bags", "--out", out)
    assert code == 0
    text = out.read_text()
    p = _Page()
    p.feed(text)
    (row,) = p.rows["paired"][1:]
    assert row[:5] == ["a", "b", "0", "0", "1 + 1"] and row[-1] == "not distinguishable at this n"
    assert "Episodes without a start–goal pair in their facts: 2." in text
    assert "No episode records its start–goal pair" in text
    # their failures' captions name the missing world in words, not "?"
    assert "<b>a</b> in a world not recorded: 1 failed" in text and " in ?" not in text


def test_the_page_states_version_commit_and_seeds(page: tuple[Path, _Page]) -> None:
    """Under the title: the package's version, the git commit of the source it ran from (this
    checkout's: HEAD when the page was built, so HEAD or an ancestor of it now) and the seeds
    of the episodes (bench_bags: run r, pair k has seed 1000 r + k)."""
    import subprocess
    from importlib.metadata import version

    _, p = page
    line = next(t for t in p.text if t.startswith("pic4rl ") and "git commit" in t)
    match = re.fullmatch(r"pic4rl (\S+) · git commit (\w+) · seeds 0–3, 1000–1003 "
                         r"\(24 of 24 episodes record one\)", line)
    assert match and match[1] == version("pic4rl"), line
    here = Path(__file__).parent
    ancestor = subprocess.run(["git", "merge-base", "--is-ancestor", match[2], "HEAD"],
                              cwd=here, capture_output=True, check=False)
    assert len(match[2]) == 12 and ancestor.returncode == 0


def test_the_inputs_fold_behind_a_one_line_summary(page: tuple[Path, _Page]) -> None:
    _, p = page
    assert "inputs" in p.folded  # the detail: behind a <details>
    summary = next(t for t in p.text if "bag(s) in" in t)
    # 3 agents × 2 runs, each run's folder; every episode's time budget differs in its facts
    assert summary.startswith("1 input(s), 24 bag(s) in 6 folder(s), 0 config file(s), 6 agent "
                              "run(s) (6 with more than one set-up: see the detail)")
    rows = {r[0]: r[1] for r in p.rows["inputs"][1:]}
    assert rows["git commit"] and rows["pic4rl version"]


def test_the_leaderboard_saves_as_compares_csv_and_latex(page: tuple[Path, _Page],
                                                         bench_bags: Path, capsys) -> None:
    from urllib.parse import unquote

    _, p = page
    exports = {a["download"]: a["href"] for a in p.anchors if a.get("class") == "export"}
    assert sorted(exports) == ["leaderboard.csv", "leaderboard.tex"]
    for name, fmt, mime in (("leaderboard.csv", "csv", "text/csv"),
                            ("leaderboard.tex", "latex", "application/x-tex")):
        head, _, body = str(exports[name]).partition(",")
        assert head == f"data:{mime};charset=utf-8"
        code, out, _ = _run(capsys, "compare", "--format", fmt, bench_bags)
        assert code == 0 and unquote(body).rstrip("\n") == out.rstrip("\n")  # as compare


def test_every_figure_can_be_saved_as_png(page: tuple[Path, _Page]) -> None:
    _, p = page
    saves = [a for a in p.anchors if a.get("class") == "save"]
    assert len(saves) == len(p.images) > 0
    names = [str(a["download"]) for a in saves]
    assert all(re.fullmatch(r"[\w.-]+\.png", n) for n in names)
    assert "td3_failures.png" in names


def test_every_name_is_escaped(tmp_path: Path, capsys) -> None:
    """Agent, world, run and episode names with markup, in the leaderboard, the logs, the
    figures' captions and file names, the downloads and the inputs, stay text."""
    from pic4rl_metrics.synthetic.synthetic import straight_line, write_episode_bag

    evil = '<img src=x onerror="alert(1)">&amp;\'"'
    facts = {"agent": evil, "world": f"w{evil}", "run": f"r{evil}", "episode": f"e{evil}"}
    write_episode_bag(tmp_path / "bags" / "a", straight_line(0.5, 4.0),
                      facts={**facts, "start": [0.0, 0.0, 0.0], "goal": [2.0, 0.0]},
                      outcome="goal")
    write_episode_bag(tmp_path / "bags" / "log", straight_line(0.5, 4.0), facts=facts)
    out = tmp_path / "report.html"
    assert _run(capsys, "report", tmp_path / "bags", "--out", out)[0] == 0
    text = out.read_text()
    assert "<img src=x" not in text and 'onerror="alert' not in text
    p = _Page()
    p.feed(text)
    assert p.rows["leaderboard"][1][0] == evil and p.rows["logs"][1][0] == evil
    assert any(evil in t for t in p.text if "·" not in t)
