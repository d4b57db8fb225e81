"""Poses from ``/tf`` and ``/tf_static`` (``--pose-frames``), against analytic motion.

The robot drives a circle (radius 2 m, 0.5 m/s, 10 s) published as ``odom -> base_link`` at
20 Hz; ``map -> odom`` is either a static offset (rotation by pi/6, then (3, -1) m) or a
drifting transform at 5 Hz whose translation and yaw grow linearly in time, so that linear
interpolation and slerp are exact and every pose in ``map`` is known in closed form.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
from metrics_helpers import DIFF, EXACT, transform, write_tf_bag

from pic4rl_metrics import TopicError, compute_metrics, read_episode
from pic4rl_metrics.cli.commands import main
from pic4rl_metrics.synthetic.synthetic import DEFAULT_T0_NS, circle, straight_line, write_episode_bag
from pic4rl_metrics.bags.topics import TopicMap

CIRCLE = circle(2.0, 0.5, 10.0, dt_s=0.05)  # 201 poses, 5 m of arc (1.25 rad)
STEP_NS = 50_000_000
OFFSET = (3.0, -1.0, math.pi / 6)  # map -> odom: static


def _odom_records(every: int = 1) -> list[tuple[int, str, list[object]]]:
    """odom -> base_link of CIRCLE, stamped t0 + i * 50 ms, received 2 ms later."""
    return [
        (DEFAULT_T0_NS + i * STEP_NS + 2_000_000, "/tf",
         [transform(DEFAULT_T0_NS + i * STEP_NS, "odom", "base_link",
                    CIRCLE.x[i], CIRCLE.y[i], CIRCLE.yaw[i])])
        for i in range(0, len(CIRCLE), every)
    ]  # fmt: skip


def _statics() -> list[tuple[int, str, list[object]]]:
    x, y, yaw = OFFSET
    return [(DEFAULT_T0_NS, "/tf_static", [
        transform(0, "map", "odom", x, y, yaw),
        transform(0, "base_link", "laser", 0.1, 0.0, 0.0, z=0.3),
    ])]  # fmt: skip


@pytest.fixture(scope="module")
def tf_bag(tmp_path_factory: pytest.TempPathFactory) -> Path:
    root = tmp_path_factory.mktemp("tf")
    return write_tf_bag(root / "tf_only", _statics() + _odom_records())


def _frames(parent: str, child: str) -> TopicMap:
    return TopicMap(pose_frames=(parent, child))


def _rotated(x: np.ndarray, y: np.ndarray, yaw: np.ndarray | float) -> tuple[np.ndarray, ...]:
    c, s = np.cos(yaw), np.sin(yaw)
    return c * x - s * y, s * x + c * y


def test_odom_to_base_link_is_the_driven_circle(tf_bag: Path) -> None:
    episode = read_episode(tf_bag, _frames("odom", "base_link"))
    assert episode.pose_topic == "/tf:odom->base_link"
    assert episode.warnings == ()
    np.testing.assert_allclose(episode.pose.x, CIRCLE.x, atol=EXACT)
    np.testing.assert_allclose(episode.pose.y, CIRCLE.y, atol=EXACT)
    np.testing.assert_allclose(episode.pose.yaw, CIRCLE.yaw, atol=EXACT)
    assert int(episode.pose.t_ns[0]) == DEFAULT_T0_NS  # header stamps, not receive times
    m = compute_metrics(episode)
    chords = float(np.sum(np.hypot(np.diff(CIRCLE.x), np.diff(CIRCLE.y))))
    assert m.path_length_m == pytest.approx(chords, abs=DIFF)
    assert m.path_length_m == pytest.approx(5.0, rel=1e-5)  # the arc: 0.5 m/s for 10 s
    assert m.clearance_time_s == pytest.approx(10.0, abs=EXACT)
    # No twist in a transform: speeds from pose differences, chord / dt of the 2 m circle.
    assert m.lin_vel_mean_mps == pytest.approx(0.5, rel=1e-5)
    assert m.ang_vel_mean_radps == pytest.approx(0.25, rel=1e-5)


def test_map_to_base_link_composes_the_static_offset(tf_bag: Path) -> None:
    episode = read_episode(tf_bag, _frames("map", "base_link"))
    dx, dy, dyaw = OFFSET
    x, y = _rotated(CIRCLE.x, CIRCLE.y, dyaw)
    np.testing.assert_allclose(episode.pose.x, x + dx, atol=EXACT)
    np.testing.assert_allclose(episode.pose.y, y + dy, atol=EXACT)
    yaw = np.angle(np.exp(1j * (CIRCLE.yaw + dyaw)))
    np.testing.assert_allclose(np.angle(np.exp(1j * (episode.pose.yaw - yaw))), 0.0, atol=EXACT)
    m = compute_metrics(episode)
    odom = compute_metrics(read_episode(tf_bag, _frames("odom", "base_link")))
    assert m.path_length_m == pytest.approx(odom.path_length_m, abs=DIFF)  # a rigid move
    assert m.net_displacement_m == pytest.approx(odom.net_displacement_m, abs=DIFF)


def test_a_sensor_frame_goes_through_the_static_mount(tf_bag: Path) -> None:
    """laser is 0.1 m ahead of base_link: its pose in odom is the base's plus R(yaw)(0.1, 0)."""
    episode = read_episode(tf_bag, _frames("odom", "laser"))
    np.testing.assert_allclose(episode.pose.x, CIRCLE.x + 0.1 * np.cos(CIRCLE.yaw), atol=EXACT)
    np.testing.assert_allclose(episode.pose.y, CIRCLE.y + 0.1 * np.sin(CIRCLE.yaw), atol=EXACT)


