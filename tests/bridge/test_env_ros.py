"""The env over ROS 2 against the real sim node in its own process: the same observations and
rewards as in process, Gymnasium's checker, recording every message to a bag the metrics judge,
and the real-robot reset that waits for an operator's goal."""

from __future__ import annotations

import math
import threading
import time
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest
import rclpy
from geometry_msgs.msg import PoseStamped
from nav_msgs.msg import Odometry
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from gymnasium.utils.env_checker import check_env
from rosbags.rosbag2 import Reader
from std_srvs.srv import Empty

import pic4rl_bridge  # noqa: F401 - registers the envs
from pic4rl_bridge.config import load_env_config
from pic4rl_bridge.errors import SimConflict
from pic4rl_metrics.tables.batch import compute

pytestmark = pytest.mark.integration

CONFIGS = {
    "pic4rl/GoToPoseLidar-v0": "config/env_goto_lidar.yaml",
    "pic4rl/GoToPoseDepth-v0": "config/env_goto_depth.yaml",
    "pic4rl/Vineyard-v0": "config/env_vineyard_depth.yaml",
    "pic4rl/PersonMonitoring-v0": "config/env_person_omni.yaml",
}
ROOT = Path(__file__).resolve().parents[2]


def _equal(a: object, b: object) -> bool:
    if isinstance(a, dict):
        return a.keys() == b.keys() and all(np.array_equal(a[k], b[k]) for k in a)
    return np.array_equal(a, b)


#: Every registered id, and goToPose's with memory (the grid of the episode's own scans) and
#: with the explorer's plan (made from them) as its target.
CASES = [(env_id, {}) for env_id in CONFIGS] + [
    (env_id, {"memory.enabled": True})
    for env_id in ("pic4rl/GoToPoseLidar-v0", "pic4rl/GoToPoseDepth-v0")] + [
    ("pic4rl/GoToPoseLidar-v0", {"goal_input": "explorer"})]


@pytest.mark.parametrize(("env_id", "extra"), CASES,
                         ids=[f"{e}{''.join('-' + str(v) for v in x.values())}"
                              for e, x in CASES])
def test_ros_and_in_process_agree_and_pass_the_checker(env_id: str, extra: dict, domain: int,
                                                        start_sim) -> None:
    """Same seed and actions: bit-identical observations (the memory crop too), rewards and
    ends through both transports, over several episodes; then Gymnasium's checker on the ROS
    env."""
    config = ROOT / CONFIGS[env_id]
    start_sim(domain, "--params-file", str(config))
    ros = gym.make(env_id, config=config, transport="ros",
                   overrides={"ros.domain_id": domain, "episode_max_steps": 40, **extra})
    local = gym.make(env_id, config=config, overrides={"episode_max_steps": 40, **extra})
    rng = np.random.default_rng(7)
    try:
        steps = 0
        for episode in range(3):
            seed = 11 if episode == 0 else None
            (obs_r, info_r), (obs_l, info_l) = ros.reset(seed=seed), local.reset(seed=seed)
            assert info_r["seed"] == info_l["seed"] and info_r["goal"] == info_l["goal"]
            assert _equal(obs_r, obs_l)
            done = False
            while not done:
                action = rng.uniform(-1, 1, ros.action_space.shape).astype(np.float32)
                out_r, out_l = ros.step(action), local.step(action)
                assert _equal(out_r[0], out_l[0]), f"observations differ at step {steps}"
                assert out_r[1:4] == out_l[1:4], f"reward or end differs at step {steps}"
                assert out_r[4]["reward_terms"] == out_l[4]["reward_terms"]
                done = out_r[2] or out_r[3]
                steps += 1
        assert steps > 20
        check_env(ros.unwrapped)
    finally:
        ros.close()
        local.close()


