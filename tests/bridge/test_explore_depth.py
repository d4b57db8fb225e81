"""explore from the depth camera (config/env_explore_depth.yaml, in process): the area seen is
the depth pseudo-scan's, an 87° camera's, less than the 360° LiDAR's from the same start and
growing as the robot turns; with sensors [lidar, depth] both count on one grid; the sectors
beyond the camera's field of view read as no return."""

from __future__ import annotations

from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest

import pic4rl_bridge  # noqa: F401 - registers the envs

REPO = Path(__file__).resolve().parents[2]
SEED, TURN_STEPS = 3, 30


def _areas(env_id: str, config: str, **overrides: object) -> tuple[float, float, np.ndarray]:
    """(area seen at the start, after turning in place ``TURN_STEPS`` steps (m²), the first
    observation) of one episode."""
    env = gym.make(env_id, config=str(REPO / "config" / config), overrides=overrides)
    nav = env.unwrapped
    try:
        obs, _ = env.reset(seed=SEED)
        first = nav._context.extra["seen"].grid.area_m2
        for _ in range(TURN_STEPS):
            env.step(np.array([0.0, 1.0], dtype=np.float32))
        return first, nav._context.extra["seen"].grid.area_m2, obs
    finally:
        env.close()


def test_depth_counts_its_pseudo_scan_and_fused_counts_both() -> None:
    lidar = _areas("pic4rl/ExploreLidar-v0", "env_explore.yaml")
    depth = _areas("pic4rl/ExploreDepth-v0", "env_explore_depth.yaml")
    fused = _areas("pic4rl/ExploreDepth-v0", "env_explore_depth.yaml",
                   sensors=["depth", "lidar"])
    # an 87 degree camera sees a part of what the LiDAR sees round it
    assert 0.5 < depth[0] < 0.7 * lidar[0]
    # turning 3 s at 1 rad/s (about 170 degrees) shows the camera more
    assert depth[1] > 1.5 * depth[0]
    # one grid for both: at least either's, and the camera adds cells the LiDAR's plane missed
    # or, at most, nothing
    assert fused[0] >= lidar[0] and fused[0] == pytest.approx(lidar[0], rel=0.1)
    assert fused[1] >= max(lidar[1], depth[1]) - 1e-9
    sectors = depth[2][:36]
    clip = sectors.max()
    # the camera looks ahead: the sectors behind the robot (the scan's first and last, from
    # -pi) read as no return, some ahead read nearer
    assert sectors[0] == sectors[-1] == clip and (sectors[12:24] < clip).any()
