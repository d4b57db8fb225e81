"""A collision is what the robot touched in simulation, sensed or not: a Jackal driven at a box
below its LiDAR's plane (``clutter3d``) ends the episode ``collision`` by the ``contact`` rule,
in process and through the sim node, and the bag says so; on the sensed rule alone (a real
robot's: no contact known) the same drive is a timeout against the unseen box. A real robot's
frames know no contact, so only the sensed rule can end its episodes."""

from __future__ import annotations

import dataclasses
import math
import sys
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from ros_helpers import SimProcess
from rosbags.rosbag2 import Reader

from pic4rl_base.geometry import Pose2D
from pic4rl_bridge.perception.collision import assess
from pic4rl_bridge.readings.frame import ScanData, SensorFrame
from pic4rl_bridge.recording import make_env
from pic4rl_metrics.contract import CollisionRule
from pic4rl_sim.engine.geometry import Twist2D
from pic4rl_sim.engine.worlds.generators import make_world

ROOT = Path(__file__).resolve().parents[2]
CONFIG = ROOT / "config" / "env_goto_lidar.yaml"
WORLD = {"world": "clutter3d", "world_variant": 1, "world.clutter3d.low_boxes": 1,
         "world.clutter3d.tables": 0, "world.clutter3d.inner_walls": 0}
FORWARD = np.array([1.0, 0.0], np.float32)  # full speed ahead
STEPS = 40


def _episode() -> dict[str, list[float]]:
    """1.5 m short of the low box, facing it, the goal 1.5 m beyond it."""
    box = next(b for b in make_world("clutter3d", seed=1, low_boxes=1, tables=0,
                                     inner_walls=0).boxes if b.kind == "obstacle")
    toward = math.atan2(box.y, box.x)
    c, s = math.cos(toward), math.sin(toward)
    return {"start": [box.x - 1.5 * c, box.y - 1.5 * s, toward],
            "goal": [box.x + 1.5 * c, box.y + 1.5 * s]}


def _drive(env: Any) -> dict[str, Any]:
    env.reset(seed=0, options=_episode())
    for _ in range(STEPS):
        _, _, terminated, truncated, info = env.step(FORWARD)
        if terminated or truncated:
            return info
    return info


def _bag_facts(bags: Path) -> dict[str, str]:
    with Reader(bags / "r" / "episode_0000") as reader:
        return dict(reader.storage.metadata.custom)


def test_a_low_box_touched_in_process_is_a_contact_collision(tmp_path):
    env = make_env(CONFIG, sim=WORLD, overrides={
        "episode_max_steps": STEPS, "record.enabled": True,
        "record.bags_dir": str(tmp_path / "bags"), "record.run": "r"})
    try:
        info = _drive(env)
    finally:
        env.close()
    assert info["outcome"] == "collision" and info["collision_rule"] == "contact"
    assert info["step"] < STEPS and info["reward_terms"]["collision"] == -150.0
    assert info["min_obstacle_m"] > 0.05  # the LiDAR never saw the box it touched
    facts = _bag_facts(tmp_path / "bags")
    assert facts["outcome"] == "collision" and facts["collision_rule"] == "contact"


def test_on_the_sensed_rule_alone_the_same_drive_is_a_timeout():
    """The frames stripped of the contact, as a real robot's: the robot stands pressed
    against the box it cannot see until the time limit."""
    env = make_env(CONFIG, sim=WORLD, overrides={"episode_max_steps": STEPS})
    step = env.transport.step
    env.transport.step = lambda command: dataclasses.replace(step(command), contact=None)
    try:
        info = _drive(env)
        stuck = env.frame.pose
    finally:
        env.close()
    assert info["outcome"] == "timeout" and "collision_rule" not in info
    assert info["step"] == STEPS and info["collision"] is False
    start = _episode()["start"]
    assert math.hypot(stuck.x - start[0], stuck.y - start[1]) < 1.5  # short of the box's centre


def test_without_a_known_contact_only_a_sensed_point_ends_the_episode():
    env = make_env(CONFIG, sim=WORLD)
    try:
        robot, config = env.task.robot, env.config
    finally:
        env.close()
    near = ScanData(np.array([0.15], np.float32), 0.0, 0.01, 0.1, 10.0, Pose2D(0.12, 0, 0))
    far = dataclasses.replace(near, ranges=np.array([5.0], np.float32))
    pose, twist = Pose2D(0, 0, 0), Twist2D()
    cases = [(near, None, CollisionRule.SENSED), (far, None, None),
             (far, False, None), (far, True, CollisionRule.CONTACT),
             (near, True, CollisionRule.SENSED)]
    for scan, contact, rule in cases:
        safety = assess(SensorFrame(0, pose, twist, contact=contact, scan=scan), robot, config, 0)
        assert (safety.rule, safety.ended) == (rule, rule is not None), (contact, rule)


@pytest.mark.integration
def test_a_low_box_touched_through_the_sim_node_is_a_contact_collision(
        domain, start_sim, tmp_path):
    args = [f"{k}:={v}" for k, v in WORLD.items()]
    start_sim(domain, "--params-file", str(CONFIG), *[a for x in args for a in ("-p", x)])
    env = make_env(CONFIG, transport="ros", sim=WORLD, overrides={
        "ros.domain_id": domain, "episode_max_steps": STEPS, "record.enabled": True,
        "record.bags_dir": str(tmp_path / "bags"), "record.run": "r"})
    try:
        info = _drive(env)
    finally:
        env.close()
    assert info["outcome"] == "collision" and info["collision_rule"] == "contact"
    assert info["min_obstacle_m"] > 0.05
    assert _bag_facts(tmp_path / "bags")["collision_rule"] == "contact"


@pytest.mark.integration
def test_a_real_robots_frames_know_no_contact(domain, tmp_path):
    """``fake_robot.py`` (no sim node): every frame's ``contact`` is ``None``."""
    robot = SimProcess([sys.executable, str(Path(__file__).with_name("fake_robot.py")),
                        "--scan", f"scan:{-math.pi!r}:{2 * math.pi / 360!r}:360"], domain,
                       tmp_path / "robot.log")
    env = make_env({"task": "goToPose", "sensor": "lidar", "robot": "jackal"}, transport="ros",
                   overrides={"ros.domain_id": domain, "ros.sim_node": "",
                              "ros.reset_service": "", "ros.step_mode": "rate",
                              "ros.timeout_s": 10.0, "ros.operator_timeout_s": 20.0})
    try:
        env.reset()
        frames = [env.frame]
        for _ in range(3):
            env.step(np.array([-1.0, 0.0], np.float32))
            frames.append(env.frame)
    finally:
        env.close()
        robot.stop()
    assert [f.contact for f in frames] == [None] * 4