def test_a_world_per_episode_is_the_same_through_both_transports(domain: int,
                                                                 start_sim) -> None:
    """``episodes.world_variants`` on BARN: one seed gives the same worlds, pairs,
    observations and rewards through the sim node (its ``world_variant`` set with each
    episode's seed) as in process, and each episode's bag names its world."""
    config = ROOT / "config" / "env_barn.yaml"
    start_sim(domain, "--params-file", str(config))
    overrides = {"episodes.world_variants": "1:300:6,2:300:6", "episode_max_steps": 15}
    ros = gym.make("pic4rl/GoToPoseLidar-v0", config=config, transport="ros",
                   overrides={"ros.domain_id": domain, **overrides})
    local = gym.make("pic4rl/GoToPoseLidar-v0", config=config, overrides=overrides)
    rng = np.random.default_rng(3)
    worlds = []
    try:
        for episode in range(4):
            seed = 21 if episode == 0 else None
            (obs_r, info_r), (obs_l, info_l) = ros.reset(seed=seed), local.reset(seed=seed)
            names = ros.unwrapped.transport.world_name, local.unwrapped.transport.world_name
            assert names[0] == names[1] and info_r["seed"] == info_l["seed"]
            assert _equal(obs_r, obs_l), f"first observations differ in {names[0]}"
            worlds.append(names[0])
            done = False
            while not done:
                action = rng.uniform(-1, 1, ros.action_space.shape).astype(np.float32)
                out_r, out_l = ros.step(action), local.step(action)
                assert _equal(out_r[0], out_l[0]) and out_r[1:4] == out_l[1:4]
                done = out_r[2] or out_r[3]
    finally:
        ros.close()
        local.close()
    assert len(set(worlds)) >= 3 and all(w.startswith("barn:") for w in worlds)


@pytest.mark.bad_input
def test_a_second_sim_node_is_refused_at_reset_naming_both(domain: int, start_sim,
                                                            ros_client) -> None:
    """A twin ``sim`` publishing the goal and odometry (as a forgotten sim would): the reset
    refuses with one message naming both nodes, not the "is a sim answering?" hint of a
    silent graph."""
    config = ROOT / CONFIGS["pic4rl/GoToPoseLidar-v0"]
    start_sim(domain, "--params-file", str(config))
    client = ros_client(domain)
    latched = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE,
                         durability=DurabilityPolicy.TRANSIENT_LOCAL)
    client.collect("/goal_pose", PoseStamped, latched, 60.0)
    client.spin_for(2.0)  # past the sim's own look for a twin, which would stop it
    twin = rclpy.create_node("sim", context=client.context)
    twin.create_publisher(PoseStamped, "goal_pose", latched).publish(PoseStamped())
    twin.create_publisher(Odometry, "odom", 10)
    env = gym.make("pic4rl/GoToPoseLidar-v0", config=config, transport="ros",
                   overrides={"ros.domain_id": domain, "ros.timeout_s": 5.0})
    # The check reads the graph; a graph still discovering the twin has nothing to refuse.
    node = env.unwrapped.transport.node
    deadline = time.monotonic() + 10.0
    while len(node.get_publishers_info_by_topic("/odom")) < 2 and time.monotonic() < deadline:
        time.sleep(0.05)
    try:
        with pytest.raises(SimConflict, match=(
                rf"^2 simulator nodes publish /(goal_pose|odom) in ROS domain {domain}: "
                r"(/sim|a node not yet named) and (/sim|a node not yet named) "
                r"\(a pic4rl-sim left running\?\)")):
            env.reset(seed=1)
    finally:
        env.close()
        twin.destroy_node()


def _go_to_goal(env: gym.Env, max_steps: int = 300) -> dict:
    """A proportional go-to-goal controller: turn to the goal, drive when facing it."""
    obs, info = env.reset(options={"start": [-3.0, -2.0, 0.3], "goal": [2.0, 1.0]})
    beams = env.unwrapped.config.lidar.sectors
    for _ in range(max_steps):
        distance, angle = float(obs[beams]), float(obs[beams + 1])
        turn = float(np.clip(2.0 * angle, -1.0, 1.0))
        speed = float(np.clip(distance, 0.0, 1.0)) * max(0.0, math.cos(angle)) ** 4
        obs, _, terminated, truncated, info = env.step(np.array([2 * speed - 1, turn]))
        if terminated or truncated:
            return info
    raise AssertionError("the episode did not end")


