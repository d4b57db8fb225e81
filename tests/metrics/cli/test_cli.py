"""``pic4rl-metrics`` end to end: real bags written into a temporary directory, judged through
``cli.main`` (stdout/stderr captured), and the installed console script.

Numbers that come back through text are compared at the precision the format keeps: full
float precision in CSV/JSON (``EXACT``, as in test_analytic), two decimals in table,
markdown and LaTeX (the cells are compared as strings).
"""

from __future__ import annotations

import errno
import io
import json
import math
import subprocess
import sys
from pathlib import Path

import pandas as pd
import pytest
from rosbags.rosbag2 import Reader, Writer
from rosbags.typesys import Stores, get_typestore

from pic4rl_metrics.cli import commands as cli
from pic4rl_metrics.synthetic.synthetic import (DEFAULT_T0_NS, Obstacles, straight_line,
                                              write_episode_bag)

EXACT = 1e-12
F32 = 1e-6  # scan ranges travel as float32

LINE = straight_line(0.5, 10.0)  # 5 m along +x in 10 s
WALL = Obstacles(segments=((-100.0, 1.0, 100.0, 1.0),))  # parallel wall 1 m to the left


def _rename_topics(src: Path, dst: Path, rename: dict[str, str]) -> Path:
    """Copy a bag message by message under new topic names (custom_data is not copied)."""
    ts = get_typestore(Stores.ROS2_JAZZY)
    with Reader(src) as reader, Writer(dst, version=9) as writer:
        conns = {
            c.id: writer.add_connection(rename.get(c.topic, c.topic), c.msgtype, typestore=ts)
            for c in reader.connections
        }
        for conn, t_ns, raw in reader.messages():
            writer.write(conns[conn.id], t_ns, bytes(raw))
    return dst


def _run(capsys: pytest.CaptureFixture[str], *argv: object) -> tuple[int, str, str]:
    code = cli.main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


