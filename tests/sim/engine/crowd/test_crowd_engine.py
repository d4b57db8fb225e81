"""The crowd in the engine: seeded walks kept off the walls and each other, people seen by the
LiDAR and the depth camera and touched by the robot, and the ``people`` topic recorded through
the in-process transport."""

from __future__ import annotations

import math
import tempfile
from pathlib import Path

import mujoco
import numpy as np
import pytest
from rosbags.rosbag2 import Reader
from rosbags.typesys import Stores, get_typestore

from pic4rl_base.errors import ConfigError
from pic4rl_base.geometry import Pose2D
from pic4rl_sim.engine.core import Engine
from pic4rl_sim.errors import WorldError
from pic4rl_sim.engine.crowd.params import CrowdParams
from pic4rl_sim.engine.engine_config import EngineConfig
from pic4rl_sim.engine.geometry import Twist2D
from pic4rl_sim.engine.ray_sensors import DepthCameraSpec
from pic4rl_sim.engine.robot_specs import JACKAL
from pic4rl_sim.engine.worlds.generators import make_world
from pic4rl_sim.engine.worlds.spec import WorldSpec

ROOT = Path(__file__).resolve().parents[4]


def _engine(count: int, *, seed: int = 0, world: WorldSpec | None = None, **crowd) -> Engine:
    config = EngineConfig(crowd=CrowdParams(count=count, **crowd))
    return Engine(JACKAL, world or make_world("indoor", seed=0), config, seed=seed)


def _walk(engine: Engine, steps: int) -> np.ndarray:
    for _ in range(steps):
        engine.step(Twist2D(0.0, 0.0, 0.0))
    people = engine.people()
    assert people is not None
    return people[0]


def test_the_same_seed_gives_the_same_walks_and_another_seed_others():
    a = _walk(_engine(8, seed=5, max_group_size=3), 30)
    b = _walk(_engine(8, seed=5, max_group_size=3), 30)
    c = _walk(_engine(8, seed=6, max_group_size=3), 30)
    np.testing.assert_array_equal(a, b)
    assert np.abs(a - c).max() > 0.5


def test_people_walk_among_the_walls_without_entering_them_or_each_other():
    engine = _engine(30, seed=1, max_group_size=3)
    last = engine.people()[0].copy()
    walked = np.zeros(30)
    wall_gaps, pair_gaps = [], []
    for _ in range(100):
        people = _walk(engine, 3)
        walked += np.hypot(*(people - last).T)
        last = people.copy()
        wall_gaps.append(engine.world.clearance(people).min() - 0.25)
        centres = np.hypot(*(people[:, None] - people[None]).transpose(2, 0, 1))
        pair_gaps.append((centres + 99 * np.eye(30)).min() - 0.5)
    assert np.median(walked) > 15.0  # 30 s in a crowded indoor world: about 0.8 m/s
    assert min(wall_gaps) > -1e-6  # a body never inside an obstacle
    assert np.median(pair_gaps) > -0.05 and min(pair_gaps) > -0.25  # bodies barely overlap


