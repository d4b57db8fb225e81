"""Bad input: each broken bag raises a clear error from ``read_episode`` and becomes an error
row naming the bag and the problem in ``compute``; the batch goes on (a good bag beside it
keeps its numbers), the CLI prints every row and exits 1, and no input is written to.

Bags are built in temporary directories: good ones with ``synthetic``, malformed ones (stamps
out of order, a pose topic of the wrong type, no poses) message by message with rosbags.
"""

from __future__ import annotations

import csv
import io
import math
import os
import random
import shutil
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from rosbags.rosbag2 import Writer
from rosbags.typesys import Stores, get_typestore

from pic4rl_metrics import (
    BagError,
    ConfigError,
    EpisodeError,
    MetricsError,
    TopicError,
    compute,
    read_episode,
)
from pic4rl_metrics.cli.commands import main
from pic4rl_metrics.contract import parse_facts
from pic4rl_metrics.synthetic.synthetic import (
    DEFAULT_T0_NS,
    Obstacles,
    Track,
    straight_line,
    write_episode_bag,
)
from pic4rl_metrics.bags.topics import TopicMap

pytestmark = pytest.mark.bad_input

TS = get_typestore(Stores.ROS2_JAZZY)
T = TS.types
ODOMETRY = "nav_msgs/msg/Odometry"
LINE = straight_line(0.5, 4.0)  # 2 m along +x, 41 poses
WALL = Obstacles(segments=((-100.0, 1.0, 100.0, 1.0),))  # 1 m to the left


# --------------------------------------------------------------------------- bag building


def _header(ns: int, frame: str) -> Any:
    sec, nanosec = divmod(int(ns), 1_000_000_000)
    return T["std_msgs/msg/Header"](T["builtin_interfaces/msg/Time"](sec, nanosec), frame)


def _odometry(ns: int, x: float, y: float, yaw: float, vx: float = 0.0, wz: float = 0.0) -> Any:
    vec = T["geometry_msgs/msg/Vector3"]
    q = T["geometry_msgs/msg/Quaternion"](0.0, 0.0, math.sin(yaw / 2), math.cos(yaw / 2))
    pose = T["geometry_msgs/msg/Pose"](T["geometry_msgs/msg/Point"](x, y, 0.0), q)
    twist = T["geometry_msgs/msg/Twist"](vec(vx, 0.0, 0.0), vec(0.0, 0.0, wz))
    return T[ODOMETRY](
        _header(ns, "odom"),
        "base_link",
        T["geometry_msgs/msg/PoseWithCovariance"](pose, np.zeros(36)),
        T["geometry_msgs/msg/TwistWithCovariance"](twist, np.zeros(36)),
    )


def _scan(ns: int, ranges: Sequence[float]) -> Any:
    n = len(ranges)
    return T["sensor_msgs/msg/LaserScan"](
        _header(ns, "base_scan"),
        -math.pi,
        math.pi - 2 * math.pi / n,
        2 * math.pi / n,
        0.0,
        0.0,
        0.05,
        10.0,
        np.asarray(ranges, dtype=np.float32),
        np.zeros(0, np.float32),
    )


def _write(
    path: Path, messages: Sequence[tuple[str, Any]], empty_topics: dict[str, str] | None = None
) -> Path:
    """A bag holding ``messages`` (topic, message) in the given order, received 10 ms apart,
    plus topics that have a connection and no message."""
    with Writer(path, version=9) as writer:
        conns: dict[str, Any] = {}
        for topic, msgtype in (empty_topics or {}).items():
            conns[topic] = writer.add_connection(topic, msgtype, typestore=TS)
        for i, (topic, msg) in enumerate(messages):
            if topic not in conns:
                conns[topic] = writer.add_connection(topic, msg.__msgtype__, typestore=TS)
            writer.write(
                conns[topic], DEFAULT_T0_NS + i * 10_000_000, TS.serialize_cdr(msg, msg.__msgtype__)
            )
    return path


