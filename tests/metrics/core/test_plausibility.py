"""Implausible speed samples (issue 37, item 10): counted (``n_speed_outliers``) and warned
with their times, and the warning says whether the max acceleration and jerk are taken at them.
Analytic answers on synthetic odometry whose twist has spikes."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from pic4rl_metrics import compute
from pic4rl_metrics.contract import parse_facts
from pic4rl_metrics.synthetic.synthetic import straight_line, write_episode_bag
from pic4rl_metrics.synthetic.synthetic_tracks import Track


def _judged(bag: Path, max_speed: float | None) -> dict[str, object]:
    facts, given = parse_facts({} if max_speed is None else {"max_speed_mps": max_speed},
                               source="test")
    row = compute([bag], facts=facts, given=given).frame.iloc[0].to_dict()
    assert row["error"] == "", row["error"]
    return row


def _with_twist(vx: dict[int, float]) -> Track:
    """0.5 m/s along +x at 10 Hz for 10 s; the twist's vx replaced at the given samples."""
    line = straight_line(0.5, 10.0)
    speed = line.vx.copy()
    for i, value in vx.items():
        speed[i] = value
    return Track(line.t_s, line.x, line.y, line.yaw, speed, line.vy, line.wz)


def test_twist_spikes_are_counted_with_their_times_and_the_maxima_at_them(tmp_path: Path) -> None:
    # vx 2.0 at 3 s and 7 s: acceleration (2.0 - 0.5) / 0.1 = 15 m/s^2, then -15; jerk at the
    # spike (-15 - 15) / 0.1 = -300 m/s^3.
    bag = write_episode_bag(tmp_path / "spikes", _with_twist({30: 2.0, 70: 2.0}))
    row = _judged(bag, 0.5)  # limit 2 x 0.5 = 1.0 m/s
    assert row["n_speed_outliers"] == 2
    assert row["lin_acc_max_mps2"] == pytest.approx(15.0, abs=1e-9)
    assert row["lin_jerk_max_mps3"] == pytest.approx(300.0, abs=1e-6)
    assert row["warnings"] == (
        "/ground_truth: 2 implausible speed sample(s) (odometry spikes?), above 1 m/s (2 x the "
        "max speed 0.5 m/s), up to 2 m/s, at t = 3.00, 7.00 s; kept as read: the acceleration "
        "and jerk columns include them (max linear acceleration 15 m/s^2 at them; max linear "
        "jerk 300 m/s^3 at them)")
    # twice the max speed: 2.0 m/s is within a 1.5 m/s robot's reach
    assert _judged(bag, 1.5)["n_speed_outliers"] == 0
    # no max speed known: 20 m/s
    none = _judged(bag, None)
    assert none["n_speed_outliers"] == 0 and none["warnings"] == ""
    assert none["lin_acc_max_mps2"] == pytest.approx(15.0, abs=1e-9)  # kept as read


def test_the_warning_says_when_a_maximum_is_not_at_them(tmp_path: Path) -> None:
    # a 1.2 m/s spike at 2 s: 7 m/s^2 and a jerk of (-7 - 7) / 0.1 = -140 m/s^3; reversing
    # from 0.5 to -0.5 m/s at 6 s: 10 m/s^2 (no outlier), a jerk of 100 m/s^3
    vx = {20: 1.2} | {i: -0.5 for i in range(60, 101)}
    row = _judged(write_episode_bag(tmp_path / "mixed", _with_twist(vx)), 0.5)
    assert row["n_speed_outliers"] == 1
    assert row["lin_acc_max_mps2"] == pytest.approx(10.0, abs=1e-9)
    assert row["lin_jerk_max_mps3"] == pytest.approx(140.0, abs=1e-6)
    assert row["warnings"].endswith(
        "at t = 2.00 s; kept as read: the acceleration and jerk columns include them (max linear "
        "acceleration 10 m/s^2 not at them; max linear jerk 140 m/s^3 at them)")


def test_a_calm_episode_has_none(tmp_path: Path) -> None:
    row = _judged(write_episode_bag(tmp_path / "calm", straight_line(0.5, 10.0)), 0.5)
    assert row["n_speed_outliers"] == 0 and row["warnings"] == ""
    assert np.isclose(row["lin_acc_max_mps2"], 0.0)