def test_scripted_controller_reaches_the_goal_and_its_bag_says_so(
        domain: int, start_sim, arena: Path, tmp_path: Path) -> None:
    """Real sim + ROS env + proportional controller in an open arena: the goal is reached;
    the bag holds every message of the episode, and the metrics give success 1 and a path
    close to the straight line."""
    start_sim(domain, "--params-file", str(ROOT / "config/env_goto_lidar.yaml"),
              "-p", f"world:={arena}")
    env = gym.make("pic4rl/GoToPoseLidar-v0", config=ROOT / "config/env_goto_lidar.yaml",
                   transport="ros", sim={"world": str(arena)},
                   overrides={"ros.domain_id": domain, "record.enabled": True,
                              "record.bags_dir": str(tmp_path / "bags"), "record.run": "p",
                              "agent": "proportional"})
    try:
        info = _go_to_goal(env)
    finally:
        env.close()
    assert info["outcome"] == "goal" and info["is_success"]
    steps = info["step"]
    bag = tmp_path / "bags" / "p" / "episode_0000"
    with Reader(bag) as reader:
        counts = {c.topic: c.msgcount for c in reader.connections}
        assert reader.storage.metadata.custom["outcome"] == "goal"
    per_step = ("/clock", "/ground_truth", "/odom", "/scan")
    assert {t: counts[t] for t in per_step} == dict.fromkeys(per_step, steps + 1)
    assert counts["/cmd_vel"] == steps and counts["/goal_pose"] == 1
    assert counts["/episode/facts"] == 1 and counts["/episode/outcome"] == 1
    assert load_env_config(tmp_path / "bags" / "p" / "config.yaml").agent == "proportional"
    (row,) = compute([bag]).results
    assert row.error == "" and row.metrics is not None
    straight = math.hypot(2.0 + 3.0, 1.0 + 2.0)
    assert row.metrics.success == 1.0
    assert straight - 0.4 <= row.metrics.path_length_m <= 1.1 * straight


def test_without_a_reset_service_a_reset_waits_for_the_operators_goal(
        domain: int, start_sim, arena: Path, ros_client) -> None:
    """A real robot's shape: no sim node, no reset service, rate stepping against a sim
    running in real time. Each reset waits for the operator's next goal (here the operator
    calls the sim's reset_world from another node a second later, which publishes a new goal);
    steps move the robot."""
    start_sim(domain, "--params-file", str(ROOT / "config/env_goto_lidar.yaml"),
              "-p", f"world:={arena}", "-p", "clock_mode:=realtime",
              "-p", "real_time_factor:=2.0")
    operator = ros_client(domain)
    env = gym.make("pic4rl/GoToPoseLidar-v0", config=ROOT / "config/env_goto_lidar.yaml",
                   transport="ros", sim={"world": str(arena)},
                   overrides={"ros.domain_id": domain, "ros.sim_node": "",
                              "ros.reset_service": "", "ros.step_mode": "rate",
                              "ros.operator_timeout_s": 20.0, "topics.pose": "ground_truth"})

    def reset_by_operator(**kwargs: object) -> dict:
        timer = threading.Timer(1.0, operator.call, args=(Empty, "/reset_world"))
        timer.start()
        try:
            return env.reset(**kwargs)[1]
        finally:
            timer.join()

    try:
        first = reset_by_operator(seed=3)
        start = env.unwrapped.frame.pose
        for _ in range(5):
            env.step(np.array([1.0, 0.0], dtype=np.float32))
        moved = env.unwrapped.frame.pose
        assert math.hypot(moved.x - start.x, moved.y - start.y) > 0.05
        second = reset_by_operator()
        assert second["goal"] != first["goal"]
    finally:
        env.close()