def _odom_messages(
    stamps_ms: Sequence[int], xs: Sequence[float], topic: str = "/odom"
) -> list[tuple[str, Any]]:
    """Odometry along +x at ``xs`` (m), header stamps in ms after DEFAULT_T0_NS."""
    return [
        (topic, _odometry(DEFAULT_T0_NS + ms * 1_000_000, x, 0.0, 0.0, vx=x / 10 + 0.1))
        for ms, x in zip(stamps_ms, xs, strict=True)
    ]


def _snapshot(root: Path) -> dict[str, tuple[int, int, bytes]]:
    return {
        str(p.relative_to(root)): (p.stat().st_mtime_ns, p.stat().st_size, p.read_bytes())
        for p in sorted(root.rglob("*"))
        if p.is_file()
    }


def _row(result: Any, name: str) -> Any:
    """The one result whose bag is named ``name`` (last path component)."""
    found = [r for r in result.results if Path(r.bag).name == name]
    assert len(found) == 1, [r.bag for r in result.results]
    return found[0]


# --------------------------------------------------------------------------- fixtures


@pytest.fixture(scope="module")
def bad(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A directory of one good and many broken bags, each in its own sub-directory."""
    root = tmp_path_factory.mktemp("bad")
    good = write_episode_bag(root / "good", LINE, obstacles=WALL)
    rng = random.Random(1)

    corrupt = root / "corrupt"
    shutil.copytree(good, corrupt)
    next(corrupt.glob("*.db3")).write_bytes(rng.randbytes(50_000))

    data = next(good.glob("*.db3")).read_bytes()
    (root / "truncated").mkdir()
    (root / "truncated" / "truncated.db3").write_bytes(data[: len(data) // 2])

    (root / "empty").mkdir()

    garbage = root / "garbage_metadata"
    shutil.copytree(good, garbage)
    (garbage / "metadata.yaml").write_text("rosbag2_bagfile_information: {{{ [ :: not yaml\n")

    scan_only = [("/scan", _scan(DEFAULT_T0_NS + i * 100_000_000, [1.0] * 8)) for i in range(5)]
    _write(
        root / "no_pose_topic",
        [
            *scan_only,
            (
                "/cmd_vel",
                T["geometry_msgs/msg/Twist"](
                    T["geometry_msgs/msg/Vector3"](0.1, 0.0, 0.0),
                    T["geometry_msgs/msg/Vector3"](0.0, 0.0, 0.0),
                ),
            ),
        ],
    )
    _write(
        root / "string_odom", [("/odom", T["std_msgs/msg/String"](f"pose {i}")) for i in range(5)]
    )
    _write(root / "zero_poses", scan_only, empty_topics={"/odom": ODOMETRY})
    _write(root / "one_pose", _odom_messages([0], [0.0]))
    return root


# --------------------------------------------------------------------------- each broken bag


def test_a_db3_of_random_bytes_is_a_bag_error(bad: Path) -> None:
    with pytest.raises(BagError, match=r"'.*corrupt': cannot open bag: .*not a database"):
        read_episode(bad / "corrupt")


def test_a_truncated_db3_without_metadata_is_a_bag_error(bad: Path) -> None:
    with pytest.raises(BagError, match=r"truncated\.db3': cannot open bag: .*malformed"):
        read_episode(bad / "truncated" / "truncated.db3")


def _mutations(data: bytes, n: int, *, keep_header: int) -> list[tuple[str, bytes]]:
    """``n`` damaged copies of ``data`` (seeded): every third cut short, the others with
    1 to 512 bytes overwritten after the first ``keep_header`` bytes."""
    rng = random.Random(0)
    out = []
    for k in range(n):
        if k % 3 == 0:
            cut = rng.randrange(keep_header, len(data))
            out.append((f"cut at {cut}", data[:cut]))
            continue
        mutated = bytearray(data)
        start = rng.randrange(keep_header, len(data) - 64)
        for i in range(start, min(len(data), start + rng.choice([1, 8, 64, 512]))):
            mutated[i] = rng.randrange(256)
        out.append((f"bytes at {start}", bytes(mutated)))
    return out


@pytest.mark.parametrize(("storage", "suffix"), [("sqlite3", ".db3"), ("mcap", ".mcap")])
def test_a_storage_file_damaged_inside_is_an_episode_or_a_bag_error(
    tmp_path: Path, storage: str, suffix: str
) -> None:
    """A recorder's file cut short or with bytes overwritten past its header: it may open and
    fail only while its messages are read. Whatever happens must be an Episode or a
    MetricsError naming the file, never a storage library's own exception."""
    good = write_episode_bag(
        tmp_path / "good",
        straight_line(0.5, 10.0),
        obstacles=WALL,
        storage=storage,
        write_metadata=False,
    )
    data = next(good.glob(f"*{suffix}")).read_bytes()
    escaped: list[str] = []
    for k, (what, damaged) in enumerate(_mutations(data, 60, keep_header=4096)):
        path = tmp_path / f"damaged_{k}{suffix}"
        path.write_bytes(damaged)
        try:
            read_episode(path)
        except MetricsError as err:
            assert path.name in str(err)
        except Exception as err:  # noqa: BLE001 - what escapes is the finding
            escaped.append(
                f"{path.name} ({what}): {type(err).__module__}.{type(err).__name__}: {err}"
            )
    assert escaped == []


def test_an_empty_directory_is_a_bag_error_and_an_error_row(bad: Path) -> None:
    with pytest.raises(BagError, match=r"'.*empty': cannot open bag"):
        read_episode(bad / "empty")
    result = compute([bad / "empty"])
    assert len(result.results) == 1
    assert "empty" in result.results[0].error and "no bag found here" in result.results[0].error


def test_garbage_metadata_is_a_bag_error(bad: Path) -> None:
    with pytest.raises(BagError, match=r"garbage_metadata': cannot open bag: .*(YAML|metadata)"):
        read_episode(bad / "garbage_metadata")


@pytest.mark.parametrize(("text", "why"), [
    ("rosbag2_bagfile_information: [\n  {: garbage\n",
     "not valid YAML: while parsing a flow node; did not find expected node content; at line "
     "2, column 4"),
    ("\x00\x01 garbage: : :\n", "not valid YAML: unacceptable character #x0000: control "
     "characters are not allowed; at position 0"),
    ("just a string\n", "not rosbag2 metadata: string indices must be integers, not 'str'"),
])
def test_a_garbage_metadata_yaml_is_one_line_naming_the_file(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], text: str, why: str,
) -> None:
    """It printed the YAML parser's 4-line error (issue 37, minor)."""
    bag = write_episode_bag(tmp_path / "bag", LINE)
    (bag / "metadata.yaml").write_text(text)
    assert main(["compute", "--format", "csv", str(bag)]) == 1
    lines = capsys.readouterr().err.splitlines()
    assert lines == [f"error: {str(bag)!r}: cannot open bag: {str(bag / 'metadata.yaml')!r}: {why}",
                     "1 of 1 bag(s) failed"]


