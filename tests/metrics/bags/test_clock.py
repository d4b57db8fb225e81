"""The one time rule of ``timebase`` (issue 27, items 5 and 9), on real rosbag2 bags.

A clock that jumps back once is repaired in arrival order (the analytic answer: a straight
track at a known speed keeps its true length); a stream from two sources (two publishers,
stamps jumping back and forth, a pose leaping across the jump) is refused as corrupt, an error
row while the batch goes on.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path

import numpy as np
import pytest
from rosbags.rosbag2 import Writer

from pic4rl_metrics import compute, read_episode
from pic4rl_metrics.bags.bagwriter import DEFAULT_QOS
from pic4rl_metrics.cli.commands import main
from pic4rl_metrics.contract import encode_custom_data, typestore
from pic4rl_metrics.errors import CorruptBagError
from pic4rl_metrics.synthetic.synthetic import DEFAULT_T0_NS, write_episode_bag

from metrics_helpers import LINE, row

TS = typestore()
T = TS.types
SPEED = 0.5  # m/s along +x
RATE = 50  # Hz
NS = 1_000_000_000


def _header(stamp_ns: int, frame: str) -> object:
    sec, nsec = divmod(stamp_ns, NS)
    return T["std_msgs/msg/Header"](T["builtin_interfaces/msg/Time"](sec, nsec), frame)


def _odom(stamp_ns: int, x: float, y: float = 0.0) -> object:
    vec, cov = T["geometry_msgs/msg/Vector3"], np.zeros(36)
    pose = T["geometry_msgs/msg/Pose"](T["geometry_msgs/msg/Point"](x, y, 0.0),
                                       T["geometry_msgs/msg/Quaternion"](0.0, 0.0, 0.0, 1.0))
    twist = T["geometry_msgs/msg/Twist"](vec(SPEED, 0.0, 0.0), vec(0.0, 0.0, 0.0))
    return T["nav_msgs/msg/Odometry"](
        _header(stamp_ns, "odom"), "base_link", T["geometry_msgs/msg/PoseWithCovariance"](pose, cov),
        T["geometry_msgs/msg/TwistWithCovariance"](twist, cov))


def _scan(stamp_ns: int, wall_m: float) -> object:
    inc = 2 * math.pi / 8
    return T["sensor_msgs/msg/LaserScan"](
        _header(stamp_ns, "base_scan"), -math.pi, math.pi - inc, inc, 0.0, 0.0, 0.05, 10.0,
        np.full(8, wall_m, dtype=np.float32), np.zeros(0, dtype=np.float32))


def _write(path: Path, odom: Sequence[tuple[int, float, float]], *, scans: bool = False,
           profiles: int = 1, connections: int = 1) -> Path:
    """A bag of odometry ``(header stamp ns, x, y)`` received in the given order, 20 ms apart
    (monotonic receive times, whatever the stamps), each with a scan when ``scans``; /odom
    recorded with ``profiles`` offered QoS profiles, its messages spread over ``connections``."""
    facts = {"goal": [SPEED * 10.0, 0.0], "footprint": {"radius_m": 0.2}}
    with Writer(path, version=9) as writer:
        odom_conns = [writer.add_connection("/odom", "nav_msgs/msg/Odometry", typestore=TS,
                                            offered_qos_profiles=[DEFAULT_QOS] * (profiles + k))
                      for k in range(connections)]
        scan_conn = writer.add_connection("/scan", "sensor_msgs/msg/LaserScan", typestore=TS)
        for i, (stamp, x, y) in enumerate(odom):
            recv = DEFAULT_T0_NS + i * NS // RATE
            msg = _odom(stamp, x, y)
            writer.write(odom_conns[i % connections], recv,
                         TS.serialize_cdr(msg, "nav_msgs/msg/Odometry"))
            if scans:
                writer.write(scan_conn, recv,
                             TS.serialize_cdr(_scan(stamp, 2.0 + x / 10), "sensor_msgs/msg/LaserScan"))
        for key, value in encode_custom_data(facts).items():
            writer.set_custom_data(key, value)
    return path


def _jumped(back_s: float, at_s: float = 6.0) -> list[tuple[int, float, float]]:
    """10 s along +x at SPEED, 50 Hz; the stamps jump back ``back_s`` after ``at_s``."""
    t = np.arange(10 * RATE + 1) / RATE
    stamps = np.round((t - np.where(t > at_s + 1e-9, back_s, 0.0)) * NS).astype(np.int64)
    return [(DEFAULT_T0_NS + int(s), SPEED * ti, 0.0) for s, ti in zip(stamps, t, strict=True)]


@pytest.mark.parametrize("back_s", [3.05, 5.0])
def test_a_clock_jump_keeps_the_true_path_and_says_where_it_jumped(tmp_path: Path,
                                                                  back_s: float) -> None:
    """3.05 s gave a 95 m path instead of 5 m; 5 s (stamps back on the same 20 ms grid) lost
    half the episode as "repeated stamps". Both keep every pose and the true length."""
    bag = _write(tmp_path / "jump", _jumped(back_s), scans=True)
    episode = read_episode(bag)
    jumps = [w for w in episode.warnings if "clock jumped back" in w]
    assert len(jumps) == 2, episode.warnings  # /odom and /scan
    assert any(w.startswith("/odom: ") and f"{back_s:.3f} s" in w for w in jumps), jumps
    assert any(w.startswith("/scan: ") and f"{back_s:.3f} s" in w for w in jumps), jumps
    assert not any("repeated" in w or "went backwards" in w for w in episode.warnings)
    m = row(bag)
    assert m["n_poses"] == 10 * RATE + 1 and m["n_scans"] == 10 * RATE + 1
    assert m["path_length_m"] == pytest.approx(SPEED * 10.0, abs=1e-9)
    assert m["clearance_time_s"] == pytest.approx(10.0, abs=1e-9)
    assert m["outcome"] == "goal"
    assert m["lin_acc_max_mps2"] == pytest.approx(0.0, abs=1e-9)  # twist constant throughout
    assert m["obstacle_dist_min_m"] == pytest.approx(2.0, abs=1e-6)
    assert m["obstacle_dist_mean_m"] == pytest.approx(2.0 + SPEED * 5.0 / 10, abs=1e-6)


def test_a_late_message_is_put_in_place_not_taken_for_a_jump(tmp_path: Path) -> None:
    odom = _jumped(0.0)
    late = odom.pop(100)  # received 0.6 s (30 messages) late
    odom.insert(130, late)
    episode = read_episode(_write(tmp_path / "late", odom))
    assert not any("clock" in w for w in episode.warnings), episode.warnings
    assert any("went backwards" in w for w in episode.warnings), episode.warnings
    assert len(episode.pose) == len(odom)


@pytest.mark.bad_input
def test_two_sources_interleaved_are_refused_and_the_batch_goes_on(
    tmp_path: Path, capsys: pytest.CaptureFixture[str],
) -> None:
    """Two sims' stamps mixed (0.1-1.1 s and 87.6-88.5 s, as the probe saw): an error row."""
    a = [(DEFAULT_T0_NS + int((0.1 + i / 20) * NS), 0.05 * i, 0.0) for i in range(20)]
    b = [(DEFAULT_T0_NS + int((87.6 + i / 20) * NS), 3.0 + 0.05 * i, 1.0) for i in range(20)]
    mixed = _write(tmp_path / "mixed", [m for pair in zip(a, b, strict=True) for m in pair])
    good = write_episode_bag(tmp_path / "good", LINE)
    with pytest.raises(CorruptBagError, match=r"/odom: header stamps jump back 19 times"):
        read_episode(mixed)
    frame = compute([mixed, good]).frame.set_index("bag")
    error = frame.loc[str(mixed), "error"]
    assert "refused as corrupt" in error and "two sources" in error, error
    assert "1700000000.10-1700000001.05 s and 1700000087.60-1700000088.55 s" in error, error
    assert math.isnan(frame.loc[str(mixed), "path_length_m"])
    assert frame.loc[str(good), "error"] == "" and frame.loc[str(good), "path_length_m"] > 0
    assert main(["compute", str(mixed), str(good)]) == 1
    err = capsys.readouterr().err
    assert f"error: {str(mixed)!r}: /odom: header stamps jump back 19 times" in err


