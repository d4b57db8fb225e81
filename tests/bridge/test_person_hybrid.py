"""personMonitoring's RL-DWA hybrid: the agent gives ω, DWA (vx, vy); and its classical
version, DWA with a proportional heading law, judged from its bags.

The analytic layouts: the person 5 m straight ahead or to the left of a robot at rest in the
open (the follower closes in along that line), and the person world without obstacles (the
follower keeps the person in view)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from pic4rl_base.geometry import Footprint, Pose2D
from pic4rl_bridge.baselines.follow import HeadingController, PersonFollower
from pic4rl_bridge.baselines.registry import make_baseline
from pic4rl_bridge.config import EnvConfig
from pic4rl_bridge.env import NavEnv
from pic4rl_bridge.readings.frame import ScanData, SensorFrame
from pic4rl_bridge.recording import record_from_config
from pic4rl_bridge.robot_info import RobotInfo
from pic4rl_bridge.tasks import make_task
from pic4rl_metrics import compute
from pic4rl_sim.engine.geometry import Twist2D

ROOT = Path(__file__).resolve().parents[2]
CONFIG = ROOT / "config" / "env_person_omni.yaml"
OMNI = RobotInfo(name="omni", footprint=Footprint(radius_m=0.25), omni=True,
                 min_linear_m_s=-1.0, max_linear_m_s=1.0, max_angular_rad_s=2.0,
                 max_lateral_m_s=1.0, control_dt_s=0.1, mounts={"lidar": Pose2D(0.0, 0.0, 0.0)},
                 max_linear_accel_m_s2=2.0, max_angular_accel_rad_s2=4.0)
HYBRID = EnvConfig().replace(task="personMonitoring", **{"person.control": "hybrid"})
OPEN = {"world.person.count": 0, "world.person.occluders": 0}


def frame(person: Pose2D, twist: Twist2D = Twist2D(), wall_m: float = math.inf) -> SensorFrame:
    """The robot at the origin facing +x; every beam free, or a wall ``wall_m`` ahead."""
    angles = -math.pi + 2 * math.pi / 360 * np.arange(360)
    ranges = np.where(np.abs(angles) < 0.6, wall_m / np.cos(angles), np.inf).astype(np.float32)
    scan = ScanData(ranges, -math.pi, 2 * math.pi / 360, 0.1, 30.0)
    return SensorFrame(0, Pose2D(0.0, 0.0, 0.0), twist, scan=scan, person=person)


def test_the_hybrid_agent_gives_the_yaw_rate_and_dwa_the_translation():
    task = make_task(HYBRID, OMNI)
    assert task.action_space.shape == (1,)
    ahead, left = frame(Pose2D(5.0, 0.0)), frame(Pose2D(0.0, 5.0))
    for wz_action in (-0.5, 0.0, 0.75):
        command = task.command_at(np.array([wz_action]), ahead)
        assert command.wz == pytest.approx(wz_action * 2.0)
        assert command.vx == pytest.approx(0.2)  # one window's step (2 m/s² × 0.1 s) toward it
    to_left = task.command_at(np.array([0.0]), left)
    assert to_left.vy == pytest.approx(0.2) and to_left.vx == pytest.approx(0.0, abs=1e-9)
    # Closer than the desired 2 m: it backs off; a wall 0.5 m ahead: it does not go on.
    assert task.command_at(np.array([0.0]), frame(Pose2D(1.0, 0.0))).vx < 0
    blocked = task.command_at(np.array([0.0]), frame(Pose2D(5.0, 0.0), Twist2D(0.2), 0.5))
    assert blocked.vx < 0.2
    assert task.command(np.array([0.75])) == Twist2D(0.0, 0.0, 1.5)  # the agent's share


def test_the_follower_comes_to_rest_at_the_desired_distance():
    follower = PersonFollower(OMNI, distance_m=2.0)
    assert follower.follow_point(frame(Pose2D(2.0, 0.0))) == pytest.approx((0.0, 0.0))
    vx, vy = follower.translation(frame(Pose2D(2.0, 0.0)), 0.0)
    assert (vx, vy) == pytest.approx((0.0, 0.0), abs=1e-9)


def test_through_the_env_the_agents_omega_and_dwas_translation_both_reach_the_command():
    env = NavEnv(CONFIG, overrides={"person.control": "hybrid"}, sim=OPEN)
    sent: list[Twist2D] = []
    step = env.transport.step
    env.transport.step = lambda command: (sent.append(command), step(command))[1]
    try:
        env.reset(seed=0)
        for k in range(20):
            before = env.frame
            action = np.array([math.sin(k / 3.0)], np.float32)
            env.step(action)
            expected = env.task.follower.translation(before, float(action[0]) * 2.0)
            assert sent[-1].wz == pytest.approx(float(action[0]) * 2.0)
            assert (sent[-1].vx, sent[-1].vy) == pytest.approx(expected)
    finally:
        env.close()
    assert max(math.hypot(c.vx, c.vy) for c in sent) > 0.3  # DWA did drive


@pytest.mark.parametrize("control", ["hybrid", "end_to_end"])
def test_dwa_with_heading_keeps_the_person_in_view_judged_from_its_bags(tmp_path, control):
    """In the open person world the classical version follows without a collision and keeps
    the person in the 87 degree view nearly all the time, as its bags say."""
    overrides = {"person.control": control, "record.enabled": True, "record.run": control,
                 "record.bags_dir": str(tmp_path), "episode_max_steps": 150}
    nav = NavEnv(CONFIG, overrides=overrides, sim=OPEN)
    env = record_from_config(nav)
    try:
        controller = make_baseline("dwa_heading", nav.config, nav.scenario.robot)
        assert isinstance(controller, HeadingController)
        env.reset(seed=3)
        done, info = False, {}
        while not done:
            action = controller.action(nav.frame)
            assert action.shape == env.action_space.shape
            _, _, terminated, truncated, info = env.step(action)
            done = terminated or truncated
    finally:
        env.close()
    assert info["outcome"] == "timeout"
    row = compute(sorted(tmp_path.rglob("*.db3"))).frame.iloc[0]
    assert row["person_in_view_fraction"] >= 0.9
    assert row["follow_heading_mae_rad"] < 0.3
    assert abs(row["person_dist_mean_m"] - 2.0) < 1.0
    assert row["collision_count"] == 0