def test_a_bag_without_the_pose_topic_names_the_topics_it_has(bad: Path) -> None:
    with pytest.raises(
        TopicError,
        match=r"no_pose_topic': none of the pose topics \['/ground_truth', '/odom'\] is in the bag"
        r"; it has \['/cmd_vel', '/scan'\]",
    ):
        read_episode(bad / "no_pose_topic")


def test_a_pose_topic_of_an_unsupported_type_is_a_topic_error(bad: Path) -> None:
    with pytest.raises(
        TopicError,
        match=r"string_odom': pose topic '/odom' has type 'std_msgs/msg/String'; expected one of",
    ):
        read_episode(bad / "string_odom")


@pytest.mark.parametrize(("name", "count"), [("zero_poses", 0), ("one_pose", 1)])
def test_fewer_than_two_poses_is_an_episode_error(bad: Path, name: str, count: int) -> None:
    with pytest.raises(
        EpisodeError, match=rf"{name}': pose topic '/odom' has {count} message\(s\); at least 2"
    ):
        read_episode(bad / name)


def test_the_batch_goes_on_past_every_broken_bag(bad: Path) -> None:
    before = _snapshot(bad)
    # An empty directory inside a searched one holds no bag and is passed over; named on
    # its own it is an error row.
    result = compute([bad, bad / "empty", bad / "no_such_bag", str(bad / "nothing_*.db3")])
    after = _snapshot(bad)
    assert after == before  # nothing written into any input

    expected = {
        "corrupt": "not a database",
        "truncated.db3": "malformed",
        "empty": "no bag found here",
        "garbage_metadata": "cannot open bag",
        "no_pose_topic": "it has ['/cmd_vel', '/scan']",
        "string_odom": "'std_msgs/msg/String'",
        "zero_poses": "has 0 message(s)",
        "one_pose": "has 1 message(s)",
        "no_such_bag": "no such file or directory",
        "nothing_*.db3": "no file matches this pattern",
    }
    errors = {Path(r.bag).name: r.error for r in result.results if r.error}
    assert sorted(errors) == sorted(expected)
    for name, what in expected.items():
        assert name in errors[name] and what in errors[name], errors[name]
    good = _row(result, "good")
    assert good.error == "" and good.metrics is not None
    assert good.metrics.path_length_m == pytest.approx(2.0, abs=1e-9)
    assert good.metrics.obstacle_dist_min_m == pytest.approx(1.0, abs=1e-6)
    frame = result.frame
    assert len(frame) == len(expected) + 1
    assert frame.loc[frame["error"] != "", "path_length_m"].isna().all()