def test_a_lidar_beam_hits_a_person_at_the_expected_range():
    world = WorldSpec("open", (-5.0, -5.0, 5.0, 5.0))
    engine = _engine(1, world=world)
    engine.reset(start=Pose2D(0.0, 0.0, 0.0))
    lidar = JACKAL.lidar
    assert lidar is not None
    mocap = engine.ids.crowd_mocap[0]
    engine.data.mocap_pos[mocap] = (3.0, 0.0, 0.0)
    mujoco.mj_forward(engine.model, engine.data)
    ranges = engine.scan()
    angles = lidar.angle_min_rad + np.arange(lidar.beams) * lidar.angle_increment_rad
    ahead = int(np.argmin(np.abs(angles + lidar.mount_yaw_rad)))
    assert ranges[ahead] == pytest.approx(3.0 - 0.25 - lidar.mount_xyz_m[0], abs=1e-3)
    assert np.isinf(ranges[(ahead + lidar.beams // 2) % lidar.beams])  # nothing behind


def test_the_depth_camera_sees_a_person_at_the_expected_depth():
    world = WorldSpec("open", (-5.0, -5.0, 5.0, 5.0))
    robot = JACKAL.with_sensors(depth=DepthCameraSpec())  # level, 0.2 m ahead of the base
    engine = Engine(robot, world, EngineConfig(crowd=CrowdParams(count=1)))
    engine.reset(start=Pose2D(0.0, 0.0, 0.0))
    mocap = engine.ids.crowd_mocap[0]
    engine.data.mocap_pos[mocap] = (-3.0, 0.0, 0.0)  # behind the camera
    mujoco.mj_forward(engine.model, engine.data)
    assert np.isinf(engine.depth_image()[30, 40])
    engine.data.mocap_pos[mocap] = (3.0, 0.0, 0.0)
    mujoco.mj_forward(engine.model, engine.data)
    assert engine.depth_image()[30, 40] == pytest.approx(3.0 - 0.25 - 0.2, abs=0.01)


def test_the_robot_driving_into_a_person_collides():
    world = WorldSpec("open", (-5.0, -5.0, 5.0, 5.0))
    engine = _engine(1, world=world, speed_mean_m_s=0.1, speed_std_m_s=0.0)
    engine.reset(start=Pose2D(0.0, 0.0, 0.0))
    engine.crowd.pos[0] = (1.0, 0.0)
    engine.data.mocap_pos[engine.ids.crowd_mocap[0], :2] = (1.0, 0.0)
    collided = [engine.step(Twist2D(1.0, 0.0, 0.0)).collided for _ in range(20)]
    assert any(collided)  # a contact with a person counts as a collision


def test_people_walk_round_a_standing_robot():
    # 10 people, 30 s, a robot that never moves: touched (a body within the env's 5 cm
    # collision tolerance of the box) in at most 1 of 10 episodes. With the field of view
    # turned round (a person ahead weighing 0.5, one behind 1), seeds 0-9 touched it in 5.
    engine = _engine(10)
    footprint, person_m = JACKAL.footprint, engine.config.crowd.radius_m
    touched = 0
    for seed in range(10):
        engine.reset(seed=seed)
        gaps = []
        for _ in range(300):
            people = _walk(engine, 1)
            pose = engine.robot_pose()
            c, s = math.cos(pose.yaw), math.sin(pose.yaw)
            d = people - (pose.x, pose.y)
            body = np.column_stack((c * d[:, 0] + s * d[:, 1], -s * d[:, 0] + c * d[:, 1]))
            gaps.append(footprint.signed_distance(body).min() - person_m)
        touched += min(gaps) < 0.05
    assert touched <= 1


def test_a_crowd_that_does_not_fit_is_a_one_line_error():
    world = WorldSpec("small", (-1.5, -1.5, 1.5, 1.5))  # room for the robot, not for 12 more
    with pytest.raises(WorldError, match=r"^crowd.count: 12 is invalid; expected a crowd that "
                       r"fits world 'small'"):
        _engine(12, world=world)
    with pytest.raises(ConfigError, match="crowd.max_group_size"):
        CrowdParams(count=2, max_group_size=3)


def test_the_people_topic_is_recorded_through_the_in_process_transport():
    from pic4rl_bridge.recording import make_env

    store = get_typestore(Stores.ROS2_JAZZY)
    with tempfile.TemporaryDirectory() as bags:
        env = make_env(ROOT / "config" / "env_goto_lidar.yaml",
                       overrides={"record.enabled": True, "record.bags_dir": bags,
                                  "record.run": "r", "record.storage": "sqlite3",
                                  "episode_max_steps": 5}, sim={"crowd.count": 4})
        try:
            env.reset(seed=3)
            for _ in range(5):
                env.step(np.zeros(env.action_space.shape, np.float32))
        finally:
            env.close()
        with Reader(Path(bags) / "r" / "episode_0000") as reader:
            msgs = {c.topic: [] for c in reader.connections}
            for conn, stamp, raw in reader.messages():
                msgs[conn.topic].append(store.deserialize_cdr(raw, conn.msgtype))
    arrays = msgs["/people"]
    assert len(arrays) == len(msgs["/clock"]) == 6
    assert all(len(a.poses) == 4 and a.header.frame_id == "world" for a in arrays)
    assert [a.header.stamp for a in arrays] == [c.clock for c in msgs["/clock"]]
    first, last = (np.array([[p.position.x, p.position.y] for p in a.poses])
                   for a in (arrays[0], arrays[-1]))
    assert np.hypot(*(last - first).T).max() > 0.2  # they walk
    yaw = [2 * math.atan2(p.orientation.z, p.orientation.w) for p in arrays[-1].poses]
    step = last - np.array([[p.position.x, p.position.y] for p in arrays[-2].poses])
    np.testing.assert_allclose(np.cos(yaw), step[:, 0] / np.hypot(*step.T), atol=0.05)
