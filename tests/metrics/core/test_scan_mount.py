"""The scan's mount decides a collision: the metrics place a scan's points by the LiDAR's mount
(an episode fact, or ``/tf_static`` in a real bag) before measuring their distance to the
footprint."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from pic4rl_metrics import compute, read_episode
from pic4rl_metrics.synthetic.synthetic import Obstacles, cast_scan, straight_line, write_episode_bag

REAL_BAGS = Path(__file__).resolve().parents[3].parent / "shared" / "real_bags"
JACKAL = {"length_m": 0.508, "width_m": 0.430}


def test_the_mount_decides_a_collision_behind_a_jackal(tmp_path: Path) -> None:
    """Jackal, LiDAR 0.12 m forward, a wall 0.03 m behind its rear face (x = -0.284): within the
    0.05 m tolerance. From the base's origin the wall's returns (0.404 m behind the LiDAR)
    would be 0.15 m away: no collision. With the mount fact, the metrics see the contact."""
    still = straight_line(0.0, 1.0)
    wall = Obstacles(segments=((-0.284, -5.0, -0.284, 5.0),))
    scans = [cast_scan(x + 0.12, y, yaw, wall) for x, y, yaw in zip(still.x, still.y, still.yaw)]
    facts = {"footprint": JACKAL, "collision_tolerance_m": 0.05}
    mounted = write_episode_bag(tmp_path / "mounted", still, scans=scans,
                                facts={**facts, "scan_mount": {"x_m": 0.12, "y_m": 0.0, "yaw_rad": 0.0}})
    centred = write_episode_bag(tmp_path / "centred", still, scans=scans, facts=facts)
    frame = compute([mounted, centred]).frame
    rows = {Path(r["bag"]).name: r for _, r in frame.iterrows()}
    assert rows["mounted"]["collision_count"] == 1 and rows["mounted"]["outcome"] == "collision"
    assert rows["centred"]["collision_count"] == 0


def test_the_mount_is_read_from_tf_static_in_a_real_bag() -> None:
    """The Neato's /tf_static: base_footprint -> base_link (identity) -> base_laser_link; the
    bag re-publishes the laser's transform, the last one (x = -0.084 m, yaw = pi) wins."""
    bag = REAL_BAGS / "neato_obstacle_avoider"
    if not bag.is_dir():
        pytest.skip(f"real-robot bags not found in {REAL_BAGS} (see its README)")
    mount = read_episode(bag).facts.scan_mount
    assert mount is not None
    assert mount.x == pytest.approx(-0.084, abs=1e-9) and mount.y == pytest.approx(0.0, abs=1e-9)
    assert abs(abs(mount.yaw) - math.pi) < 1e-9
