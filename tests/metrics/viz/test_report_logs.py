"""The report of logs without a goal (issue 37, item 11): real-robot bags have no success to
rank and no failure to map, so the page shows what they have — time, path, speeds, obstacle
distances and the trajectory from the pose stream — and no "(unknown) in ?" line."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from pic4rl_metrics.cli import commands as cli
from pic4rl_metrics.synthetic.synthetic import write_long_bag
from report_page import Page

REAL_BAGS = Path(__file__).resolve().parents[4] / "shared" / "real_bags"
#: Path length (m) and scan minimum (m) per real bag, from its README (NaN: no scan).
REAL = {"neato_person_follower": (5.72, 0.332), "neato_obstacle_avoider": (6.37, 0.323),
        "neato_teleop_odom_spikes": (5.37, 0.324), "husky_outdoor_gps_odom": (358.8, math.nan)}


def _report(tmp_path: Path, *bags: Path) -> Page:
    out = tmp_path / "report.html"
    assert cli.main(["report", *map(str, bags), "--out", str(out), "--no-progress"]) == 0
    page = Page()
    page.feed(out.read_text())
    return page


def _logs(page: Page) -> dict[str, dict[str, str]]:
    header, *rows = page.rows["logs"]
    return {r[1].split("/")[-1]: dict(zip(header, r)) for r in rows}


def test_a_real_robot_report_shows_what_its_bags_have(tmp_path: Path) -> None:
    if not REAL_BAGS.is_dir():
        pytest.skip("../shared/real_bags not found")
    page = _report(tmp_path, *(REAL_BAGS / name for name in REAL))
    text = "".join(page.text)
    assert "Logs without a goal" in page.h2 and "(unknown) in ?" not in text
    assert "No episode has a goal: nothing to rank" in text
    logs = _logs(page)
    assert sorted(logs) == sorted(REAL)
    for name, (path_m, scan_min_m) in REAL.items():
        row = logs[name]
        assert float(row["path [m]"]) == pytest.approx(path_m, abs=0.02)
        assert float(row["time [s]"]) > 0 and float(row["v mean [m/s]"]) > 0
        if math.isnan(scan_min_m):
            assert row["min obstacle distance [m]"] == "–"
        else:
            assert float(row["min obstacle distance [m]"]) == pytest.approx(scan_min_m, abs=0.006)
    # one trajectory per log, drawn from its pose stream, in the logs' own section
    assert sorted(page.section_images["sec-logs"]) == sorted(
        f"trajectory of real_bags/{name}" for name in REAL)
    assert "sec-failures" not in page.section_images


def test_a_log_without_a_goal_is_summarized_not_ranked(bench_bags: Path, tmp_path: Path) -> None:
    """Beside a benchmark, a 6-s log along +x at 0.5 m/s past a wall 2 + 0.5 sin t m away:
    3 m in 6 s, nearest obstacle 1.5 m; the benchmark's agents stay ranked."""
    log = write_long_bag(tmp_path / "robot_log", 0.1)
    page = _report(tmp_path, bench_bags / "run0", log)
    (row,) = _logs(page).values()
    assert float(row["time [s]"]) == pytest.approx(6.0, abs=1e-6)
    assert float(row["path [m]"]) == pytest.approx(3.0, abs=1e-6)
    assert float(row["v mean [m/s]"]) == pytest.approx(0.5, abs=1e-6)
    assert float(row["min obstacle distance [m]"]) == pytest.approx(1.5, abs=0.01)
    (alt,) = page.section_images["sec-logs"]
    assert alt.startswith("trajectory of ") and alt.endswith("/robot_log")
    ranked = [r[0] for r in page.rows["leaderboard"][1:]]
    assert sorted(ranked) == ["dwa", "planner", "td3"]
    episodes = page.rows["episodes"][1:]
    assert len(episodes) == 13  # 12 benchmark episodes and the log, each a row
    assert not any(cell == "nan" for r in episodes for cell in r)


def test_the_footprints_clearance_is_a_column_only_where_a_footprint_gave_one() -> None:
    import pandas as pd

    from pic4rl_metrics.viz.report_logs import logs_section

    frame = pd.DataFrame({"bag": ["/b/a", "/b/b"], "error": ["", ""],
                          "outcome": ["unknown", "unknown"], "path_length_m": [1.0, 2.0],
                          "footprint_clearance_min_m": [math.nan, math.nan]})
    names = pd.Series(["x", "y"])
    page = Page()
    page.feed(logs_section(frame, names, {}, str) or "")
    assert page.rows["logs"][0] == ["agent", "bag", "path_length_m"]
    page = Page()
    page.feed(logs_section(frame.assign(footprint_clearance_min_m=[0.25, math.nan]), names, {},
                           str) or "")
    header, first, second = page.rows["logs"]
    assert header[-1] == "footprint_clearance_min_m" and first[-1] == "0.25" and second[-1] == "–"