def test_twist_stamped_commands(domain: int, ros_client) -> None:
    """``ros.cmd_vel_type: TwistStamped`` publishes stamped commands on the configured topic
    (for robots whose drivers want them)."""
    from geometry_msgs.msg import TwistStamped
    from pic4rl_sim.engine.geometry import Twist2D

    from pic4rl_bridge.config import load_env_config
    from pic4rl_bridge.scenario import Scenario
    from pic4rl_bridge.transports.ros_transport import RosTransport

    config = load_env_config(ROOT / "config/env_goto_lidar.yaml").replace(
        **{"ros.domain_id": domain, "ros.cmd_vel_type": "TwistStamped",
           "topics.cmd_vel": "base/cmd_vel", "transport": "ros"})
    client = ros_client(domain)
    inbox = []
    client.node.create_subscription(TwistStamped, "/base/cmd_vel", inbox.append, 10)
    transport = RosTransport(config, Scenario(config), frozenset({"scan"}))
    try:
        assert client.spin_until(lambda: transport._cmd_pub.get_subscription_count() > 0)
        transport.step_command(Twist2D(0.3, 0.0, -0.2))
        assert client.spin_until(lambda: len(inbox) > 0)
    finally:
        transport.close()
    assert inbox[0].twist.linear.x == pytest.approx(0.3)
    assert inbox[0].twist.angular.z == pytest.approx(-0.2)


def test_the_plan_is_published_recorded_and_observed_alike(domain: int, start_sim,
                                                            tmp_path: Path) -> None:
    """``goal_input: plan``: the sim node's ``plan`` reaches the ROS env's frame as the engine's
    plan reaches the in-process one (bit-identical observations through both), and each bag
    holds it as a ``nav_msgs/Path`` at the episode's first stamp."""
    from pic4rl_bridge.recording import make_env
    from pic4rl_metrics.contract import typestore

    config = ROOT / CONFIGS["pic4rl/GoToPoseLidar-v0"]
    start_sim(domain, "--params-file", str(config))
    common = {"goal_input": "plan", "episode_max_steps": 30, "record.enabled": True}
    ros = make_env(config, transport="ros", overrides={
        **common, "ros.domain_id": domain, "record.bags_dir": str(tmp_path), "record.run": "ros"})
    local = make_env(config, overrides={**common, "record.bags_dir": str(tmp_path),
                                        "record.run": "local"})
    rng = np.random.default_rng(3)
    plans = []
    try:
        for episode in range(2):
            seed = 5 if episode == 0 else None
            (obs_r, _), (obs_l, _) = ros.reset(seed=seed), local.reset(seed=seed)
            assert ros.unwrapped.frame.plan is not None and len(ros.unwrapped.frame.plan) >= 2
            assert np.array_equal(ros.unwrapped.frame.plan, local.unwrapped.frame.plan)
            assert np.allclose(ros.unwrapped.frame.plan[-1], ros.unwrapped.frame.goal)
            plans.append(ros.unwrapped.frame.plan)
            assert np.array_equal(obs_r, obs_l)
            done = False
            while not done:
                action = rng.uniform(-1, 1, 2).astype(np.float32)
                out_r, out_l = ros.step(action), local.step(action)
                assert np.array_equal(out_r[0], out_l[0])
                done = out_r[2] or out_r[3]
    finally:
        ros.close()
        local.close()
    store = typestore()
    for run in ("ros", "local"):
        bags = sorted((tmp_path / run).glob("episode_*"))
        assert len(bags) == 2
        for bag, plan in zip(bags, plans):
            with Reader(bag) as reader:
                found = [(c, t, d) for c, t, d in reader.messages() if c.topic == "/plan"]
                first = min(t for _, t, _ in reader.messages())
            assert len(found) == 1 and found[0][1] == first
            msg = store.deserialize_cdr(found[0][2], found[0][0].msgtype)
            points = np.array([(p.pose.position.x, p.pose.position.y) for p in msg.poses])
            assert np.array_equal(points, plan)
