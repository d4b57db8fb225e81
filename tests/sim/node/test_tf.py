"""The sim's TF (issue 38 item 4): ``tf`` carries ``odom → base_link`` from the odometry,
``tf_static`` ``base_link →`` each sensor frame from the robot's mounts (REP 105); bags carry
both, and the message package built at set-up (``ros/build.sh``) is real Jazzy's."""

from __future__ import annotations

import json
import math
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest
from rosbags.rosbag2 import Reader
from ros_helpers import ARENA_MJCF, SimProcess, next_domain, sim_command, sim_env

from pic4rl_bridge.recording import make_env
from pic4rl_metrics import compute_metrics, read_episode
from pic4rl_metrics.bags import tf
from pic4rl_metrics.bags.topics import TopicMap
from pic4rl_metrics.contract import typestore
from pic4rl_sim.engine.core import Engine
from pic4rl_sim.engine.robot_specs import JACKAL, DepthCameraSpec, LidarSpec
from pic4rl_sim.engine.worlds.spec import WorldSpec
from pic4rl_sim.node.transforms import static_transforms

ROOT = Path(__file__).resolve().parents[3]
#: tf2_msgs/msg/TFMessage's type hash in ROS 2 Jazzy, as `ros2 topic info /tf --verbose` and a
#: Jazzy bag's metadata.yaml (`type_description_hash`) report it.
JAZZY_TF_HASH = "RIHS01_e369d0f05a23ae52508854b66f6aa0437f3449d652e8cbf22d5abe85d020f087"


def _rotate(q, v) -> np.ndarray:
    """``v`` rotated by the unit quaternion ``q`` (x, y, z, w)."""
    u, w = np.array([q.x, q.y, q.z]), q.w
    t = 2.0 * np.cross(u, v)
    return np.asarray(v, dtype=float) + w * t + np.cross(u, t)


def test_the_built_message_has_real_jazzys_type_hash() -> None:
    described = json.loads((Path(sys.prefix) / "share" / "tf2_msgs" / "msg" /
                            "TFMessage.json").read_text())
    assert described["type_hashes"][0] == {"type_name": "tf2_msgs/msg/TFMessage",
                                           "hash_string": JAZZY_TF_HASH}
    # rosbags computes it from its own copy of Jazzy's definitions: the same.
    assert typestore().hash_rihs01("tf2_msgs/msg/TFMessage") == JAZZY_TF_HASH


def test_static_transforms_place_each_sensor_at_its_mount() -> None:
    pitch = 0.3
    robot = JACKAL.with_sensors(
        lidar=LidarSpec(mount_xyz_m=(0.12, -0.05, 0.3), mount_yaw_rad=0.5),
        depth=DepthCameraSpec(mount_xyz_m=(0.2, 0.0, 0.4), mount_pitch_rad=pitch))
    engine = Engine(robot, WorldSpec("field", (-5.0, -5.0, 5.0, 5.0)), seed=1)
    msg = static_transforms(engine, 2_500_000_000)
    frames = {tf.child_frame_id: tf for tf in msg.transforms}
    assert set(frames) == {"laser", "camera_depth_optical_frame", "imu_link"}
    for tf in msg.transforms:
        assert tf.header.frame_id == "base_link"
        assert (tf.header.stamp.sec, tf.header.stamp.nanosec) == (2, 500_000_000)
    laser = frames["laser"].transform
    assert (laser.translation.x, laser.translation.y, laser.translation.z) == (0.12, -0.05, 0.3)
    assert _rotate(laser.rotation, [1, 0, 0]) == pytest.approx([math.cos(0.5), math.sin(0.5), 0])
    cam = frames["camera_depth_optical_frame"].transform
    assert (cam.translation.x, cam.translation.y, cam.translation.z) == (0.2, 0.0, 0.4)
    # Optical axes: z along the view (forward, pitched down), x right, y down.
    assert _rotate(cam.rotation, [0, 0, 1]) == pytest.approx(
        [math.cos(pitch), 0, -math.sin(pitch)], abs=1e-12)
    assert _rotate(cam.rotation, [1, 0, 0]) == pytest.approx([0, -1, 0], abs=1e-12)
    assert _rotate(cam.rotation, [0, 1, 0]) == pytest.approx(
        [-math.sin(pitch), 0, -math.cos(pitch)], abs=1e-12)
    imu = frames["imu_link"].transform
    assert (imu.rotation.w, imu.translation.z) == (1.0, 0.0)


def _bag_paths_agree(bag: Path) -> int:
    """Assert that ``bag``'s pose from /tf equals its /odom's (every sample, to 1e-9, and the
    metrics' path length); return the number of poses."""
    by_odom = read_episode(bag, TopicMap(pose=("/odom",)))
    by_tf = read_episode(bag, TopicMap(pose_frames=("odom", "base_link")))
    np.testing.assert_array_equal(by_tf.pose.t_ns, by_odom.pose.t_ns)
    for axis in ("x", "y", "yaw"):
        np.testing.assert_allclose(getattr(by_tf.pose, axis), getattr(by_odom.pose, axis),
                                   rtol=0, atol=1e-9)
    length = compute_metrics(by_odom).path_length_m
    assert compute_metrics(by_tf).path_length_m == pytest.approx(length, abs=1e-9)
    return len(by_odom.pose)


