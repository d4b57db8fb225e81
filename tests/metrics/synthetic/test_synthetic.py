"""Synthetic bags: the geometry is exact and the bags read back as written."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
from rosbags.highlevel import AnyReader

from pic4rl_metrics import contract
from pic4rl_metrics.contract import parse_facts
from pic4rl_metrics.synthetic.synthetic import (
    DEFAULT_T0_NS,
    Obstacles,
    cast_scan,
    circle,
    from_waypoints,
    speed_ramp,
    straight_line,
    write_episode_bag,
)


def _counts(reader: AnyReader) -> dict[str, int]:
    return {c.topic: c.msgcount for c in reader.connections}


def test_cast_scan_wall_and_cylinder_are_analytic() -> None:
    # Robot at the origin facing +y: wall x = 2 in front-right, cylinder of radius 0.5 at (0, -3).
    world = Obstacles(circles=((0.0, -3.0, 0.5),), segments=((2.0, -10.0, 2.0, 10.0),))
    ranges = cast_scan(0.0, 0.0, math.pi / 2, world, n_beams=8, range_max=5.0)
    bearings = math.pi / 2 + np.linspace(-math.pi, math.pi - 2 * math.pi / 8, 8)
    assert ranges.dtype == np.float32
    # Beams pointing at +x (bearing 0) and ±45° hit the wall at 2 / cos(bearing).
    for i, bearing in enumerate(bearings):
        c = math.cos(bearing)
        if c > 1e-9 and 2 / c <= 5.0:
            assert ranges[i] == pytest.approx(2 / c, abs=1e-5)
    beam_down = int(np.argmin(np.abs(np.sin(bearings) + 1) + np.abs(np.cos(bearings))))
    assert ranges[beam_down] == pytest.approx(2.5, abs=1e-6)  # 3 - r
    beam_up = int(np.argmin(np.abs(np.sin(bearings) - 1) + np.abs(np.cos(bearings))))
    assert ranges[beam_up] == np.inf  # nothing within range_max
    beam_left = int(np.argmin(np.abs(np.cos(bearings) + 1)))
    assert ranges[beam_left] == np.inf


def test_cast_scan_marks_out_of_range_returns() -> None:
    near = Obstacles(segments=((0.01, -1.0, 0.01, 1.0),))
    far = Obstacles(segments=((12.0, -1.0, 12.0, 1.0),))
    assert cast_scan(0, 0, 0, near, n_beams=4)[2] == -np.inf  # closer than range_min
    assert cast_scan(0, 0, 0, far, n_beams=4)[2] == np.inf  # beyond range_max
    assert cast_scan(0, 0, 0, far, n_beams=4, range_max=20.0)[2] == pytest.approx(12.0)


def test_cast_scan_from_inside_a_cylinder_hits_its_wall() -> None:
    ranges = cast_scan(0.1, 0.0, 0.0, Obstacles(circles=((0.0, 0.0, 1.0),)), n_beams=4)
    assert ranges[2] == pytest.approx(0.9) and ranges[0] == pytest.approx(1.1)


def test_circle_points_lie_on_the_circle() -> None:
    track = circle(2.5, 0.5, 40.0, center=(1.0, -2.0))
    assert np.allclose(np.hypot(track.x - 1.0, track.y + 2.0), 2.5, atol=1e-12)
    assert np.allclose(track.wz, 0.2)
    # Counter-clockwise: the heading leads the radius by +90°.
    radial = np.arctan2(track.y + 2.0, track.x - 1.0)
    assert np.allclose(np.cos(track.yaw - radial - math.pi / 2), 1.0)


def test_straight_line_and_ramp_are_exact() -> None:
    line = straight_line(0.5, 10.0, start=(1.0, 2.0, math.pi / 2))
    assert len(line) == 101
    assert line.y[-1] == pytest.approx(7.0) and line.x[-1] == pytest.approx(1.0)
    ramp = speed_ramp(0.3, 4.0, dt_s=0.5)
    assert ramp.x[-1] == pytest.approx(0.3 * 4.0**3 / 6)
    assert ramp.vx[-1] == pytest.approx(0.5 * 0.3 * 16)


def test_from_waypoints_turns_in_place_and_ends_on_the_last_point() -> None:
    track = from_waypoints([(0, 0), (1, 0), (1, 1.03)], 0.5, yaw_rate_radps=1.0)
    assert (track.x[-1], track.y[-1]) == pytest.approx((1.0, 1.03))
    assert track.t_s[-1] == pytest.approx(2 + math.pi / 2 + 2.06)
    turning = track.wz != 0
    assert np.all(track.vx[turning] == 0) and np.all(track.wz[turning] == 1.0)
    assert track.yaw[-1] == pytest.approx(math.pi / 2)


def test_bag_reads_back_with_counts_facts_and_stamps(tmp_path: Path) -> None:
    track = straight_line(0.4, 2.0)  # 21 poses
    facts = {"agent": "a", "seed": 7, "footprint": {"radius_m": 0.2}, "start": [0.0, 0.0, 0.0]}
    bag = write_episode_bag(
        tmp_path / "ep",
        track,
        obstacles=Obstacles(segments=((3.0, -1.0, 3.0, 1.0),)),
        scan_every=5,
        goal=(0.8, 0.0),
        person=straight_line(1.0, 1.0, dt_s=0.5),
        facts=facts,
        outcome="goal",
        receive_offset_ns=1234,
    )
    with AnyReader([bag]) as reader:
        assert _counts(reader) == {
            contract.FACTS_TOPIC: 1,
            contract.GOAL_TOPIC: 1,
            contract.GROUND_TRUTH_TOPIC: 21,
            contract.ODOM_TOPIC: 21,
            contract.SCAN_TOPIC: 5,
            contract.CMD_VEL_TOPIC: 21,
            contract.PERSON_TOPIC: 3,
            contract.OUTCOME_TOPIC: 1,
        }
        custom = reader.readers[0].storage.metadata.custom
        parsed, _ = parse_facts(custom, source="test")
        assert parsed.seed == 7 and parsed.footprint.radius_m == 0.2
        assert parsed.outcome is not None and parsed.outcome.value == "goal"
        stamps, log_times, outcome = [], [], None
        for conn, log_ns, raw in reader.messages():
            msg = reader.deserialize(raw, conn.msgtype)
            log_times.append(log_ns)
            if conn.topic == contract.GROUND_TRUTH_TOPIC:
                stamps.append(msg.header.stamp.sec * 10**9 + msg.header.stamp.nanosec)
                assert log_ns == stamps[-1] + 1234
            elif conn.topic == contract.OUTCOME_TOPIC:
                outcome = json.loads(msg.data)
            elif conn.topic == contract.FACTS_TOPIC:
                assert json.loads(msg.data) == facts
            elif conn.topic == contract.SCAN_TOPIC:
                assert np.nanmin(msg.ranges) == pytest.approx(3.0 - 0.04 * (len(stamps) - 1))
    assert stamps == [DEFAULT_T0_NS + i * 100_000_000 for i in range(21)]
    assert log_times == sorted(log_times)
    assert outcome == {"outcome": "goal", "stamp_ns": stamps[-1]}


def test_pose_types_and_stamped_commands(tmp_path: Path) -> None:
    bag = write_episode_bag(
        tmp_path / "ep", circle(1.0, 0.5, 1.0), pose_type="pose_cov", cmd_stamped=True,
        also_odom=False, storage="mcap",
    )  # fmt: skip
    with AnyReader([bag]) as reader:
        types = {c.topic: c.msgtype for c in reader.connections}
        assert types == {
            contract.GROUND_TRUTH_TOPIC: "geometry_msgs/msg/PoseWithCovarianceStamped",
            contract.CMD_VEL_TOPIC: "geometry_msgs/msg/TwistStamped",
        }


def test_without_metadata_only_the_db3_remains_and_reads(tmp_path: Path) -> None:
    bag = write_episode_bag(tmp_path / "x", straight_line(0.5, 1.0), write_metadata=False)
    assert sorted(p.name for p in bag.iterdir()) == ["x.db3"]
    with AnyReader([bag / "x.db3"]) as reader:
        assert _counts(reader)[contract.GROUND_TRUTH_TOPIC] == 11


def test_existing_path_is_never_overwritten(tmp_path: Path) -> None:
    (tmp_path / "ep").mkdir()
    with pytest.raises(FileExistsError, match="exists already"):
        write_episode_bag(tmp_path / "ep", straight_line(0.5, 1.0))


def test_bad_arguments_name_the_value(tmp_path: Path) -> None:
    with pytest.raises(ValueError, match="pose_type='twist'"):
        write_episode_bag(tmp_path / "ep", straight_line(0.5, 1.0), pose_type="twist")
    assert not (tmp_path / "ep").exists()
