"""The four real-robot bags of ../shared/real_bags, judged through the public API and the CLI,
against the figures of their README.

The README's "duration" is the bag's span; ``clearance_time_s`` is the span of the odometry
header stamps, which this module reads itself with rosbags to compare.
"""

from __future__ import annotations

import csv
import hashlib
import io
import math
from pathlib import Path
from typing import NamedTuple

import pandas as pd
import pytest
from rosbags.highlevel import AnyReader
from rosbags.typesys import Stores, get_typestore

import pic4rl_metrics
from pic4rl_metrics.cli.commands import main

REAL_BAGS = Path(__file__).resolve().parents[4] / "shared" / "real_bags"


class Expected(NamedTuple):
    """A bag's figures from the README."""

    pose_topic: str
    duration_s: float
    path_m: float
    net_m: float
    scan_min_m: float  # NaN: no scan
    n_odom: int
    n_scan: int


README = {
    "neato_person_follower": Expected("/odom", 36.37, 5.72, 0.98, 0.332, 194, 181),
    "neato_obstacle_avoider": Expected("/odom", 32.45, 6.37, 0.95, 0.323, 166, 153),
    "neato_teleop_odom_spikes": Expected("/odom", 56.77, 5.37, 0.25, 0.324, 290, 243),
    "husky_outdoor_gps_odom": Expected(
        "/husky_velocity_controller/odom", 395.31, 358.8, 30.9, math.nan, 3952, 0
    ),
}
SCAN_METRICS = (
    "obstacle_dist_min_m",
    "obstacle_dist_mean_m",
    "scan_range_mean_m",
    "collision_count",
    "safety_violation_time_s",
)


@pytest.fixture(scope="module")
def real_bags() -> Path:
    if not REAL_BAGS.is_dir():
        pytest.skip("../shared/real_bags not found: real-robot bag tests not run")
    return REAL_BAGS


@pytest.fixture(scope="module")
def frame(real_bags: Path) -> pd.DataFrame:
    """One row per real bag, indexed by the bag's directory name."""
    result = pic4rl_metrics.compute([real_bags / name for name in README])
    table = result.frame
    table.index = [Path(b).name for b in table["bag"]]
    return table


def _odom_span_s(bag: Path, topic: str) -> float:
    """Span (s) of the header stamps of ``topic``, read independently with rosbags."""
    stamps: list[int] = []
    with AnyReader([bag], default_typestore=get_typestore(Stores.ROS2_HUMBLE)) as reader:
        conns = [c for c in reader.connections if c.topic == topic]
        for conn, _, raw in reader.messages(connections=conns):
            stamp = reader.deserialize(raw, conn.msgtype).header.stamp
            stamps.append(stamp.sec * 1_000_000_000 + stamp.nanosec)
    return (max(stamps) - min(stamps)) * 1e-9


def _snapshot(root: Path) -> dict[str, tuple[int, int, str]]:
    """(mtime ns, size, sha256) of every file under ``root``."""
    return {
        str(p.relative_to(root)): (
            p.stat().st_mtime_ns,
            p.stat().st_size,
            hashlib.sha256(p.read_bytes()).hexdigest(),
        )
        for p in sorted(root.rglob("*"))
        if p.is_file()
    }


def test_the_readme_describes_the_bags_this_module_checks(real_bags: Path) -> None:
    found = sorted(p.name for p in real_bags.iterdir() if p.is_dir())
    assert found == sorted(README)
    text = (real_bags / "README.md").read_text()
    for name, exp in README.items():
        assert f"`{name}/`" in text
        assert f"{exp.path_m}" in text and f"net {exp.net_m}" in text.replace(
            "net displacement", "net"
        )


def test_every_real_bag_gives_a_row_without_error(frame: pd.DataFrame) -> None:
    assert sorted(frame.index) == sorted(README)
    assert (frame["error"] == "").all(), frame["error"].to_dict()
    for name, exp in README.items():
        row = frame.loc[name]
        assert row["pose_topic"] == exp.pose_topic
        assert row["n_poses"] == exp.n_odom
        assert row["n_scans"] == exp.n_scan
        assert row["outcome"] == "unknown" and math.isnan(row["success"])  # no goal, no outcome


@pytest.mark.parametrize("name", sorted(README))
def test_path_length_and_net_displacement_match_the_readme(frame: pd.DataFrame, name: str) -> None:
    exp, row = README[name], frame.loc[name]
    assert row["path_length_m"] == pytest.approx(exp.path_m, rel=0.005, abs=0.02)
    # README figures are rounded to the digits shown.
    assert row["net_displacement_m"] == pytest.approx(
        exp.net_m, abs=0.05 if exp.net_m > 10 else 0.0051
    )
    assert row["net_displacement_m"] <= row["path_length_m"]


@pytest.mark.parametrize("name", sorted(README))
def test_clearance_time_is_the_odometry_span(
    frame: pd.DataFrame, real_bags: Path, name: str
) -> None:
    exp, row = README[name], frame.loc[name]
    assert row["clearance_time_s"] == pytest.approx(
        _odom_span_s(real_bags / name, exp.pose_topic), abs=0.1
    )
    assert row["clearance_time_s"] == pytest.approx(exp.duration_s, abs=0.2)  # the bag's span


@pytest.mark.parametrize("name", sorted(n for n, e in README.items() if e.n_scan))
def test_nearest_obstacle_is_the_readme_minimum_scan_range(frame: pd.DataFrame, name: str) -> None:
    row = frame.loc[name]
    assert row["obstacle_dist_min_m"] == pytest.approx(README[name].scan_min_m, abs=5e-4)
    assert row["obstacle_dist_min_m"] <= row["obstacle_dist_mean_m"] <= row["scan_range_mean_m"]
    # No footprint is known for a real-robot log: collisions cannot be judged.
    assert math.isnan(row["collision_count"]) and math.isnan(row["safety_violation_time_s"])