def test_a_moving_map_to_odom_is_interpolated_and_not_extrapolated(tmp_path: Path) -> None:
    """map -> odom at 5 Hz from 1 s to 9 s: translation (0.1 t, 0.05 t), yaw 0.02 t. Poses
    outside [1, 9] s are dropped (tf2 does not extrapolate), the others are exact."""
    drift = [
        (DEFAULT_T0_NS + k * 200_000_000 + 1_000_000, "/tf",
         [transform(DEFAULT_T0_NS + k * 200_000_000, "map", "odom", 0.1 * k * 0.2,
                    0.05 * k * 0.2, 0.02 * k * 0.2)])
        for k in range(5, 46)
    ]  # fmt: skip
    records = sorted(drift + _odom_records(), key=lambda r: r[0])
    bag = write_tf_bag(tmp_path / "drift", records)
    episode = read_episode(bag, _frames("map", "base_link"))
    assert episode.warnings == (
        "40 pose(s) of map->base_link outside the time span of the transform map->odom "
        "dropped (tf2 does not extrapolate)",
    )
    t = (episode.pose.t_ns - DEFAULT_T0_NS) / 1e9
    assert len(t) == 161 and t[0] == pytest.approx(1.0) and t[-1] == pytest.approx(9.0)
    i = np.round(t / 0.05).astype(int)
    x, y = _rotated(CIRCLE.x[i], CIRCLE.y[i], 0.02 * t)
    np.testing.assert_allclose(episode.pose.x, x + 0.1 * t, atol=1e-9)
    np.testing.assert_allclose(episode.pose.y, y + 0.05 * t, atol=1e-9)


def test_the_cli_reads_tf_poses_and_the_topic_map_key(
    tf_bag: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["compute", "--format", "json", "--pose-frames", "map:base_link", str(tf_bag)]) == 0
    (row,) = json.loads(capsys.readouterr().out)
    assert row["pose_topic"] == "/tf:map->base_link"
    assert row["path_length_m"] == pytest.approx(5.0, rel=1e-5)
    topic_map = tmp_path / "tf.yaml"
    topic_map.write_text("pose_frames: odom:base_link\n")
    assert main(["compute", "--format", "json", "--topic-map", str(topic_map), str(tf_bag)]) == 0
    (row,) = json.loads(capsys.readouterr().out)
    assert row["pose_topic"] == "/tf:odom->base_link" and row["error"] == ""


