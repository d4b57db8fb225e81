"""personMonitoring: 3-D omni actions, facing and distance reward, no goal outcome."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from pic4rl_base.geometry import Footprint, Pose2D
from pic4rl_bridge.config import EnvConfig
from pic4rl_bridge.errors import ConfigError
from pic4rl_bridge.readings.frame import ScanData, SensorFrame
from pic4rl_bridge.robot_info import RobotInfo
from pic4rl_bridge.tasks import make_task
from pic4rl_bridge.tasks.person import PersonMonitoringTask
from pic4rl_metrics.contract import Outcome
from pic4rl_sim.engine.geometry import Twist2D

OMNI = RobotInfo(name="omni", footprint=Footprint(length_m=0.6, width_m=0.4), omni=True,
                 min_linear_m_s=-0.8, max_linear_m_s=0.8, max_angular_rad_s=1.5,
                 max_lateral_m_s=0.6, control_dt_s=0.1)
CONFIG = EnvConfig().replace(task="personMonitoring")


def frame(person: Pose2D, yaw: float = 0.0, ahead_m: float = math.inf) -> SensorFrame:
    ranges = np.full(360, np.inf, np.float32)
    ranges[180] = ahead_m
    scan = ScanData(ranges, -math.pi, 2 * math.pi / 360, 0.1, 30.0)
    return SensorFrame(0, Pose2D(0.0, 0.0, yaw), Twist2D(), scan=scan, person=person)


def test_action_to_omni_command():
    task = make_task(CONFIG, OMNI)
    assert isinstance(task, PersonMonitoringTask) and task.action_space.shape == (3,)
    assert task.command(np.array([1.0, -1.0, 0.5])) == pytest.approx(Twist2D(0.8, -0.6, 0.75))
    assert task.command(np.array([-2.0, 0.0, -1.0])) == pytest.approx(Twist2D(-0.8, 0.0, -1.5))


@pytest.mark.parametrize("person, yaw, bearing", [
    (Pose2D(2.0, 2.0), 0.0, math.pi / 4), (Pose2D(-2.0, 0.0), 0.0, math.pi),
    (Pose2D(0.0, 3.0), math.pi / 2, 0.0), (Pose2D(1.0, 0.0), -math.pi / 3, math.pi / 3)])
def test_facing_and_distance_terms(person, yaw, bearing):
    task = PersonMonitoringTask(CONFIG.replace(**{"reward.bearing": 0.3}), OMNI)
    f = frame(person, yaw)
    j = task.judge(f, f, task.begin(f), 0)
    distance = math.hypot(person.x, person.y)
    assert set(j.terms) == {"facing", "bearing", "person_distance", "collision", "step"}
    assert j.terms["facing"] == pytest.approx(math.cos(bearing))
    assert j.terms["bearing"] == pytest.approx(-0.3 * bearing)
    assert j.terms["person_distance"] == pytest.approx(-0.5 * abs(distance - 2.0))
    assert j.outcome is None and j.terms["collision"] == 0.0


def test_observation_in_space():
    task = PersonMonitoringTask(CONFIG, OMNI)
    f = frame(Pose2D(0.0, -3.0), ahead_m=1.5)
    f = dataclasses.replace(f, person=Pose2D(0.0, -3.0, math.pi))  # walking toward -x
    obs = task.observe(f, task.begin(f), np.array([0.1, 2.0, -0.3]))
    assert obs.shape == (CONFIG.lidar.sectors + 6,) and task.observation_space.contains(obs)
    np.testing.assert_allclose(np.abs(obs[-4]), math.pi, rtol=1e-6)  # walking at the robot's back
    np.testing.assert_allclose(obs[[-6, -5, -3, -2, -1]], [3.0, -math.pi / 2, 0.1, 1.0, -0.3],
                               rtol=1e-6)
    assert obs[CONFIG.lidar.sectors // 2] == 1.5
    assert task.required == {"scan", "person"}


def test_collision_ends_but_nothing_else_does():
    task = PersonMonitoringTask(CONFIG.replace(collision_steps=2), OMNI)
    near = frame(Pose2D(2.0, 0.0), ahead_m=0.32)  # 0.02 m from the box's front face
    first = task.judge(near, near, task.begin(near), 0)
    assert first.collision and first.outcome is None and first.collision_streak == 1
    second = task.judge(near, near, task.begin(near), first.collision_streak)
    assert second.outcome is Outcome.COLLISION and second.terms["collision"] == -150.0
    at_person = frame(Pose2D(2.0, 0.0))
    assert task.judge(at_person, at_person, task.begin(at_person), 0).outcome is None


def test_make_task_needs_an_omni_robot():
    diff = RobotInfo(name="jackal", footprint=Footprint(radius_m=0.3), omni=False,
                     min_linear_m_s=0.0, max_linear_m_s=1.0, max_angular_rad_s=1.0,
                     max_lateral_m_s=0.0, control_dt_s=0.1)
    with pytest.raises(ConfigError, match="personMonitoring.*'jackal' is not omni"):
        make_task(CONFIG, diff)
