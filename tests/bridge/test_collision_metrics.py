"""On recorded episodes the metrics flag the very steps the env flagged: both place the scan's
points by the LiDAR's mount and measure their signed distance to the footprint with the one
geometry (``pic4rl_base.geometry``)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from world_helpers import walled_square_mjcf

from pic4rl_metrics import compute, read_episode
from pic4rl_metrics.core.scan_summary import scan_clearance

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
    from pic4rl_bridge.recording import make_env  # heavy: MuJoCo

    world = tmp_path / "arena.xml"
    world.write_text(ARENA_MJCF)
    config = Path(__file__).resolve().parents[2] / "config" / "env_goto_lidar.yaml"
    env = make_env(config, sim={"world": str(world)}, overrides={
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
