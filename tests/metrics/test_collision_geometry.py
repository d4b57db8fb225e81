"""One collision judgement: the metrics place the scan's points by the LiDAR's mount and
measure their signed distance to the footprint exactly as the env does
(``pic4rl_bridge.perception.collision``), and on recorded episodes they flag the very steps the env
flagged. This test imports the bridge; ``pic4rl_metrics`` itself never does."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pic4rl_bridge.transports.frame import ScanData
from pic4rl_bridge.perception.collision import footprint_clearance, scan_points
from pic4rl_metrics import EpisodeFacts, Footprint, compute, read_episode
from pic4rl_metrics.geometry import Mount
from pic4rl_metrics.scan_summary import scan_clearance
from pic4rl_metrics.series import ScanSeries
from pic4rl_metrics.synthetic import Obstacles, cast_scan, straight_line, write_episode_bag
from pic4rl_sim.engine.geometry import Pose2D
from world_helpers import walled_square_mjcf

REAL_BAGS = Path(__file__).resolve().parents[2].parent / "shared" / "real_bags"
JACKAL = {"length_m": 0.508, "width_m": 0.430}
sizes = st.floats(0.05, 1.5)
footprints = st.one_of(
    st.builds(Footprint, radius_m=sizes),
    st.builds(Footprint, length_m=sizes, width_m=sizes),
)


@settings(max_examples=200, deadline=None)
@given(footprints, st.integers(0, 2**32 - 1))
def test_signed_distance_equals_the_envs(footprint: Footprint, seed: int) -> None:
    points = np.random.default_rng(seed).uniform(-2, 2, size=(64, 2))
    assert np.allclose(footprint.signed_distance(points), footprint_clearance(points, footprint),
                       rtol=0, atol=1e-12)


@settings(max_examples=100, deadline=None)
@given(footprints, st.integers(0, 2**32 - 1),
       st.tuples(st.floats(-0.3, 0.3), st.floats(-0.3, 0.3), st.floats(-math.pi, math.pi)))
def test_scan_margin_equals_the_envs_obstacle_distance(
    footprint: Footprint, seed: int, mount: tuple[float, float, float]
) -> None:
    """Random scans (with inf, -inf and NaN beams) from a random mount: the metrics' margin of
    each scan is the env's nearest signed distance."""
    rng = np.random.default_rng(seed)
    n = 24
    ranges = rng.uniform(0.0, 3.0, size=(3, n)).astype(np.float32)
    ranges[rng.random((3, n)) < 0.1] = np.inf
    ranges[rng.random((3, n)) < 0.05] = -np.inf
    ranges[rng.random((3, n)) < 0.05] = np.nan
    amin, inc, rmin, rmax = -math.pi, 2 * math.pi / n, 0.0, 10.0
    series = ScanSeries(np.arange(3) * 100, ranges, np.tile(amin + inc * np.arange(n), (3, 1)),
                        np.full(3, rmin), np.full(3, rmax))
    facts = EpisodeFacts(footprint=footprint, scan_mount=Mount(*mount))
    margin = scan_clearance(series, facts).margin_m
    for row, got in zip(ranges, margin, strict=True):
        points = scan_points(ScanData(row, amin, inc, rmin, rmax, Pose2D(*mount)))
        want = footprint_clearance(points, footprint).min() if len(points) else math.nan
        assert got == pytest.approx(want, abs=1e-9, nan_ok=True)


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
    assert mount.x_m == pytest.approx(-0.084, abs=1e-9) and mount.y_m == pytest.approx(0.0, abs=1e-9)
    assert abs(abs(mount.yaw_rad) - math.pi) < 1e-9


# --- recorded episodes: the env's flags are the metrics' flags ------------------------------

ARENA_MJCF = walled_square_mjcf(
    3.0, '<geom name="post" type="cylinder" pos="-1 1.5 0.5" size="0.3 0.5"/>')
#: (start x, y, yaw; constant action): into a wall head-on, at a slant, a circle that touches
#: nothing (a timeout: no false flag), and into the post.
DRIVES = (
    ([1.5, 0.0, 0.0], [1.0, 0.0]),
    ([0.0, 1.0, 1.2], [1.0, 0.3]),
    ([1.0, -1.0, -0.8], [0.6, -0.5]),
    ([-1.0, 0.3, 1.57], [1.0, 0.1]),
)


def test_recorded_episodes_flag_the_steps_the_env_flagged(tmp_path: Path) -> None:
    """The in-process env (Jackal, LiDAR mounted off the base's origin per its robot file)
    records episodes driving into walls with a constant action; the scans the metrics judge in
    collision are exactly the steps whose ``info["collision"]`` is set (the reset scan is not
    judged by the env), and every collision outcome has a collision counted."""
    from pic4rl_bridge.env import NavEnv  # heavy: MuJoCo

    world = tmp_path / "arena.xml"
    world.write_text(ARENA_MJCF)
    config = Path(__file__).resolve().parents[2] / "config" / "env_goto_lidar.yaml"
    env = NavEnv(config, sim={"world": str(world)}, overrides={
        "record.enabled": True, "record.bags_dir": str(tmp_path), "record.run": "crash",
        "collision_steps": 4, "collision_tolerance_m": 0.1, "episode_max_steps": 80,
    })
    flags: list[list[bool]] = []
    outcomes: list[str] = []
    try:
        for start, action in DRIVES:
            env.reset(seed=1, options={"start": start, "goal": [-2.5, -2.5]})
            steps: list[bool] = []
            while True:
                *_, terminated, truncated, info = env.step(np.asarray(action, np.float32))
                steps.append(bool(info["collision"]))
                if terminated or truncated:
                    break
            flags.append(steps)
            outcomes.append(info["outcome"])
    finally:
        env.close()
    assert outcomes.count("collision") >= 3, outcomes  # the drives do crash
    bags = sorted((tmp_path / "crash").glob("episode_*"))
    assert len(bags) == len(DRIVES)
    result = compute(bags)
    for bag, env_flags, outcome, (_, row) in zip(bags, flags, outcomes, result.frame.iterrows(),
                                                 strict=True):
        episode = read_episode(bag, full_scans=True)
        assert episode.facts.scan_mount is not None
        margin = scan_clearance(episode.scan, episode.facts).margin_m
        judged = list(margin < episode.facts.collision_tolerance_m)
        assert judged[1:] == env_flags, bag.name
        assert row["outcome"] == outcome
        if outcome == "collision":
            assert row["collision_count"] >= 1
        edges = sum(f and not p for p, f in zip([judged[0], *env_flags], env_flags)) + judged[0]
        assert row["collision_count"] == edges
