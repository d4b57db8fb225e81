"""The one geometry every package uses (``pic4rl_base.geometry``), against analytic answers:
angle wrapping, a yaw's quaternion and back, a scan's points from an offset and turned
mount, and a footprint's signed distance."""

from __future__ import annotations

import math

import numpy as np
import pytest

from pic4rl_base.geometry import (Footprint, Pose2D, scan_points, sensor_to_base, wrap_angle,
                                  yaw_from_quaternion, yaw_to_quaternion)


def test_wrap_angle_maps_into_minus_pi_to_pi_for_floats_and_arrays() -> None:
    assert wrap_angle(1.5 * math.pi) == pytest.approx(-0.5 * math.pi, abs=1e-12)
    assert wrap_angle(-1.5 * math.pi) == pytest.approx(0.5 * math.pi, abs=1e-12)
    assert wrap_angle(math.pi) == pytest.approx(-math.pi, abs=1e-12)  # [-pi, pi)
    assert isinstance(wrap_angle(0.3), float)
    np.testing.assert_allclose(wrap_angle(np.array([0.0, 7.0, -7.0, 4 * math.pi + 0.1])),
                               [0.0, 7.0 - 2 * math.pi, 2 * math.pi - 7.0, 0.1], atol=1e-12)


def test_a_yaw_s_quaternion_and_back() -> None:
    assert yaw_to_quaternion(math.pi / 2) == pytest.approx(
        (0.0, 0.0, math.sqrt(0.5), math.sqrt(0.5)), abs=1e-15)
    for yaw in np.linspace(-3.1, 3.1, 13):
        assert yaw_from_quaternion(*yaw_to_quaternion(yaw)) == pytest.approx(yaw, abs=1e-12)


def test_scan_points_place_each_beam_from_the_mount() -> None:
    """A scanner 0.2 m ahead and 0.1 m left of the base, turned 90° left: its beam at 0 rad
    points along base +y, its beam at -90° along base +x."""
    mount = Pose2D(0.2, 0.1, math.pi / 2)
    x, y = scan_points(np.array([1.0, 2.0, np.nan]), np.array([0.0, -math.pi / 2, 0.0]), mount)
    np.testing.assert_allclose(x[:2], [0.2, 2.2], atol=1e-12)
    np.testing.assert_allclose(y[:2], [1.1, 0.1], atol=1e-12)
    assert math.isnan(x[2]) and math.isnan(y[2])
    # a (n_scans, n_beams) block against one row of angles; any (x, y, yaw) triple is a mount
    bx, by = scan_points(np.full((2, 2), 1.0), np.array([0.0, math.pi]), (0.0, 0.0, 0.0))
    np.testing.assert_allclose(bx, [[1.0, -1.0]] * 2, atol=1e-12)
    np.testing.assert_allclose(by, [[0.0, 0.0]] * 2, atol=1e-12)
    assert sensor_to_base(1.0, 0.0, (0.5, 0.0, math.pi)) == pytest.approx((-0.5, 0.0), abs=1e-12)


def test_a_footprint_s_signed_distance_is_the_exact_circle_and_box_distance() -> None:
    box, disc = Footprint(length_m=0.5, width_m=0.4), Footprint(radius_m=0.3)
    points = np.array([[0.0, 0.0], [0.0, 1.0], [1.0, 0.1], [0.6, 0.6], [0.25, 0.0], [0.3, 0.2]])
    np.testing.assert_allclose(box.signed_distance(points),
                               [-0.2, 0.8, 0.75, math.hypot(0.35, 0.4), 0.0, 0.05], atol=1e-12)
    np.testing.assert_allclose(disc.signed_distance(points[:2]), [-0.3, 0.7], atol=1e-12)
    # a planner's float32 points stay float32
    assert box.signed_distance(points.astype(np.float32)).dtype == np.float32
