"""The moving-obstacle tracker (``pic4rl_bridge.perception.movers``) on scans ray-cast
analytically: a circle's centre recovered from its visible arc, consecutive returns split at
gaps, a mover crossing beside a static pillar tracked to its true position and velocity (the
pillar's returns left to the static field), a mover that leaves the scan coasting for
``keep_s`` and then dropped."""

from __future__ import annotations

import math

import numpy as np
import pytest

from pic4rl_base.geometry import Pose2D
from pic4rl_bridge.perception.movers import MoverTracker, fit_circle, scan_clusters
from pic4rl_bridge.readings.frame import ScanData, SensorFrame
from pic4rl_sim.engine.geometry import Twist2D
from pic4rl_sim.engine.worlds.spec import Cylinder, WorldSpec

PILLAR = Cylinder(2.0, -1.0, 0.3, 1.0)
WORLD = WorldSpec("field", (-5.0, -5.0, 5.0, 5.0), cylinders=(PILLAR,))
RADIUS = 0.15
START, VELOCITY = np.array([1.5, 1.5]), np.array([0.8, -0.4])
BEAMS = 720


def _ranges(circles: list[tuple[float, float, float]]) -> np.ndarray:
    """Ranges (m) from the origin of ``BEAMS`` beams over a full turn to the nearest circle
    (x, y, r), ``inf`` where none is hit: the ray-circle intersection, exact."""
    angles = -math.pi + 2 * math.pi * np.arange(BEAMS) / BEAMS
    ux, uy = np.cos(angles), np.sin(angles)
    best = np.full(BEAMS, np.inf)
    for x, y, r in circles:
        along = ux * x + uy * y
        disc = along**2 - (x * x + y * y - r * r)
        hit = (disc >= 0) & (along > 0)
        best = np.where(hit, np.minimum(best, along - np.sqrt(np.where(hit, disc, 0))), best)
    return best


def _frame(step: int, mover: np.ndarray | None) -> SensorFrame:
    circles = [(PILLAR.x, PILLAR.y, PILLAR.radius_m)]
    if mover is not None:
        circles.append((mover[0], mover[1], RADIUS))
    scan = ScanData(_ranges(circles).astype(np.float32), -math.pi, 2 * math.pi / BEAMS,
                    0.05, 10.0)
    return SensorFrame(step * 100_000_000, Pose2D(0.0, 0.0, 0.0), Twist2D(), scan=scan)


def test_a_circle_s_centre_is_recovered_from_its_visible_arc() -> None:
    centre, sensor = np.array([2.0, 1.0]), np.zeros(2)
    facing = math.atan2(*(sensor - centre)[::-1])
    arc = facing + np.linspace(-1.0, 1.0, 15)
    points = centre + RADIUS * np.column_stack((np.cos(arc), np.sin(arc)))
    np.testing.assert_allclose(fit_circle(points, sensor, RADIUS), centre, atol=1e-9)
    noisy = points + np.random.default_rng(0).normal(0.0, 0.005, points.shape)
    assert np.hypot(*(fit_circle(noisy, sensor, RADIUS) - centre)) < 0.02


def test_consecutive_returns_are_split_where_they_lie_apart() -> None:
    points = np.array([[0.0, 0.0], [0.1, 0.0], [0.5, 0.0], [0.55, 0.0], [2.0, 0.0]])
    assert [c.tolist() for c in scan_clusters(points, 0.15)] == [[0, 1], [2, 3], [4]]
    assert scan_clusters(np.empty((0, 2)), 0.15) == []


def test_a_mover_beside_a_pillar_is_tracked_to_its_position_and_velocity() -> None:
    tracker = MoverTracker(WORLD, RADIUS)
    for step in range(15):
        mover = START + VELOCITY * 0.1 * step
        theirs = tracker.update(_frame(step, mover))
    frame = _frame(14, mover)
    points = frame.scan.points()
    on_pillar = np.abs(np.hypot(points[:, 0] - PILLAR.x, points[:, 1] - PILLAR.y)
                       - PILLAR.radius_m) < 1e-3
    assert on_pillar.any() and not theirs[on_pillar].any()  # the pillar is the static field's
    assert theirs[~on_pillar].all()
    assert len(tracker.pos) == 1
    np.testing.assert_allclose(tracker.pos[0], mover, atol=0.01)
    np.testing.assert_allclose(tracker.vel[0], VELOCITY, atol=0.05)
    np.testing.assert_allclose(tracker.predict(np.array([1.0]))[0, 0], mover + VELOCITY,
                               atol=0.06)


@pytest.mark.parametrize("unseen_steps, kept", [(10, 1), (11, 0)])
def test_a_mover_that_leaves_the_scan_coasts_for_keep_s_then_is_dropped(
        unseen_steps: int, kept: int) -> None:
    tracker = MoverTracker(WORLD, RADIUS, keep_s=1.0)
    for step in range(10):
        tracker.update(_frame(step, START + VELOCITY * 0.1 * step))
    for step in range(10, 10 + unseen_steps):
        tracker.update(_frame(step, None))
    assert len(tracker.pos) == kept
    if kept:  # coasting at its velocity to where the mover would be
        np.testing.assert_allclose(tracker.pos[0], START + VELOCITY * 0.1 * 19, atol=0.05)