@pytest.mark.bad_input
@pytest.mark.parametrize(("profiles", "connections", "publishers"), [(2, 1, 2), (1, 2, 2)])
def test_a_sensor_topic_with_two_publishers_is_refused(
    tmp_path: Path, profiles: int, connections: int, publishers: int,
) -> None:
    """Two robots in one domain, stamps close enough to look like one stream: the bag's own
    record of publishers (offered QoS profiles, connections) gives them away."""
    bag = _write(tmp_path / "two", _jumped(0.0), profiles=profiles, connections=connections)
    with pytest.raises(CorruptBagError, match=rf"'{bag}': /odom: {publishers} publishers recorded"):
        read_episode(bag)


@pytest.mark.bad_input
def test_a_pose_leaping_across_a_jump_is_another_robot(tmp_path: Path) -> None:
    """An orphan sim's stamps first, then the retry's from its start: one jump back, but the
    robot would cross 4 m in 20 ms. Two sources, not a clock step."""
    odom = [(s, x + (4.0 if i <= 300 else 0.0), 0.0) for i, (s, x, _) in enumerate(_jumped(3.0))]
    with pytest.raises(CorruptBagError, match=r"/odom: the pose leaps 3\.99 m in 0\.020 s"):
        read_episode(_write(tmp_path / "leap", odom))