def test_husky_has_no_scan_and_its_odometry_topic_is_picked_with_a_warning(
    frame: pd.DataFrame,
) -> None:
    row = frame.loc["husky_outdoor_gps_odom"]
    assert row["n_scans"] == 0
    assert all(math.isnan(row[m]) for m in SCAN_METRICS)
    assert row["pose_topic"] == "/husky_velocity_controller/odom"
    assert "/husky_velocity_controller/odom" in row["warnings"]
    assert all(frame.loc[n, "warnings"] == "" for n in README if n != "husky_outdoor_gps_odom")


def test_teleop_odometry_spikes_show_in_the_maximum_acceleration(frame: pd.DataFrame) -> None:
    spikes = frame.loc["neato_teleop_odom_spikes", "lin_acc_max_mps2"]
    others = frame.drop(index="neato_teleop_odom_spikes")["lin_acc_max_mps2"]
    # A 1.2 m/s twist glitch between ~0.2 s samples: several m/s², the others stay below 1.
    assert spikes > 3.0
    assert spikes > 3 * others.max()


def test_teleop_odometry_spikes_are_counted_and_warned_with_their_times(
    real_bags: Path, capsys: pytest.CaptureFixture[str],
) -> None:
    """Issue 37, item 10: the six glitches (0.63-1.20 m/s on a robot that tops out near
    0.3 m/s, at the README's 6.5, 10.6, 13.6, 23.2, 29.7 and 33.2 s) passed unflagged even with
    ``--max-speed 0.3``. Above twice 0.3 m/s they are counted and warned, with their times; the
    bag is still judged (isolated spikes, not two sources), its numbers as read."""
    bag = real_bags / "neato_teleop_odom_spikes"
    assert main(["compute", str(bag), "--max-speed", "0.3", "--format", "csv"]) == 0
    out, err = capsys.readouterr()
    row = next(csv.DictReader(io.StringIO(out)))
    assert row["error"] == "" and int(row["n_speed_outliers"]) == 6
    assert float(row["lin_acc_max_mps2"]) == pytest.approx(6.213, abs=1e-3)
    assert float(row["lin_jerk_max_mps3"]) == pytest.approx(62.35, abs=1e-2)
    assert float(row["path_length_m"]) == pytest.approx(5.37, abs=0.01)
    assert (f"warning: {bag}: /odom: 6 implausible speed sample(s) (odometry spikes?), above "
            "0.6 m/s (2 x the max speed 0.3 m/s), up to 1.2 m/s, at t = 6.52, 10.57, 13.58, "
            "23.16, 29.69, 33.16 s; kept as read: the acceleration and jerk columns include them "
            "(max linear acceleration 6.21 m/s^2 at them; max linear jerk 62.3 m/s^3 at them)"
            ) in err
    # without a max speed nothing a robot could do is beyond 20 m/s: no outlier, no warning
    assert main(["compute", str(bag), "--format", "csv"]) == 0
    row = next(csv.DictReader(io.StringIO(capsys.readouterr().out)))
    assert int(row["n_speed_outliers"]) == 0 and row["warnings"] in ("", None)


def test_velocities_stay_within_the_readme_twist_ranges(frame: pd.DataFrame) -> None:
    avoider = frame.loc["neato_obstacle_avoider"]
    assert 0.133 <= avoider["lin_vel_mean_mps"] <= 0.302  # vx in [0.133, 0.302], no vy
    assert avoider["ang_vel_mean_radps"] <= 1.15
    husky = frame.loc["husky_outdoor_gps_odom"]
    assert 0 < husky["lin_vel_mean_mps"] <= 1.017
    # Mean speed times duration is the distance the twist claims, close to the odometry path.
    assert husky["lin_vel_mean_mps"] * husky["clearance_time_s"] == pytest.approx(
        husky["path_length_m"], rel=0.05
    )


def test_cli_compute_csv_prints_one_row_per_real_bag(
    real_bags: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    code = main(["compute", str(real_bags), "--format", "csv"])
    out, err = capsys.readouterr()
    assert code == 0, err
    rows = list(csv.DictReader(io.StringIO(out)))
    assert len(rows) == 4
    assert sorted(Path(r["bag"]).name for r in rows) == sorted(README)
    assert all(r["error"] == "" for r in rows)
    by_name = {Path(r["bag"]).name: r for r in rows}
    for name, exp in README.items():
        assert float(by_name[name]["path_length_m"]) == pytest.approx(
            exp.path_m, rel=0.005, abs=0.02
        )
    assert "/husky_velocity_controller/odom" in err  # the auto-picked topic is reported


def test_cli_with_a_missing_pose_topic_makes_every_bag_an_error_row(
    real_bags: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    code = main(["compute", str(real_bags), "--format", "csv", "--pose-topic", "/nope"])
    out, err = capsys.readouterr()
    assert code == 1
    rows = list(csv.DictReader(io.StringIO(out)))
    assert len(rows) == 4
    for row in rows:
        assert "'/nope'" in row["error"]
        assert Path(row["bag"]).name in row["error"]
        assert row["path_length_m"] == ""
    assert "4 of 4 bag(s) failed" in err


def test_judging_never_modifies_the_real_bags(
    real_bags: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    before = _snapshot(real_bags)
    assert len(before) == 9  # README + 4 x (metadata.yaml, one .db3)
    result = pic4rl_metrics.compute([real_bags], jobs=2)
    assert not result.failed
    main(["compute", str(real_bags), "--format", "json"])
    capsys.readouterr()
    assert _snapshot(real_bags) == before
