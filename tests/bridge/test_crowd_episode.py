"""A recorded goToPose episode among a crowd (config/env_goto_lidar.yaml's indoor world with
``crowd.count`` 10, in process): the ``orca`` baseline drives on the env's ``people`` reading,
and pic4rl_metrics judges its bag alone, the social metrics from the recorded ``people``
topic present and consistent with what the robot saw each step, body to body (the bag records
the crowd's person radius) (issue 41 item 4)."""

from __future__ import annotations

import math
from pathlib import Path

from pic4rl_bridge.baselines.registry import make_baseline
from pic4rl_bridge.recording import make_env
from pic4rl_metrics import compute
from pic4rl_metrics.core.tasks.crowd import PERSON_RADIUS_M

CONFIG = Path(__file__).resolve().parents[2] / "config" / "env_goto_lidar.yaml"
SEED, STEPS, PEOPLE = 3, 150, 10


def test_orca_drives_among_a_crowd_and_its_bag_has_the_social_metrics(tmp_path: Path) -> None:
    env = make_env(CONFIG, sim={"crowd.count": PEOPLE},
                   overrides={"episode_max_steps": STEPS, "record.enabled": True,
                              "record.bags_dir": str(tmp_path), "record.run": "orca"})
    nav = env.unwrapped
    nearest, person_m = math.inf, nav.scenario.sim.engine.crowd.radius_m
    footprint = nav.scenario.robot.footprint
    try:
        baseline = make_baseline("orca", nav.config, nav.scenario.robot, nav.scenario.world)
        env.reset(seed=SEED)
        baseline.reset()
        for _ in range(STEPS):
            frame = nav.frame
            people = frame.readings["people"]
            assert people.shape == (PEOPLE, 3)
            dx, dy = people[:, 0] - frame.pose.x, people[:, 1] - frame.pose.y
            cos, sin = math.cos(frame.pose.yaw), math.sin(frame.pose.yaw)
            gap = footprint.signed_distance_xy(cos * dx + sin * dy, -sin * dx + cos * dy)
            nearest = min(nearest, max(float(gap.min()) - person_m, 0.0))
            _, _, terminated, truncated, info = env.step(baseline.action(frame))
            if terminated or truncated:
                break
    finally:
        env.close()
    assert info["outcome"] in ("goal", "timeout"), info
    result = compute([tmp_path / "orca" / "episode_0000"])
    row = result.frame.iloc[0]
    assert row["error"] == ""
    # the sim's default radius is the metrics' default for a bag without the fact
    assert result.results[0].episode.facts.person_radius_m == person_m == PERSON_RADIUS_M
    # the bag's closest approach is the frames' within a step's walk (the bag has the last step)
    assert abs(row["people_dist_min_m"] - nearest) < 0.2, (row["people_dist_min_m"], nearest)
    for name in ("intimate_intrusion_time_s", "personal_intrusion_time_s",
                 "social_intrusion_time_s", "people_ttc_min_s", "speed_near_people_mean_mps"):
        assert name in row.index, name
    assert 0.0 <= row["intimate_intrusion_time_s"] <= row["personal_intrusion_time_s"] \
        <= row["social_intrusion_time_s"]
    assert row["social_intrusion_time_s"] > 0.0  # ten people in the indoor world: met some
    assert row["people_collision_count"] == 0