def test_a_namespaced_tf_topic_reads_its_own_static_sibling(tmp_path: Path) -> None:
    records = [(r, f"/robot1{topic}", tfs) for r, topic, tfs in _statics() + _odom_records()]
    bag = write_tf_bag(tmp_path / "ns", records)
    topic_map = TopicMap().with_overrides(pose="/robot1/tf", pose_frames=("map", "base_link"))
    episode = read_episode(bag, topic_map)
    assert episode.pose_topic == "/robot1/tf:map->base_link"
    x, y = _rotated(CIRCLE.x, CIRCLE.y, OFFSET[2])
    np.testing.assert_allclose(episode.pose.x, x + OFFSET[0], atol=EXACT)
    np.testing.assert_allclose(episode.pose.y, y + OFFSET[1], atol=EXACT)


# --------------------------------------------------------------------------- bad input


def _cli(capsys: pytest.CaptureFixture[str], *argv: object) -> tuple[int, str]:
    code = main(["compute", "--format", "csv", *map(str, argv)])
    return code, capsys.readouterr().err


@pytest.mark.bad_input
def test_a_tf_only_bag_without_pose_frames_names_the_option(
    tf_bag: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    with pytest.raises(TopicError, match=r"it has /tf: pass --pose-frames PARENT:CHILD"):
        read_episode(tf_bag)
    code, err = _cli(capsys, tf_bag)
    assert code == 1
    (line,) = [x for x in err.splitlines() if x.startswith("error:")]
    assert "tf_only" in line and "none of the pose topics" in line and "--pose-frames" in line


@pytest.mark.bad_input
def test_pose_topic_tf_without_pose_frames_points_at_the_option(
    tf_bag: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    code, err = _cli(capsys, "--pose-topic", "/tf", tf_bag)
    assert code == 1
    assert (f"error: '{tf_bag}': pose topic '/tf' has type 'tf2_msgs/msg/TFMessage'; pass "
            "--pose-frames PARENT:CHILD (e.g. odom:base_link) to read poses from it") in err


@pytest.mark.bad_input
@pytest.mark.parametrize("frames", ["odom", "odom:", "a:b:c"])
def test_malformed_pose_frames_exit_2(
    tf_bag: Path, capsys: pytest.CaptureFixture[str], frames: str
) -> None:
    with pytest.raises(SystemExit) as exit_info:
        main(["compute", "--pose-frames", frames, str(tf_bag)])
    assert exit_info.value.code == 2
    err = capsys.readouterr().err
    assert f"argument --pose-frames: {frames!r}: expected PARENT:CHILD frames" in err


@pytest.mark.bad_input
def test_malformed_pose_frames_in_a_topic_map_exit_2(
    tf_bag: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    topic_map = tmp_path / "bad.yaml"
    topic_map.write_text("pose_frames: base_link\n")
    code, err = _cli(capsys, "--topic-map", topic_map, tf_bag)
    assert code == 2
    assert err.strip() == (f"pic4rl-metrics: topic map {str(topic_map)!r}: pose_frames "
                           "'base_link': expected PARENT:CHILD frames, e.g. odom:base_link")


@pytest.mark.bad_input
def test_frames_that_no_chain_joins_list_the_transforms(
    tf_bag: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    code, err = _cli(capsys, "--pose-frames", "world:base_link", tf_bag)
    assert code == 1
    assert (f"error: '{tf_bag}': /tf and its _static: no chain of transforms joins 'world' and "
            "'base_link'; transforms: base_link->laser, map->odom, odom->base_link") in err


@pytest.mark.bad_input
def test_a_chain_of_static_transforms_has_no_motion(
    tf_bag: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    code, err = _cli(capsys, "--pose-frames", "base_link:laser", tf_bag)
    assert code == 1
    assert "the transforms from 'base_link' to 'laser' (base_link->laser) do not move" in err


@pytest.mark.bad_input
def test_pose_frames_on_a_bag_without_tf_names_what_it_has(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    bag = write_episode_bag(tmp_path / "odom_only", straight_line(0.5, 2.0), cmd=False)
    code, err = _cli(capsys, "--pose-frames", "odom:base_link", bag)
    assert code == 1
    assert (f"error: '{bag}': none of the pose topics ['/tf'] is in the bag; it has "
            "['/ground_truth', '/odom']") in err
