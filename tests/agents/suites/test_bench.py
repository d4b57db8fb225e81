"""``pic4rl-bench``: a suite file expands to cells, bad keys are one line naming the key, a
small suite of baseline cells runs in a local process pool and yields its table, a rerun does
nothing, and a worker killed mid-episode loses only that episode."""

from __future__ import annotations

import json
import os
import pickle
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
import yaml

from pic4rl_agents.suites import cell as benchcell
from pic4rl_agents.suites import runner as bench
from pic4rl_agents.suites import table as benchtable
from pic4rl_agents.suites.suite import load_suite
from pic4rl_bridge.episodes import load_goals_and_poses
from pic4rl_bridge.errors import ConfigError
from pic4rl_metrics.tables.aggregate import wilson_interval

REPO = Path(__file__).resolve().parents[3]
PAIRS = REPO / "pic4rl_agents" / "data" / "goals_indoor_test.json"


def _files(tmp_path: Path, steps: int = 30, **task: object) -> Path:
    """An env file (short episodes) and a suite file of one task ``task`` over it."""
    (tmp_path / "env.yaml").write_text(yaml.safe_dump({
        "sim": {"ros__parameters": {"robot": "jackal", "world": "indoor", "world_variant": 0}},
        "nav_env": {"ros__parameters": {"task": "goToPose", "sensor": "lidar",
                                        "episode_max_steps": steps}}}))
    suite = {"suite": "tiny", "bags": str(tmp_path / "bags"),
             "tasks": [{"name": "goto", "env": "env.yaml", **task}]}
    (tmp_path / "suite.yaml").write_text(yaml.safe_dump(suite))
    return tmp_path / "suite.yaml"


def _bags(root: Path) -> dict[str, float]:
    return {str(p.relative_to(root)): p.stat().st_mtime_ns
            for p in root.glob("*/*/episode_*/*")}


def test_a_suite_expands_to_its_cells(tmp_path: Path) -> None:
    mine = json.loads(PAIRS.read_text())  # a user's pairs file: it records no world
    del mine["world"], mine["robot_radius_m"]
    (tmp_path / "mine.json").write_text(json.dumps(mine))
    suite = load_suite(_files(tmp_path, baselines=["dwa", "proportional"],
                              agents={"td3": str(REPO / "checkpoints" / "td3_lidar")},
                              worlds=["indoor:0", "indoor:1"], robots=["jackal"],
                              pairs=[{"file": "mine.json"},
                                     {"random": 3, "kind": "any", "seed": 4}],
                              repetitions=2, seed=10))
    assert len(suite.cells) == 3 * 2 * 1 * 2 * 2
    assert len({c.name for c in suite.cells}) == len(suite.cells)
    first = suite.cells[0]
    assert (first.agent, first.agent_path, first.world, first.variant) == (
        "td3", str(REPO / "checkpoints" / "td3_lidar"), "indoor", 0)
    assert first.name == "goto-td3-indoor0-jackal-file_mine-r0"
    assert [c.seed for c in suite.cells[:4]] == [10, 11, 10, 11]
    assert suite.cells[2].pairs.label == "random3_any_s4"
    assert suite.cells[-1].baseline == "proportional"
    assert suite.cells[0].row == suite.cells[1].row  # repetitions share a row
    assert suite.root == tmp_path / "bags" / "tiny"


def test_a_relative_bags_path_is_read_from_the_suite_file(tmp_path: Path,
                                                          monkeypatch: pytest.MonkeyPatch) -> None:
    path = _files(tmp_path, baselines=["dwa"])
    path.write_text(path.read_text().replace(str(tmp_path / "bags"), "out"))
    (tmp_path / "elsewhere").mkdir()
    monkeypatch.chdir(tmp_path / "elsewhere")
    assert load_suite(path).root == tmp_path / "out" / "tiny"  # like its env: paths
    assert load_suite(path, bags_dir="mine").root == tmp_path / "elsewhere" / "mine" / "tiny"


@pytest.mark.bad_input
@pytest.mark.parametrize(("change", "message"), [
    ({"taks": []}, r"suite.yaml: unknown key 'taks'; did you mean 'tasks'\?"),
    ({"transport": "dds"}, r"transport: 'dds' is invalid; expected inprocess or ros"),
    ({"task": {"baseline": ["dwa"]}}, r"tasks\[0\]: unknown key 'baseline'; did you mean "),
    ({"task": {"baselines": ["dvva"]}}, r"tasks\[0\].baselines: 'dvva' is invalid; expected one"),
    ({"task": {"pairs": [{"random": 3, "kind": "far"}]}}, r"tasks\[0\].pairs.kind: 'far'"),
    ({"task": {"pairs": [{"random": 0}]}}, r"tasks\[0\].pairs.random: 0 is invalid"),
    ({"task": {"repetitions": "two"}}, r"tasks\[0\].repetitions: 'two' is invalid"),
    ({"task": {"env": "nope.yaml"}}, r"tasks\[0\].env: 'nope.yaml' is invalid; expected an ex"),
])
def test_bad_suite_keys_are_named(tmp_path: Path, change: dict, message: str) -> None:
    path = _files(tmp_path, baselines=["dwa"])
    data = yaml.safe_load(path.read_text())
    data["tasks"][0].update(change.pop("task", {}))
    data.update(change)
    path.write_text(yaml.safe_dump(data))
    with pytest.raises(ConfigError, match=message):
        load_suite(path)