def test_the_cli_prints_every_row_and_exits_1_when_a_bag_failed(
    bad: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    code = main(
        [
            "compute",
            str(bad / "good"),
            str(bad / "corrupt"),
            str(bad / "string_odom"),
            str(bad / "nope*"),
            "--format",
            "csv",
        ]
    )
    out, err = capsys.readouterr()
    assert code == 1
    rows = {Path(r["bag"]).name: r for r in csv.DictReader(io.StringIO(out))}
    assert sorted(rows) == ["corrupt", "good", "nope*", "string_odom"]
    assert rows["good"]["error"] == "" and float(rows["good"]["path_length_m"]) == pytest.approx(
        2.0
    )
    for name in ("corrupt", "string_odom", "nope*"):
        assert rows[name]["error"] and rows[name]["path_length_m"] == ""
        assert f"error: '{bad / name}'" in err
    assert "3 of 4 bag(s) failed" in err

    assert main(["compute", str(bad / "good"), "--format", "csv"]) == 0
    capsys.readouterr()


def test_a_bag_with_two_odometry_topics_and_no_default_one_lists_the_candidates(
    tmp_path: Path,
) -> None:
    bag = _write(
        tmp_path / "two_odom",
        [
            *_odom_messages([0, 100], [0.0, 0.1], topic="/wheel/odom"),
            *_odom_messages([0, 100], [0.0, 0.1], topic="/gps/odom"),
        ],
    )
    with pytest.raises(
        TopicError,
        match=r"pose-like topics in it: \['/gps/odom', '/wheel/odom'\] \(pass --pose-topic\)",
    ):
        read_episode(bag)


def test_an_unreadable_fact_is_left_out_with_a_warning_naming_the_key(tmp_path: Path) -> None:
    """One bad fact costs only the metrics that need it: the rest of the row stays."""
    facts = {"footprint": "banana", "goal": [2.0, 0.0], "agent": "a"}
    bag = write_episode_bag(tmp_path / "bad_facts", LINE, facts=facts)
    episode = read_episode(bag)
    assert episode.facts.footprint is None and episode.facts.goal == (2.0, 0.0)
    assert any("footprint" in w and "'banana'" in w and "ignored" in w for w in episode.warnings)
    row = _row(compute([bag]), "bad_facts")
    assert row.error == "" and row.metrics.path_length_m == pytest.approx(2.0, abs=1e-9)
    assert row.metrics.goal_dist_final_m == pytest.approx(0.0, abs=1e-9)
    assert math.isnan(row.metrics.collision_count)  # needs the footprint
    with pytest.raises(ConfigError, match=r"footprint.*'banana'"):  # typed by a user: refused
        parse_facts({"footprint": "banana"}, source="command line")


# --------------------------------------------------------------------------- odd but readable


def test_repeated_and_backwards_stamps_are_sorted_with_warnings(tmp_path: Path) -> None:
    """Messages received out of header-stamp order, with two repeated stamps (the last one
    received wins): the metrics equal those of the cleaned-up, sorted bag."""
    stamps = [0, 100, 300, 200, 400, 100, 500, 700, 600, 700, 800]
    xs = [0.0, 9.9, 0.3, 0.2, 0.4, 0.1, 0.5, 9.9, 0.6, 0.7, 0.8]  # 9.9: overridden repeats
    messy = _write(tmp_path / "messy", _odom_messages(stamps, xs))
    clean = _write(
        tmp_path / "clean",
        _odom_messages(
            [0, 100, 200, 300, 400, 500, 600, 700, 800],
            [0.0, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8],
        ),
    )
    episode = read_episode(messy)
    assert any("went backwards" in w and "/odom" in w for w in episode.warnings), episode.warnings
    assert any("2 repeated stamp(s)" in w for w in episode.warnings), episode.warnings
    assert read_episode(clean).warnings == ()
    result = compute([messy, clean])
    messy_m, clean_m = _row(result, "messy").metrics, _row(result, "clean").metrics
    assert messy_m is not None and clean_m is not None
    assert messy_m.path_length_m == pytest.approx(0.8, abs=1e-12)
    differ = {
        k: (v, dict(clean_m)[k])
        for k, v in dict(messy_m).items()
        if not (
            v == dict(clean_m)[k]
            or (isinstance(v, float) and math.isnan(v) and math.isnan(dict(clean_m)[k]))
        )
    }
    assert differ == {}
    frame = result.frame.set_index("bag")
    assert "went backwards" in frame.loc[str(messy), "warnings"]
    assert frame.loc[str(clean), "warnings"] == ""


def test_nan_and_inf_scan_values_follow_rep_117(tmp_path: Path) -> None:
    n = len(LINE)
    inf, nan = math.inf, math.nan
    mixed = [[inf, nan, 2.0, 3.0, 20.0, inf, inf, inf] for _ in range(n)]
    mixed[5] = [-inf, inf, nan, inf, inf, inf, inf, inf]  # -inf: closer than range_min 0.05
    mixed[6] = [inf, nan, inf, nan, 20.0, inf, inf, inf]  # no valid beam in this scan
    # 20.0 > range_max and 0.01 < range_min: finite but out of range, so no obstacle either
    none_valid = [[inf, nan, 20.0, 0.01, inf, inf, inf, inf] for _ in range(n)]
    result = compute(
        [
            write_episode_bag(tmp_path / "mixed", LINE, scans=mixed),
            write_episode_bag(tmp_path / "none_valid", LINE, scans=none_valid),
        ]
    )
    m = _row(result, "mixed").metrics
    assert m is not None and m.n_scans == n
    assert m.obstacle_dist_min_m == pytest.approx(0.05, abs=1e-7)
    assert math.isfinite(m.obstacle_dist_mean_m)
    # valid returns: 2.0 and 3.0 in n-2 scans, range_min in one
    assert m.scan_range_mean_m == pytest.approx(
        ((n - 2) * 5.0 + 0.05) / (2 * (n - 2) + 1), rel=1e-6
    )
    v = _row(result, "none_valid").metrics
    assert v is not None and v.n_scans == n
    assert math.isnan(v.obstacle_dist_min_m)
    assert math.isnan(v.obstacle_dist_mean_m) and math.isnan(v.scan_range_mean_m)
    assert v.path_length_m == pytest.approx(2.0, abs=1e-9)  # the rest is still judged


def _without(track: Track, drop: Sequence[int]) -> Track:
    keep = np.setdiff1d(np.arange(len(track)), drop)
    return Track(*(getattr(track, k)[keep] for k in ("t_s", "x", "y", "yaw", "vx", "vy", "wz")))


def test_nan_poses_are_dropped_with_a_warning(tmp_path: Path) -> None:
    x, y, yaw = LINE.x.copy(), LINE.y.copy(), LINE.yaw.copy()
    x[3], y[10], yaw[20] = math.nan, math.inf, math.nan
    holey = Track(LINE.t_s, x, y, yaw, LINE.vx, LINE.vy, LINE.wz)
    bag = write_episode_bag(tmp_path / "holey", holey, cmd=False)
    reference = write_episode_bag(tmp_path / "reference", _without(LINE, [3, 10, 20]), cmd=False)
    episode = read_episode(bag)
    assert any("3 pose(s) with NaN/inf dropped" in w for w in episode.warnings), episode.warnings
    assert len(episode.pose) == len(LINE) - 3
    result = compute([bag, reference])
    got, want = _row(result, "holey").metrics, _row(result, "reference").metrics
    assert got is not None and want is not None
    for key, value in dict(want).items():
        other = dict(got)[key]
        assert other == value or (
            isinstance(value, float) and math.isnan(value) and math.isnan(other)
        ), key


def test_a_bag_whose_poses_are_all_nan_is_an_episode_error(tmp_path: Path) -> None:
    nan = np.full(len(LINE), math.nan)
    bag = write_episode_bag(
        tmp_path / "all_nan", Track(LINE.t_s, nan, nan, nan, LINE.vx, LINE.vy, LINE.wz)
    )
    with pytest.raises(
        EpisodeError, match=r"all_nan': pose topic '/ground_truth' has 0 usable pose"
    ):
        read_episode(bag)
    row = compute([bag]).results[0]
    assert "all_nan" in row.error and "usable pose" in row.error


# --------------------------------------------------------------------------- topics and inputs


def test_an_explicit_scan_topic_that_is_missing_is_an_error(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    bag = write_episode_bag(tmp_path / "no_scan", LINE)  # no obstacles: no /scan at all
    default = compute([bag]).results[0]
    assert default.error == "" and default.metrics is not None
    assert math.isnan(default.metrics.obstacle_dist_min_m) and default.metrics.n_scans == 0

    code = main(["compute", str(bag), "--scan-topic", "/missing", "--format", "csv"])
    out, err = capsys.readouterr()
    assert code == 1
    (row,) = csv.DictReader(io.StringIO(out))
    assert "scan topic '/missing' is not in the bag" in row["error"] and "no_scan" in row["error"]


def test_inputs_that_match_nothing_are_error_rows(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    good = write_episode_bag(tmp_path / "good", LINE)
    missing, pattern = tmp_path / "absent", str(tmp_path / "*.nothing.db3")
    result = compute([good, missing, pattern])
    errors = {r.bag: r.error for r in result.results}
    assert errors[str(good)] == ""
    assert errors[str(missing)] == f"{str(missing)!r}: no such file or directory"
    assert errors[pattern] == f"{pattern!r}: no file matches this pattern"

    assert main(["compute", str(missing), "--format", "csv"]) == 1
    out, err = capsys.readouterr()
    (row,) = csv.DictReader(io.StringIO(out))
    assert "no such file or directory" in row["error"]
    assert "1 of 1 bag(s) failed" in err


def test_a_read_only_bag_is_judged_and_left_as_it_was(tmp_path: Path) -> None:
    """Judging needs no write access and writes nothing into the bag (run as root, the mode
    stops no write: the before/after snapshot is what proves it)."""
    bag = write_episode_bag(tmp_path / "ro", LINE, obstacles=WALL)
    for p in [*bag.iterdir(), bag]:
        os.chmod(p, 0o555 if p.is_dir() else 0o444)
    try:
        before = _snapshot(bag)
        row = compute([bag]).results[0]
        assert row.error == "" and row.metrics is not None
        assert row.metrics.path_length_m == pytest.approx(2.0, abs=1e-9)
        assert _snapshot(bag) == before
    finally:
        os.chmod(bag, 0o755)


# --------------------------------------------------------------------------- odd input (issue 11)


def _laser(ns: int, ranges: Sequence[float], *, stamp_ns: int | None = None,
           range_min: float = 0.05, range_max: float = 10.0) -> Any:
    """A LaserScan of ``ranges`` received at ``ns``, its header stamped ``stamp_ns``."""
    n = max(len(ranges), 1)
    return T["sensor_msgs/msg/LaserScan"](
        _header(ns if stamp_ns is None else stamp_ns, "base_scan"), -math.pi,
        math.pi - 2 * math.pi / n, 2 * math.pi / n, 0.0, 0.0, range_min, range_max,
        np.asarray(ranges, dtype=np.float32), np.zeros(0, np.float32),
    )  # fmt: skip


def _odom_and_scans(scan_of: Any, n: int = 11) -> list[tuple[str, Any]]:
    """Odometry along +x, 0.1 m every 100 ms, and one scan per pose from ``scan_of(i, ns)``."""
    out: list[tuple[str, Any]] = []
    for i in range(n):
        ns = DEFAULT_T0_NS + i * 100_000_000
        out.append(("/odom", _odometry(ns, 0.1 * i, 0.0, 0.0, vx=1.0)))
        out.append(("/scan", scan_of(i, ns)))
    return out


FOOTPRINT_FACT = ("/episode/facts", T["std_msgs/msg/String"]('{"footprint": {"radius_m": 0.2}}'))


def test_scans_without_ranges_leave_the_pose_metrics_and_warn(tmp_path: Path) -> None:
    """Every LaserScan with ranges=[]: no NumPy reduction error; scan metrics NaN, warned."""
    bag = _write(tmp_path / "empty", [FOOTPRINT_FACT, *_odom_and_scans(lambda i, ns: _laser(ns, []))])
    row = _row(compute([bag]), "empty")
    assert row.error == "", row.error
    assert row.metrics.path_length_m == pytest.approx(1.0, abs=1e-9)
    assert math.isnan(row.metrics.obstacle_dist_min_m) and math.isnan(row.metrics.collision_count)
    assert any("no ranges" in w for w in row.warnings), row.warnings


@pytest.mark.parametrize(
    ("name", "scan_of", "why"),
    [
        ("all_nan", lambda i, ns: _laser(ns, [math.nan] * 8), "has a valid beam"),
        ("min_over_max", lambda i, ns: _laser(ns, [0.1] * 8, range_min=10.0, range_max=0.05),
         "range_min > range_max"),
    ],
)
def test_scans_that_say_nothing_give_nan_collisions_with_a_warning(
    tmp_path: Path, name: str, scan_of: Any, why: str
) -> None:
    """docs/metrics.md: NaN when a value cannot be computed, never a silent zero."""
    bag = _write(tmp_path / name, [FOOTPRINT_FACT, *_odom_and_scans(scan_of)])
    row = _row(compute([bag]), name)
    assert row.error == ""
    assert math.isnan(row.metrics.collision_count)
    assert math.isnan(row.metrics.safety_violation_time_s)
    assert any(why in w for w in row.warnings), row.warnings


def test_a_scan_topic_with_zero_stamps_warns_like_the_pose_topic(tmp_path: Path) -> None:
    bag = _write(tmp_path / "zero", _odom_and_scans(lambda i, ns: _laser(ns, [1.0] * 8, stamp_ns=0)))
    episode = read_episode(bag)
    assert "scan: header stamps are zero; using bag receive times" in episode.warnings
    assert len(episode.scan) == 11


def test_an_unparseable_facts_message_costs_only_the_facts(tmp_path: Path) -> None:
    facts = ("/episode/facts", T["std_msgs/msg/String"]("{'goal': oops"))
    bag = _write(tmp_path / "facts", [facts, *_odom_messages(range(0, 1100, 100), [0.1 * i for i in range(11)])])
    row = _row(compute([bag]), "facts")
    assert row.error == "" and row.metrics.path_length_m == pytest.approx(1.0, abs=1e-9)
    assert any("facts topic holds no JSON object" in w for w in row.warnings), row.warnings


@pytest.mark.parametrize("payload", ["exploded", '{"outcome": "exploded", "stamp_ns": 5}', "{"])
def test_an_unknown_outcome_word_is_warned_and_the_outcome_inferred(
    tmp_path: Path, payload: str
) -> None:
    outcome = ("/episode/outcome", T["std_msgs/msg/String"](payload))
    odom = _odom_messages(range(0, 1100, 100), [0.1 * i for i in range(11)])
    bag = _write(tmp_path / "outcome", [*odom, outcome])
    row = _row(compute([bag], given=frozenset({"goal"}),
                       facts=parse_facts({"goal": [1.0, 0.0]}, source="test")[0]), "outcome")
    assert row.error == ""
    assert row.metrics.outcome == "goal" and row.metrics.success == 1.0  # inferred
    assert any("outcome topic" in w and "ignored" in w for w in row.warnings), row.warnings


def test_the_diverged_outcome_is_no_success_and_no_collision(tmp_path: Path) -> None:
    bag = write_episode_bag(tmp_path / "diverged", LINE, outcome="diverged", goal=(2.0, 0.0))
    row = _row(compute([bag]), "diverged")
    assert row.error == "" and row.warnings == ()
    assert row.metrics.outcome == "diverged" and row.metrics.success == 0.0
    assert row.metrics.spl == 0.0


@pytest.mark.parametrize("jobs", ["-3", "-1", "two"])
def test_a_negative_jobs_is_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], jobs: str
) -> None:
    bag = write_episode_bag(tmp_path / "ok", LINE)
    with pytest.raises(SystemExit) as exit_info:
        main(["compute", "--jobs", jobs, str(bag)])
    assert exit_info.value.code == 2
    assert "expected a number of processes >= 1, or 0 for one per core" in capsys.readouterr().err
    with pytest.raises(ConfigError, match="jobs=-3"):
        compute([bag], jobs=-3)


def test_jobs_0_means_one_per_core(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    bags = [write_episode_bag(tmp_path / f"ok{i}", LINE) for i in range(3)]
    assert main(["compute", "--jobs", "0", "--format", "csv", *map(str, bags)]) == 0
    assert len(capsys.readouterr().out.strip().splitlines()) == 1 + 3


def test_physically_impossible_motion_is_flagged(tmp_path: Path) -> None:
    """A few overwritten bytes turned a pose into 1e70 m: judged, but flagged, not silent."""
    xs = [0.1 * i for i in range(11)]
    xs[5] = 1e70
    bag = _write(tmp_path / "damaged", _odom_messages(range(0, 1100, 100), xs))
    row = _row(compute([bag]), "damaged")
    assert row.error == ""
    flagged = [w for w in row.warnings if "physically impossible" in w]
    assert any("speed from pose differences up to 1e+71 m/s" in w for w in flagged), row.warnings
    calm = _row(compute([write_episode_bag(tmp_path / "calm", LINE)]), "calm")
    assert calm.warnings == ()


# --------------------------------------------------------------------------- namespaced topics


def _robot1(scan_topics: Sequence[str]) -> list[tuple[str, Any]]:
    """/robot1/odom along +x, 0.1 m every 100 ms, and a scan with a return 1 m ahead on each
    of ``scan_topics``."""
    out: list[tuple[str, Any]] = []
    for i in range(11):
        ns = DEFAULT_T0_NS + i * 100_000_000
        out.append(("/robot1/odom", _odometry(ns, 0.1 * i, 0.0, 0.0, vx=1.0)))
        out += [(topic, _laser(ns, [1.0] * 8)) for topic in scan_topics]
    return out


def test_a_namespaced_scan_is_picked_like_the_namespaced_odometry(tmp_path: Path) -> None:
    bag = _write(tmp_path / "robot1", _robot1(["/robot1/scan"]))
    row = _row(compute([bag]), "robot1")
    assert row.error == "" and row.episode.pose_topic == "/robot1/odom"
    assert row.metrics.obstacle_dist_min_m == pytest.approx(1.0, abs=1e-6)
    assert row.metrics.n_scans == 11
    assert "scan topic '/scan' is not in the bag; using its only LaserScan topic '/robot1/scan'" \
        in row.warnings


def test_two_namespaced_scans_are_named_in_a_warning(tmp_path: Path) -> None:
    bag = _write(tmp_path / "two", _robot1(["/robot1/front/scan", "/robot1/rear/scan"]))
    row = _row(compute([bag]), "two")
    assert row.error == "" and math.isnan(row.metrics.obstacle_dist_min_m)
    assert ("scan topic '/scan' is not in the bag, which has ['/robot1/front/scan', "
            "'/robot1/rear/scan']; scan metrics are NaN (pass --scan-topic)") in row.warnings
    picked = compute([bag], topic_map=TopicMap().with_overrides(scan="/robot1/rear/scan"))
    assert _row(picked, "two").metrics.obstacle_dist_min_m == pytest.approx(1.0, abs=1e-6)