@pytest.fixture(scope="module")
def runs(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """Two agents' episodes in a BARN world: alpha reaches its goal (5, 0); beta times out
    (goal (10, 0))."""
    root = tmp_path_factory.mktemp("cli") / "runs"
    fp = {"radius_m": 0.2}
    write_episode_bag(root / "alpha_ep0", LINE, obstacles=WALL, goal=(5.0, 0.0), outcome="goal",
                      facts={"agent": "alpha", "footprint": fp, "world": "barn:0"})
    write_episode_bag(root / "beta_ep0", LINE, obstacles=WALL, goal=(10.0, 0.0),
                      facts={"agent": "beta", "footprint": fp, "world": "barn:0"})
    return root


#: A walled room with three cylinders; a Jackal's footprint.
ROOM = Obstacles(
    circles=((4.0, 3.0, 0.4), (2.0, 4.3, 0.3), (6.0, 1.9, 0.3)),
    segments=((0, 0, 8, 0), (8, 0, 8, 6), (8, 6, 0, 6), (0, 6, 0, 0)),
)
JACKAL = {"length_m": 0.508, "width_m": 0.430}


@pytest.fixture(scope="module")
def example_run(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """Two agents, three episodes each along free lanes of ``ROOM`` (goal reached), except
    wobbly's third: straight into the cylinder at (4, 3), stopping 0.04 m from it."""
    run_dir = tmp_path_factory.mktemp("examples") / "example"
    lanes = {"smooth": (1.0, 5.0, 1.0), "wobbly": (1.0, 5.0, 3.0)}
    for a, (agent, ys) in enumerate(lanes.items()):
        for k, y in enumerate(ys):
            crash = agent == "wobbly" and k == 2
            speed = 0.35 if agent == "wobbly" else 0.45
            duration = 6.6 if crash else 6.0 / speed  # crash: x = 1 + 0.35 * 6.6 = 3.31 m
            track = straight_line(speed, duration, start=(1.0, y, 0.0))
            facts = {"agent": agent, "run": run_dir.name, "episode": str(k), "footprint": JACKAL,
                     "start": [1.0, y, 0.0], "goal": [7.0, y], "collision_tolerance_m": 0.05}
            write_episode_bag(run_dir / f"{agent}_ep{k}", track, obstacles=ROOM, goal=(7.0, y),
                              facts=facts, outcome="collision" if crash else "goal",
                              t0_ns=DEFAULT_T0_NS + (3 * a + k) * 60_000_000_000)
    return run_dir


# --- compute: formats ---------------------------------------------------------------------


def test_compute_csv_holds_every_column_at_full_precision(capsys, runs: Path) -> None:
    code, out, err = _run(capsys, "compute", "--format", "csv", runs)
    assert code == 0, err
    df = pd.read_csv(io.StringIO(out))
    assert list(df["agent"]) == ["alpha", "beta"]
    assert list(df["outcome"]) == ["goal", "timeout"]
    assert list(df["success"]) == [1.0, 0.0]
    assert df["path_length_m"].tolist() == pytest.approx([5.0, 5.0], abs=EXACT)
    assert df["clearance_time_s"].tolist() == pytest.approx([10.0, 10.0], abs=EXACT)
    assert df["soft_spl"].tolist() == pytest.approx([1.0, 0.5], abs=EXACT)
    assert df["obstacle_dist_min_m"].tolist() == pytest.approx([1.0, 1.0], abs=F32)
    # BARN: OT = 5 m / 2 m/s, AT = 10 s - 0.2 s (0.1 m off the start); a timeout scores 0
    assert df["barn_score"].tolist() == pytest.approx([2.5 / 9.8, 0.0], abs=EXACT)
    assert df["error"].isna().all()  # empty cells


def test_compute_json_has_nulls_for_missing(capsys, runs: Path) -> None:
    code, out, err = _run(capsys, "compute", "--format", "json", runs)
    assert code == 0, err
    rows = json.loads(out)
    assert [r["agent"] for r in rows] == ["alpha", "beta"]
    alpha, beta = rows
    assert alpha["path_length_m"] == pytest.approx(5.0, abs=EXACT)
    assert alpha["spl"] == pytest.approx(1.0, abs=EXACT)
    assert beta["outcome"] == "timeout" and beta["spl"] == 0.0
    assert beta["start_goal_distance_m"] == pytest.approx(10.0, abs=EXACT)
    assert alpha["barn_score"] == pytest.approx(2.5 / 9.8, abs=EXACT)
    assert alpha["row_path_mae_m"] is None
    assert alpha["n_poses"] == 101 and alpha["n_scans"] == 101


@pytest.mark.parametrize("fmt", ["table", "markdown", "latex"])
def test_compute_text_formats_show_two_decimals(capsys, runs: Path, fmt: str) -> None:
    code, out, err = _run(capsys, "compute", "--format", fmt, runs)
    assert code == 0, err
    alpha_name = "runs/alpha\\_ep0" if fmt == "latex" else "runs/alpha_ep0"
    lines = [line for line in out.splitlines() if alpha_name in line]
    assert len(lines) == 1, out
    cells = lines[0].replace("|", " ").replace("&", " ").replace("\\\\", " ").split()
    # outcome, success, time, path, dist/path, v mean, ω std, max lin acc, max yaw acc,
    # min obst, mean obst
    assert cells[1:12] == ["goal", "yes", "10.00", "5.00", "1.00", "0.50", "0.00", "0.00",
                           "0.00", "1.00", "1.00"]
    if fmt == "latex":
        assert "\\begin{tabular}" in out and "\\end{tabular}" in out
    if fmt == "markdown":
        assert out.startswith("| bag |")


def test_out_writes_a_file_and_refuses_to_overwrite(capsys, runs: Path, tmp_path: Path) -> None:
    target = tmp_path / "deep" / "metrics.csv"
    code, out, err = _run(capsys, "compute", "--format", "csv", "--out", target, runs)
    assert code == 0, err
    assert out == ""  # the result went to the file
    first = target.read_text()
    assert len(pd.read_csv(io.StringIO(first))) == 2

    target.write_text("mine\n")
    code, out, err = _run(capsys, "compute", "--format", "csv", "--out", target, runs)
    assert code == 2
    assert "--force" in err and out == ""
    assert target.read_text() == "mine\n"

    code, _, err = _run(capsys, "compute", "--format", "csv", "--out", target, "--force", runs)
    assert code == 0, err
    assert target.read_text() == first


def _disk_full(*_: object, **__: object) -> None:
    raise OSError(errno.ENOSPC, "No space left on device")


@pytest.mark.bad_input
def test_a_full_disk_is_one_line_exit_2_and_no_file(capsys, runs: Path, tmp_path: Path,
                                                     monkeypatch: pytest.MonkeyPatch) -> None:
    """The write fails (a full disk, simulated): exit 2, one line naming the path and the
    error, no file left behind (not even a temporary one), so the next run is not refused."""
    target = tmp_path / "metrics.csv"
    monkeypatch.setattr(cli, "_write_all", _disk_full)
    code, out, err = _run(capsys, "compute", "--format", "csv", "--out", target, runs)
    assert code == 2 and out == ""
    assert err.strip().splitlines() == [
        f"pic4rl-metrics: --out {str(target)!r}: cannot write it: No space left on device"]
    assert list(tmp_path.iterdir()) == []
    monkeypatch.undo()
    code, _, err = _run(capsys, "compute", "--format", "csv", "--out", target, runs)
    assert code == 0 and target.is_file(), err


@pytest.mark.bad_input
@pytest.mark.parametrize("where", ["parent_is_a_file", "proc"])
def test_an_output_that_cannot_exist_is_one_line_exit_2(capsys, runs: Path, tmp_path: Path,
                                                        where: str) -> None:
    if where == "proc":
        target = Path("/proc/pic4rl_metrics_test/metrics.csv")
    else:
        (tmp_path / "file").write_text("x")
        target = tmp_path / "file" / "metrics.csv"
    code, out, err = _run(capsys, "compute", "--out", target, runs)
    assert code == 2 and out == ""
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith(f"pic4rl-metrics: --out {str(target)!r}: "
                                                   "cannot write it: ")


@pytest.mark.bad_input
def test_plot_on_a_full_disk_is_one_line_exit_2_and_no_partial_png(
        capsys, runs: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    from matplotlib.figure import Figure

    monkeypatch.setattr(Figure, "savefig", _disk_full)
    code, out, err = _run(capsys, "plot", "--out", tmp_path / "figs", runs)
    assert code == 2 and out == ""
    assert "cannot write it: No space left on device" in err
    assert "Traceback" not in err
    assert list((tmp_path / "figs").iterdir()) == []


# --- compare ---------------------------------------------------------------------------------


def test_compare_latex_has_one_row_per_agent(capsys, runs: Path) -> None:
    code, out, err = _run(capsys, "compare", "--format", "latex", runs)
    assert code == 0, err
    rows = [line for line in out.splitlines() if line.startswith(("alpha", "beta"))]
    assert len(rows) == 2
    alpha, beta = ([c.strip() for c in r.removesuffix("\\\\").split("&")] for r in rows)
    assert alpha[:5] == ["alpha", "1/1", "10.00", "0.00", "5.00"]  # success, time, heading, path
    assert beta[:2] == ["beta", "0/1"]
    assert "\\begin{table*}" in out


def test_compare_latex_on_the_examples(capsys, example_run: Path) -> None:
    code, out, err = _run(capsys, "compare", "--format", "latex", example_run)
    assert code == 0, err
    lines = out.splitlines()
    body = lines[lines.index("\\midrule") + 1 : lines.index("\\bottomrule")]
    cells = {r.split("&")[0].strip(): r.split("&")[1].strip() for r in body}
    assert len(body) == 2  # one row per agent
    assert cells == {"smooth": "3/3", "wobbly": "2/3"}


def test_compare_by_one_or_several_columns(capsys, example_run: Path) -> None:
    """``--by run`` pools both agents of the one run (5/6); ``--by agent,run`` keys a row by
    both; the examples share one task and world set (none recorded): no group header."""
    code, out, err = _run(capsys, "compare", "--by", "run", "--format", "json", example_run)
    assert code == 0, err
    (row,) = json.loads(out)
    assert (row["run"], row["success"]) == ("example", "5/6") and "worlds" not in row
    code, out, err = _run(capsys, "compare", "--by", "agent,run", example_run)
    assert code == 0, err
    assert "==" not in out and "smooth / example" in out and "wobbly / example" in out


# --- topic maps and facts from the command line ------------------------------------------------


@pytest.fixture(scope="module")
def husky_bag(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A real-robot-like bag: pose on /odometry/filtered, scan on /front/scan, no facts."""
    root = tmp_path_factory.mktemp("husky")
    raw = write_episode_bag(
        root / "raw", LINE, obstacles=WALL, pose_topic="/odometry/filtered", also_odom=False
    )
    return _rename_topics(raw, root / "husky", {"/scan": "/front/scan"})


def test_topic_map_with_renamed_topics_and_facts(capsys, husky_bag: Path, tmp_path: Path) -> None:
    topic_map = tmp_path / "husky.yaml"
    topic_map.write_text(
        "pose: [/odometry/filtered]\n"
        "scan: /front/scan\n"
        "cmd_vel: /cmd_vel\n"
        "facts:\n"
        "  agent: husky_teleop\n"
        "  goal: [5.0, 0.0]\n"
        "  footprint: {length_m: 0.99, width_m: 0.67}\n"
    )
    code, out, err = _run(capsys, "compute", "--format", "json", "--topic-map", topic_map,
                          husky_bag)
    assert code == 0, err
    (row,) = json.loads(out)
    assert row["error"] == "" and row["warnings"] == ""
    assert row["pose_topic"] == "/odometry/filtered"
    assert row["agent"] == "husky_teleop"
    assert row["outcome"] == "goal" and row["success"] == 1.0
    assert row["start_goal_distance_m"] == pytest.approx(5.0, abs=EXACT)
    assert row["obstacle_dist_min_m"] == pytest.approx(1.0, abs=F32)  # read from /front/scan
    # Rectangle 0.99 x 0.67: the wall 1 m to the left is 1 - 0.335 = 0.665 m off the side.
    assert row["collision_count"] == 0.0
    assert row["safety_violation_time_s"] == 0.0

    # Without the map: the pose and the scan fall back to the bag's only Odometry and
    # LaserScan topics (each with a warning naming it); there is no goal.
    code, out, err = _run(capsys, "compute", "--format", "json", husky_bag)
    assert code == 0, err
    (row,) = json.loads(out)
    assert row["obstacle_dist_min_m"] == pytest.approx(1.0, abs=F32)
    assert row["outcome"] == "unknown"
    assert "/odometry/filtered" in row["warnings"]
    assert "using its only LaserScan topic '/front/scan'" in row["warnings"]


def test_topic_map_typo_exits_2_with_a_suggestion(capsys, husky_bag: Path, tmp_path: Path) -> None:
    topic_map = tmp_path / "typo.yaml"
    topic_map.write_text("pose: /odometry/filtered\nscna: /front/scan\n")
    code, out, err = _run(capsys, "compute", "--topic-map", topic_map, husky_bag)
    assert code == 2
    assert "did you mean 'scan'" in err
    assert out == ""


def test_explicit_missing_topic_is_an_error_row(capsys, husky_bag: Path) -> None:
    code, out, err = _run(capsys, "compute", "--format", "json", "--scan-topic", "/rear/scan",
                          husky_bag)
    assert code == 1
    (row,) = json.loads(out)
    assert "/rear/scan" in row["error"]
    assert "1 of 1 bag(s) failed" in err


@pytest.mark.parametrize(
    ("goal", "outcome"), [(None, "unknown"), ((5.0, 0.0), "goal"), ((10.0, 0.0), "timeout")]
)
def test_goal_option_judges_an_unknown_outcome(
    capsys, husky_bag: Path, goal: tuple[float, float] | None, outcome: str
) -> None:
    extra = ["--goal", *goal] if goal else []
    code, out, err = _run(capsys, "compute", "--format", "json", "--pose-topic",
                          "/odometry/filtered", *extra, husky_bag)
    assert code == 0, err
    (row,) = json.loads(out)
    assert row["outcome"] == outcome
    if goal:
        assert row["start_goal_distance_m"] == pytest.approx(goal[0], abs=EXACT)


# --- running -----------------------------------------------------------------------------


def test_jobs_2_gives_the_same_frame_as_jobs_1(capsys, example_run: Path) -> None:
    code1, serial, err1 = _run(capsys, "compute", "--format", "csv", "--jobs", "1", example_run)
    code2, parallel, err2 = _run(capsys, "compute", "--format", "csv", "--jobs", "2", example_run)
    assert code1 == code2 == 0, err1 + err2
    pd.testing.assert_frame_equal(pd.read_csv(io.StringIO(serial)),
                                  pd.read_csv(io.StringIO(parallel)))
    assert serial == parallel


def test_progress_bar_goes_to_stderr_only(capsys, runs: Path) -> None:
    code, out, err = _run(capsys, "compute", "--format", "json", "--progress", runs)
    assert code == 0
    assert "bags" in err
    assert len(json.loads(out)) == 2  # stdout parses: nothing but the result
    code, out, err = _run(capsys, "compute", "--format", "json", "--no-progress", runs)
    assert "bags" not in err


def test_warnings_go_to_stderr_not_stdout(capsys, husky_bag: Path) -> None:
    # No default pose topic: the bag's only Odometry topic is used, with a warning.
    for fmt in ("csv", "json"):
        code, out, err = _run(capsys, "compute", "--format", fmt, husky_bag)
        assert code == 0
        assert "warning:" in err and "/odometry/filtered" in err
        assert "warning:" not in out  # the stderr report stays off stdout
        parsed = json.loads(out) if fmt == "json" else pd.read_csv(io.StringIO(out))
        assert len(parsed) == 1


# --- plot --------------------------------------------------------------------------------


def test_plot_writes_one_png_per_episode_and_keeps_existing(
    capsys, runs: Path, tmp_path: Path
) -> None:
    out_dir = tmp_path / "figs"
    out_dir.mkdir()
    kept = out_dir / "alpha_ep0.png"
    kept.write_bytes(b"not a real png")
    code, out, err = _run(capsys, "plot", "--out", out_dir, runs)
    assert code == 0, err
    assert sorted(p.name for p in out_dir.iterdir()) == [
        "alpha_ep0.png", "beta_ep0.png", "comparison.png",
    ]
    assert kept.read_bytes() == b"not a real png"
    assert "kept existing" in err
    for name in ("beta_ep0.png", "comparison.png"):
        assert (out_dir / name).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert out == ""


def test_plot_names_bags_that_share_a_name_apart_and_splits_worlds(
    capsys, tmp_path: Path
) -> None:
    """Two agents' ``episode_0000`` in two worlds (one episode each in indoor:1, two in
    indoor:0): four figures named by their agent's folder, none kept from this same run, and
    one comparison per world holding more than one episode, never the worlds overlaid."""
    fp = {"radius_m": 0.2}
    for agent, world in (("td3", "indoor:0"), ("sac", "indoor:0"), ("dwa", "indoor:1")):
        write_episode_bag(tmp_path / "run" / agent / "episode_0000", LINE, obstacles=WALL,
                          goal=(5.0, 0.0), outcome="goal",
                          facts={"agent": agent, "footprint": fp, "world": world})
    out_dir = tmp_path / "figs"
    code, _, err = _run(capsys, "plot", "--out", out_dir, tmp_path / "run")
    assert code == 0, err
    assert sorted(p.name for p in out_dir.iterdir()) == [
        "comparison_indoor-0.png", "dwa-episode_0000.png", "sac-episode_0000.png",
        "td3-episode_0000.png"]
    assert "kept existing" not in err
    for png in out_dir.iterdir():
        assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


# --- a run of several agents and the console script ---------------------------------------


def test_examples_are_all_judged(capsys, example_run: Path) -> None:
    bags = sorted(p.name for p in example_run.iterdir() if p.is_dir())
    assert bags == [f"{a}_ep{k}" for a in ("smooth", "wobbly") for k in range(3)]
    code, out, err = _run(capsys, "compute", "--format", "json", example_run)
    assert code == 0, err
    rows = json.loads(out)
    assert len(rows) == 6 and all(r["error"] == "" for r in rows)
    outcomes = {Path(r["bag"]).name: r["outcome"] for r in rows}
    assert outcomes == {name: ("collision" if name == "wobbly_ep2" else "goal") for name in bags}
    wobbly = next(r for r in rows if Path(r["bag"]).name == "wobbly_ep2")
    assert wobbly["collision_count"] >= 1 and wobbly["success"] == 0.0
    assert all(not math.isnan(r["path_length_m"]) for r in rows)


def test_console_script_runs(runs: Path) -> None:
    script = Path(sys.executable).parent / "pic4rl-metrics"
    assert script.exists()
    done = subprocess.run(
        [str(script), "compute", "--format", "csv", str(runs / "alpha_ep0")],
        capture_output=True, text=True, timeout=120, check=False,
    )
    assert done.returncode == 0, done.stderr
    df = pd.read_csv(io.StringIO(done.stdout))
    assert df.loc[0, "path_length_m"] == pytest.approx(5.0, abs=EXACT)