def test_a_recorded_bags_tf_gives_the_path_of_its_odom(tmp_path: Path) -> None:
    env = make_env(ROOT / "config" / "env_goto_lidar.yaml",
                   overrides={"transport": "inprocess", "record.enabled": True,
                              "record.bags_dir": str(tmp_path), "record.run": "r",
                              "episode_max_steps": 40})
    try:
        env.reset(seed=5)
        for i in range(40):
            action = np.array([0.6, 0.8 * math.sin(i / 4)], np.float32)
            _, _, terminated, truncated, _ = env.step(action)
            if terminated or truncated:
                break
    finally:
        env.close()
    bag = tmp_path / "r" / "episode_0000"
    assert _bag_paths_agree(bag) > 10
    assert compute_metrics(read_episode(bag, TopicMap(pose=("/odom",)))).path_length_m > 0.5
    # The scan's frame resolves through the bag's /tf_static to the Jackal's LiDAR mount.
    with Reader(bag) as reader:
        first = {}
        for conn, _, raw in reader.messages():
            first.setdefault(conn.topic, typestore().deserialize_cdr(raw, conn.msgtype))
    assert {"/tf", "/tf_static", "/scan"} <= set(first)
    tree = tf.edges([], [tf.tf_rows(first["/tf_static"])])
    mount = tf.static_pose(tree, "base_link", first["/scan"].header.frame_id)
    assert mount == pytest.approx((0.12, 0.0, 0.0))


@pytest.mark.integration
def test_the_ros_transport_records_tf_per_step_and_tf_static_per_episode(
        tmp_path: Path, start_sim) -> None:
    config = ROOT / "config" / "env_goto_lidar.yaml"
    domain = next_domain()
    start_sim(sim_command("--params-file", str(config)), domain)
    env = make_env(config, transport="ros", overrides={
        "ros.domain_id": domain, "record.enabled": True, "record.bags_dir": str(tmp_path),
        "record.run": "ros", "episode_max_steps": 12})
    rng = np.random.default_rng(2)
    try:
        for episode in range(2):
            env.reset(seed=7 if episode == 0 else None)
            done = False
            while not done:
                out = env.step(rng.uniform(-1, 1, 2).astype(np.float32))
                done = out[2] or out[3]
    finally:
        env.close()
    bags = sorted((tmp_path / "ros").glob("episode_*"))
    assert len(bags) == 2
    for bag in bags:
        with Reader(bag) as reader:
            counts = {c.topic: c.msgcount for c in reader.connections}
            first = min(t for _, t, _ in reader.messages())
            static = [t for c, t, _ in reader.messages() if c.topic == "/tf_static"]
        assert counts["/tf"] == counts["/odom"] > 1
        assert static == [first]  # once, at the episode's first stamp
        assert _bag_paths_agree(bag) == counts["/odom"]


#: A user's node: plain rclpy and standard messages, nothing of this project. It drives the
#: lockstep sim with zero commands until it has seen both transforms, then prints them.
LISTENER = textwrap.dedent("""
    import json, sys, time
    import rclpy
    from geometry_msgs.msg import Twist
    from rclpy.qos import DurabilityPolicy, QoSProfile
    from tf2_msgs.msg import TFMessage

    rclpy.init()
    node = rclpy.create_node("tf_listener")
    seen = {}
    def keep(msg):
        for tf in msg.transforms:
            t, q = tf.transform.translation, tf.transform.rotation
            name = tf.header.frame_id + "->" + tf.child_frame_id
            seen[name] = [t.x, t.y, t.z, q.x, q.y, q.z, q.w]
    node.create_subscription(TFMessage, "/tf", keep, 10)
    node.create_subscription(TFMessage, "/tf_static", keep, QoSProfile(
        depth=1, durability=DurabilityPolicy.TRANSIENT_LOCAL))
    cmd = node.create_publisher(Twist, "/cmd_vel", 10)
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline and not {"odom->base_link", "base_link->laser"} <= set(seen):
        cmd.publish(Twist())
        rclpy.spin_once(node, timeout_sec=0.2)
    hashes = [str(i.topic_type_hash) for i in node.get_publishers_info_by_topic("/tf")]
    print(json.dumps({"seen": seen, "hashes": hashes}))
    node.destroy_node()
    rclpy.shutdown()
""")


@pytest.mark.integration
def test_a_plain_rclpy_process_receives_the_transforms(tmp_path: Path) -> None:
    world = tmp_path / "arena.xml"
    world.write_text(ARENA_MJCF)
    domain = next_domain()
    sim = SimProcess(sim_command("-p", f"world:={world}", "-p", "robot:=jackal",
                                 "-p", "start_pose:=[1.0, -2.0, 0.5]"),
                     domain, tmp_path / "sim.log")
    try:
        done = subprocess.run([sys.executable, "-c", LISTENER], env=sim_env(domain),
                              capture_output=True, text=True, timeout=90, check=False)
    finally:
        sim.stop()
    assert done.returncode == 0, done.stderr
    report = json.loads(done.stdout.strip().splitlines()[-1])
    seen = report["seen"]
    x, y, z, qx, qy, qz, qw = seen["odom->base_link"]
    assert (x, y, z) == pytest.approx((1.0, -2.0, 0.0), abs=1e-6)  # odom starts at the start
    assert 2 * math.atan2(qz, qw) == pytest.approx(0.5, abs=1e-6)
    assert seen["base_link->laser"] == pytest.approx([0.12, 0.0, 0.3, 0.0, 0.0, 0.0, 1.0])
    assert "base_link->imu_link" in seen
    assert JAZZY_TF_HASH in report["hashes"][0]
