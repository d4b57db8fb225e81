"""A pose stream that holds two sources is refused, not judged with a warning (issue 37,
item 2): a clock step that moved the header stamps *and* the receive times (the bag itself
interleaves the two stretches), and one publisher relaying two robots' poses 50 ms apart.

Before, the first was judged ``goal`` with a 95 m path (true 5 m) and the second ``goal`` with
a path of hundreds of metres, with only a speed warning. Isolated odometry spikes stay judged.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path

import numpy as np
import pytest

from pic4rl_metrics import compute, read_episode
from pic4rl_metrics.bags.bagwriter import BagWriter
from pic4rl_metrics.cli.commands import main
from pic4rl_metrics.contract import typestore
from pic4rl_metrics.core.plausibility import (
    CORRUPT_MIN,
    alternations,
    check_one_track,
    speed_limit,
    step_speeds,
)
from pic4rl_metrics.core.series import PoseSeries
from pic4rl_metrics.errors import CorruptBagError
from pic4rl_metrics.synthetic.synthetic import DEFAULT_T0_NS, straight_line, write_episode_bag

T = typestore().types
NS = 1_000_000_000
SPEED = 0.5  # m/s along +x


def _odom(stamp_ns: int, x: float, y: float) -> object:
    sec, nsec = divmod(stamp_ns, NS)
    vec, cov = T["geometry_msgs/msg/Vector3"], np.zeros(36)
    header = T["std_msgs/msg/Header"](T["builtin_interfaces/msg/Time"](sec, nsec), "odom")
    pose = T["geometry_msgs/msg/Pose"](T["geometry_msgs/msg/Point"](x, y, 0.0),
                                       T["geometry_msgs/msg/Quaternion"](0.0, 0.0, 0.0, 1.0))
    twist = T["geometry_msgs/msg/Twist"](vec(SPEED, 0.0, 0.0), vec(0.0, 0.0, 0.0))
    return T["nav_msgs/msg/Odometry"](header, "base_link",
                                      T["geometry_msgs/msg/PoseWithCovariance"](pose, cov),
                                      T["geometry_msgs/msg/TwistWithCovariance"](twist, cov))


def _bag(path: Path, odom: Sequence[tuple[int, int, float, float]]) -> Path:
    """/odom messages ``(header stamp ns, receive time ns, x, y)`` from one publisher; the goal
    is 5 m ahead of the start."""
    facts = {"goal": [5.0, 0.0], "footprint": {"radius_m": 0.2}}
    writer = BagWriter(path)
    for stamp, recv, x, y in odom:
        writer.write_message("/odom", _odom(stamp, x, y), recv)
    writer.close(facts)
    return path


def _stepped_back(back_s: float = 3.05, at_s: float = 6.0) -> list[tuple[int, int, float, float]]:
    """10 s along +x at 0.5 m/s, 50 Hz; after ``at_s`` the machine's clock steps back
    ``back_s``: header stamps and receive times alike."""
    t = np.arange(10 * 50 + 1) / 50
    shifted = t - np.where(t > at_s + 1e-9, back_s, 0.0)
    ns = (DEFAULT_T0_NS + np.round(shifted * NS)).astype(np.int64).tolist()
    return [(s, s, SPEED * ti, 0.0) for s, ti in zip(ns, t, strict=True)]


def _relay(separation_m: float) -> list[tuple[int, int, float, float]]:
    """Two robots, 10 Hz each, side by side ``separation_m`` apart along +x at 0.5 m/s, their
    poses relayed on one topic 50 ms apart."""
    out = []
    for i in range(101):
        for robot in (0, 1):
            t_ns = DEFAULT_T0_NS + i * NS // 10 + robot * NS // 20
            out.append((t_ns, t_ns, SPEED * (t_ns - DEFAULT_T0_NS) / NS, robot * separation_m))
    return out


def test_a_clock_step_of_stamps_and_receive_times_is_refused(tmp_path: Path) -> None:
    bag = _bag(tmp_path / "stepped", _stepped_back())
    with pytest.raises(CorruptBagError, match=(
            r"/odom: consecutive poses imply a speed beyond 20 m/s in \d+ of 500 steps .*"
            r"a clock step that moved the receive times too")) as err:
        read_episode(bag)
    # the two stretches interleave from 2.95 s (the step's landing) to 6.00 s (its top)
    n = int(str(err.value).split(" in ")[1].split(" of ")[0])
    assert 290 <= n <= 310, err.value


@pytest.mark.parametrize(("separation_m", "why"), [
    (3.0, r"consecutive poses imply a speed beyond 20 m/s in 201 of 201 steps"),  # 60 m/s leaps
    (0.5, r"200 of 200 poses leap away from both neighbours"),  # 10 m/s: alternation only
])
def test_two_robots_relayed_on_one_topic_are_refused(tmp_path: Path, separation_m: float,
                                                     why: str) -> None:
    bag = _bag(tmp_path / "relay", _relay(separation_m))
    with pytest.raises(CorruptBagError, match=rf"'{bag}': /odom: {why}"):
        read_episode(bag)


@pytest.mark.bad_input
def test_the_batch_goes_on_beside_them(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    stepped = _bag(tmp_path / "stepped", _stepped_back())
    relay = _bag(tmp_path / "relay", _relay(3.0))
    good = write_episode_bag(tmp_path / "good", straight_line(SPEED, 10.0), goal=(5.0, 0.0),
                             outcome="goal")
    frame = compute([stepped, relay, good]).frame.set_index("bag")
    for bad in (stepped, relay):
        assert "refused as corrupt" in frame.loc[str(bad), "error"]
        assert math.isnan(frame.loc[str(bad), "path_length_m"])
        assert not isinstance(frame.loc[str(bad), "outcome"], str)  # not judged
    assert frame.loc[str(good), "error"] == ""
    assert frame.loc[str(good), "outcome"] == "goal"
    assert frame.loc[str(good), "path_length_m"] == pytest.approx(5.0, abs=1e-9)
    assert frame.loc[str(good), "clearance_time_s"] == pytest.approx(10.0, abs=1e-9)
    assert main(["compute", str(stepped), str(relay), str(good)]) == 1
    err = capsys.readouterr().err
    assert f"error: {str(stepped)!r}: /odom: consecutive poses imply" in err
    assert "2 of 3 bag(s) failed" in err


# --- the rule itself, on pose series with analytic answers ---------------------------------


def _pose(x: Sequence[float], y: Sequence[float] | None = None, dt_s: float = 0.1) -> PoseSeries:
    n = len(x)
    t = DEFAULT_T0_NS + np.round(np.arange(n) * dt_s * NS).astype(np.int64)
    return PoseSeries(t, np.asarray(x, float), np.zeros(n) if y is None else np.asarray(y, float),
                      np.zeros(n))


def test_the_speed_limit_is_twice_the_max_speed_capped_at_20() -> None:
    assert speed_limit(None) == 20.0
    assert speed_limit(0.3) == pytest.approx(0.6)
    assert speed_limit(15.0) == 20.0


def test_step_speeds_use_at_least_the_median_step_time() -> None:
    # 0.05 m every 0.1 s, then one message 1 ms after the last, 0.05 m on (a bunched pair)
    pose = PoseSeries(np.array([0, 100, 200, 201]) * 1_000_000, np.array([0.0, 0.05, 0.1, 0.15]),
                      np.zeros(4), np.zeros(4))
    assert step_speeds(pose) == pytest.approx([0.5, 0.5, 0.5])  # not 50 m/s


def test_isolated_spikes_are_judged_sustained_ones_refused() -> None:
    x = 0.05 * np.arange(101)  # 0.5 m/s at 10 Hz
    spiky = x.copy()
    spiky[[20, 50, 80]] += 5.0  # three spikes: six steps at 50 m/s, three alternations
    check_one_track(_pose(spiky), None, "/odom")  # 6 of 100 steps: not sustained
    assert int(alternations(_pose(spiky)).sum()) == 3
    stepped = x + np.where(np.arange(101) >= 40, 0.2, 0.0)  # odometry steps, as the teleop bag's
    stepped[70:] += 0.2
    check_one_track(_pose(stepped), 0.3, "/odom")  # 2 steps at 2.5 m/s beyond 0.6: judged
    bad = x.copy()
    bad[10:10 + 2 * CORRUPT_MIN:2] += 5.0  # five spikes: ten steps beyond, 10 % of 100
    with pytest.raises(CorruptBagError, match=r"beyond 20 m/s in 10 of 100 steps \(up to 50\.5"):
        check_one_track(_pose(bad), None, "/odom")
    with pytest.raises(CorruptBagError, match=r"0\.6 m/s \(2 x the max speed 0\.3 m/s\) in 100 of"
                                              r" 100 steps .*\(or the max speed is wrong\)"):
        check_one_track(_pose(0.1 * np.arange(101)), 0.3, "/odom")  # 1 m/s throughout


def test_alternation_needs_both_leaps_long_and_the_neighbours_close() -> None:
    zig = _pose([0.0, 0.2, 0.02, 0.22, 0.04], [0.0, 0.0, 0.0, 0.0, 0.0])
    assert alternations(zig).tolist() == [True, True, True]  # 0.18-0.2 m out, 0.02 m between
    jitter = _pose([0.0, 0.05, 0.0, 0.05, 0.0])  # 5 cm back and forth: under ALTERNATION_MIN_M
    assert alternations(jitter).tolist() == [False, False, False]
    turn = _pose([0.0, 0.2, 0.1], [0.0, 0.0, 0.0])  # back half-way: 0.1 m apart, ratio 1-2
    assert alternations(turn).tolist() == [False]