def test_cli_says_bad_suite_in_one_line(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    path = _files(tmp_path, baselines=["dwa"], worlds=["indoor:x"])
    assert bench.main([str(path), "--local"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "tasks[0].worlds: 'indoor:x' is invalid" in err


def test_a_suite_runs_yields_its_table_and_a_rerun_does_nothing(tmp_path: Path) -> None:
    suite = load_suite(_files(tmp_path, baselines=["proportional", "dwa"], pairs=[
        {"file": str(PAIRS), "episodes": 2}, {"random": 2, "kind": "paper", "seed": 1}]))
    table = bench.bench_suite(suite, workers=2, local=True, progress=False)
    assert [r[:2] for r in table.rows] == [("goto", "proportional")] * 2 + [("goto", "dwa")] * 2
    n, status = table.header.index("n"), table.header.index("status")
    assert [r[n] for r in table.rows] == ["2"] * 4 and {r[status] for r in table.rows} == {"ok"}
    ci = table.rows[0][table.header.index("success 95% CI")]
    assert ci in ("[0.00, 0.66]", "[0.09, 0.91]", "[0.34, 1.00]")  # k/2, for k = 0, 1, 2
    for name in ("results.csv", "results.md", "results.tex", "leaderboard_goto.md"):
        assert (suite.root / name).is_file()
    assert (suite.root / "comparison_goto.png").read_bytes().startswith(b"\x89PNG")
    page = (suite.root / "report.html").read_text()  # the suite's page, its baselines paired
    assert "<h2>Paired comparisons</h2>" in page
    assert page.count("<td>dwa</td><td>proportional</td>") == 1
    assert page.count('class="bag"') == 8
    before, text = _bags(suite.root), (suite.root / "results.md").read_text()
    assert len(before) == 4 * 2 * 2  # 4 cells x 2 episodes x (.db3, metadata.yaml)
    again = bench.bench_suite(suite, workers=2, local=True, progress=False)
    assert _bags(suite.root) == before and again.rows == table.rows
    assert (suite.root / "results.md").read_text() == text


def test_the_pool_imports_torch_before_forking_only_for_a_learned_agent(
        tmp_path: Path) -> None:
    """``cell.preload``, which the local pool runs before forking a cell's worker (so that no
    worker imports them again), imports the env's transport for every cell, and SB3 and torch
    only for a learned agent's: a baseline's cells never load torch."""
    suite = load_suite(_files(tmp_path, baselines=["dwa"],
                              agents={"td3": str(REPO / "checkpoints" / "td3_lidar")}))
    script = ("import pickle, sys\n"
              "from pic4rl_agents.suites import cell\n"
              "cell.preload(pickle.loads(bytes.fromhex(sys.argv[1])))\n"
              "print(*(m in sys.modules for m in ('pic4rl_bridge.transports.inprocess', "
              "'torch', 'stable_baselines3')))\n")
    imported = {}
    for c in suite.cells:
        out = subprocess.run([sys.executable, "-c", script, pickle.dumps(c).hex()],
                             capture_output=True, text=True, check=True, cwd=REPO)
        imported[c.agent] = out.stdout.split()
    assert imported == {"dwa": ["True", "False", "False"], "td3": ["True", "True", "True"]}


def test_a_cell_that_keeps_failing_is_a_failed_row(tmp_path: Path) -> None:
    pairs = tmp_path / "bad_pairs.json"  # a pair far outside the world: refused
    pairs.write_text(json.dumps({"goals": [[100.0, 100.0]], "poses": [[100.0, 100.0, 0.0]]}))
    suite = load_suite(_files(tmp_path, baselines=["proportional"],
                              pairs=[{"file": str(pairs)}, {"file": str(PAIRS), "episodes": 1}]))
    table = bench.bench_suite(suite, workers=1, local=True, retries=1, progress=False)
    status = [r[-1] for r in table.rows]
    assert status[0].startswith("failed: goto-proportional-indoor0-jackal-file_bad_pairs-r0: ")
    assert status[1] == "ok" and not (suite.root / suite.cells[0].name / benchcell.DONE).exists()


def _children(pid: int) -> list[int]:
    text = Path(f"/proc/{pid}/task/{pid}/children").read_text()
    return [int(p) for p in text.split()]


def test_a_cells_copy_of_a_pairs_file_drives_the_files_pairs_to_the_last_digit(
        tmp_path: Path) -> None:
    # The paper's file starts three pairs at 1.5708 rad: a copy rounded to mrad (1.571) sent
    # a crowd's chaotic episodes elsewhere than pic4rl-test's with the same file.
    pairs = load_goals_and_poses(PAIRS)
    benchcell._pairs_from(pairs, 2, tmp_path)
    copy = load_goals_and_poses(benchcell._pairs_file(2, tmp_path))
    order = [2, 3, 4, 0, 1]
    assert copy.goals == tuple(pairs.goals[i] for i in order)
    assert copy.poses == tuple(pairs.poses[i] for i in order)
    assert copy.poses[0].yaw == 1.5708


@pytest.mark.heavy
def test_a_killed_worker_loses_only_its_unfinished_episode(tmp_path: Path) -> None:
    suite_file = _files(tmp_path, steps=120, baselines=["dwa"], pairs=[
        {"file": str(PAIRS), "episodes": 4}, {"random": 3, "kind": "paper", "seed": 2}])
    suite = load_suite(suite_file)
    env = {**os.environ, "PYTHONPATH": str(REPO)}
    proc = subprocess.Popen([sys.executable, "-m", "pic4rl_agents.suites.runner", str(suite_file),
                             "--local", "--workers", "1", "--no-progress"], env=env,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    first = suite.root / suite.cells[0].name / "dwa"
    deadline = time.monotonic() + 120
    while not any((first / f"episode_{k:04d}").is_dir() and not
                  (first / f"episode_{k:04d}" / "metadata.yaml").exists() for k in (1, 2)):
        assert time.monotonic() < deadline and proc.poll() is None, proc.communicate()
        time.sleep(0.005)
    for child in _children(proc.pid):
        os.kill(child, signal.SIGKILL)
    out, err = proc.communicate(timeout=300)
    assert proc.returncode == 0, err
    assert "attempt 1 failed (worker died (exit code -9)); trying again" in err
    assert len(list((suite.root / benchcell.UNFINISHED).glob("*/dwa/episode_*"))) == 1
    for cell in suite.cells:
        folder = suite.root / cell.name
        pairs = json.loads(((folder / benchcell.PAIRS) if cell.pairs.random else PAIRS)
                           .read_text())["goals"]
        bags = sorted((folder / "dwa").glob("episode_*"))
        assert [b.name for b in bags] == [f"episode_{k:04d}" for k in
                                          range(benchcell.expected_episodes(cell))]
        for k, bag in enumerate(bags):  # episode k drove pair k: none twice, none skipped
            facts = yaml.safe_load((bag / "metadata.yaml").read_text())
            goal = json.loads(facts["rosbag2_bagfile_information"]["custom_data"]["goal"])
            assert goal == pytest.approx(pairs[k], abs=1e-3)
    assert out.count("| goto | dwa |") == 2 and "failed" not in out


@pytest.mark.heavy
@pytest.mark.ray
def test_cells_run_as_tasks_of_a_local_ray(tmp_path: Path) -> None:
    pytest.importorskip("ray")
    suite = load_suite(_files(tmp_path, baselines=["proportional", "dwa"],
                              pairs=[{"file": str(PAIRS), "episodes": 1}]))
    table = bench.bench_suite(suite, workers=2, progress=False)
    assert [(r[1], r[5], r[-1]) for r in table.rows] == [("proportional", "1", "ok"),
                                                          ("dwa", "1", "ok")]
    assert all((suite.root / c.name / benchcell.DONE).is_file() for c in suite.cells)


def test_the_success_figure_draws_each_rows_success_and_its_wilson_interval() -> None:
    header = ("task", "agent", "world", "robot", "pairs", "n", "success", "success 95% CI",
              "status")
    rows = [("goto", "a", "indoor:0", "jackal", "paper", "2", "1/2", None, "ok"),
            ("goto", "b", "indoor:0", "jackal", "paper", "4", "4/4", None, "ok"),
            ("goto", "c", "indoor:0", "jackal", "paper", "0", None, None, "failed: x"),
            ("person", "d", "person:0", "omni", "env", "1", "1/1", None, "ok")]
    fig = benchtable.success_figure("goto", header, rows)
    bars = fig.axes[0].patches
    assert [round(b.get_width(), 6) for b in bars] == [0.5, 1.0, 0.0]
    labels = [t.get_text() for t in fig.axes[0].get_yticklabels()]
    assert labels == ["a · indoor:0 · jackal · paper", "b · indoor:0 · jackal · paper",
                            "c · indoor:0 · jackal · paper (failed)"]
    (errors,) = [c for c in fig.axes[0].collections if c.get_segments()]
    low, high = wilson_interval(1, 2)
    first = errors.get_segments()[0]  # the first row's interval, drawn at its bar
    assert sorted(x for x, _ in first) == pytest.approx([low, high])
