"""The ``sim`` node as a real process: its interfaces, both clocks, episodes, pause, bad input,
namespaces, parameter files. Most tests share one lockstep sim in a small MJCF arena (see
conftest), each starting from a state it sets itself."""

from __future__ import annotations

import math
import sys
import time
from pathlib import Path

import pytest
from geometry_msgs.msg import PoseStamped, Twist
from nav_msgs.msg import Odometry
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy, qos_profile_sensor_data
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import CameraInfo, Image, LaserScan
from std_srvs.srv import Empty
from visualization_msgs.msg import Marker, MarkerArray

pytestmark = pytest.mark.integration

CONFIG_DIR = Path(__file__).resolve().parents[3] / "config"
CONTROL_DT_NS = 100_000_000  # the default control_dt_s
LATCHED = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE,
                     durability=DurabilityPolicy.TRANSIENT_LOCAL)
# A step at rest ramps up at the Jackal's 3 m/s² limit: 0.5 m/s is reached after 1/6 s,
# losing v²/(2a) of distance against a constant speed.
RAMP_LOSS_M = 0.5**2 / (2 * 3.0)


def sim_command(*ros_args: str) -> list[str]:
    return [sys.executable, "-m", "pic4rl_sim.node", "--ros-args", *ros_args]


def stamp_ns(stamp) -> int:
    return stamp.sec * 1_000_000_000 + stamp.nanosec


def twist(vx: float = 0.0, vy: float = 0.0, wz: float = 0.0) -> Twist:
    msg = Twist()
    msg.linear.x, msg.linear.y, msg.angular.z = vx, vy, wz
    return msg


class Stepper:
    """Drives a lockstep sim one ``cmd_vel`` at a time, waiting for each step's clock."""

    def __init__(self, client, prefix: str = "") -> None:
        self.client = client
        self.clock = client.collect(f"{prefix}/clock", Clock)
        self.pub = client.node.create_publisher(Twist, f"{prefix}/cmd_vel", 10)
        assert client.spin_until(lambda: self.pub.get_subscription_count() > 0), "no sim"
        client.spin_for(0.2)  # the sim's side of the match

    @property
    def now_ns(self) -> int:
        return stamp_ns(self.clock[-1].clock)

    def step(self, command: Twist, n: int = 1) -> None:
        for _ in range(n):
            want = len(self.clock) + 1
            self.pub.publish(command)
            assert self.client.spin_until(lambda w=want: len(self.clock) >= w, 5.0), "no step"


def reset_to(client, start: list[float], goal: list[float]) -> None:
    results = client.set_parameters("/sim", {"start_pose": start, "goal": goal})
    assert all(r.successful for r in results), [r.reason for r in results]
    client.call(Empty, "/reset_world")


def latest_at(client, inbox: list, t_ns: int, timeout_s: float = 5.0):
    """The message of ``inbox`` stamped ``t_ns``, waiting for it."""
    def found() -> bool:
        return any(stamp_ns(m.header.stamp) == t_ns for m in inbox)
    assert client.spin_until(found, timeout_s), f"no message stamped {t_ns}"
    return next(m for m in reversed(inbox) if stamp_ns(m.header.stamp) == t_ns)


def test_the_node_has_exactly_the_design_interfaces(shared_sim):
    node = shared_sim.client.node
    publishers = {
        "/clock": "rosgraph_msgs/msg/Clock", "/ground_truth": "nav_msgs/msg/Odometry",
        "/odom": "nav_msgs/msg/Odometry", "/imu/data": "sensor_msgs/msg/Imu",
        "/tf": "tf2_msgs/msg/TFMessage", "/tf_static": "tf2_msgs/msg/TFMessage",
        "/scan": "sensor_msgs/msg/LaserScan", "/goal_pose": "geometry_msgs/msg/PoseStamped",
        "/plan": "nav_msgs/msg/Path", "/world/markers": "visualization_msgs/msg/MarkerArray",
        "/diagnostics": "diagnostic_msgs/msg/DiagnosticArray",
        "/parameter_events": "rcl_interfaces/msg/ParameterEvent",
        "/rosout": "rcl_interfaces/msg/Log",
    }
    services = dict.fromkeys(("/reset_world", "/pause_physics", "/unpause_physics"),
                             "std_srvs/srv/Empty")

    def graph() -> tuple[dict, dict, dict]:
        pubs = dict(node.get_publisher_names_and_types_by_node("sim", "/"))
        subs = dict(node.get_subscriber_names_and_types_by_node("sim", "/"))
        srvs = dict(node.get_service_names_and_types_by_node("sim", "/"))
        return pubs, subs, srvs

    def complete() -> bool:
        if "sim" not in node.get_node_names():
            return False
        pubs, subs, srvs = graph()
        return set(publishers) <= set(pubs) and "/cmd_vel" in subs and set(services) <= set(srvs)

    assert shared_sim.client.spin_until(complete, 20.0)
    pubs, subs, srvs = graph()
    # A LiDAR robot in a world without a person: no camera or person topics.
    assert {k: v[0] for k, v in pubs.items()} == publishers
    assert {k: v[0] for k, v in subs.items()} == {"/cmd_vel": "geometry_msgs/msg/Twist"}
    assert {k: v[0] for k, v in srvs.items() if k in services} == services


def test_lockstep_commands_advance_time_and_move_the_robot(shared_sim):
    client = shared_sim.client
    stepper = Stepper(client)
    truth = client.collect("/ground_truth", Odometry)
    odom = client.collect("/odom", Odometry)
    scans = client.collect("/scan", LaserScan, qos_profile_sensor_data)
    reset_to(client, [-2.0, 0.0, 0.0], [3.0, -3.0])
    assert client.spin_until(lambda: len(stepper.clock) > 0)
    t0 = stepper.now_ns
    start = latest_at(client, truth, t0).pose.pose.position
    assert (start.x, start.y) == pytest.approx((-2.0, 0.0), abs=1e-6)

    n = 20
    stepper.step(twist(0.5), n)
    t_end = stepper.now_ns
    assert t_end - t0 == n * CONTROL_DT_NS
    assert [stamp_ns(c.clock) for c in stepper.clock][-n:] == [
        t0 + (i + 1) * CONTROL_DT_NS for i in range(n)]
    end = latest_at(client, truth, t_end).pose.pose.position
    # Tolerance 1 cm: the servo's lag beyond the ideal ramp.
    assert end.x - start.x == pytest.approx(n * 0.1 * 0.5 - RAMP_LOSS_M, abs=0.01)
    assert end.y == pytest.approx(0.0, abs=1e-3)
    assert latest_at(client, odom, t_end).pose.pose.position.x == pytest.approx(end.x, abs=1e-6)
    latest_at(client, scans, t_end)  # the scan of the last step, stamped with its clock
    clock_stamps = {stamp_ns(c.clock) for c in stepper.clock}
    for inbox in (truth, odom, scans):
        assert {stamp_ns(m.header.stamp) for m in inbox} <= clock_stamps


def test_reset_world_starts_a_new_episode_after_everything_before(shared_sim):
    client = shared_sim.client
    stepper = Stepper(client)
    goals = client.collect("/goal_pose", PoseStamped, LATCHED)
    markers = client.collect("/world/markers", MarkerArray, LATCHED)
    truth = client.collect("/ground_truth", Odometry)
    stepper.step(twist(1.0, 0.0, 0.5), 5)
    before = max(stamp_ns(c.clock) for c in stepper.clock)

    reset_to(client, [1.0, -2.0, 1.5], [-3.0, -3.0])
    assert client.spin_until(lambda: goals and goals[-1].pose.position.x == -3.0)
    t0 = stamp_ns(goals[-1].header.stamp)
    assert t0 == before + CONTROL_DT_NS  # strictly after everything of the last episode
    assert goals[-1].header.frame_id == "world"
    assert (goals[-1].pose.position.x, goals[-1].pose.position.y) == (-3.0, -3.0)
    first = latest_at(client, truth, t0)
    pose, vel = first.pose.pose, first.twist.twist
    assert (pose.position.x, pose.position.y) == pytest.approx((1.0, -2.0), abs=1e-9)
    assert (pose.orientation.z, pose.orientation.w) == pytest.approx(
        (math.sin(0.75), math.cos(0.75)))
    assert (vel.linear.x, vel.angular.z) == (0.0, 0.0)
    assert (first.header.frame_id, first.child_frame_id) == ("world", "base_link")

    assert client.spin_until(lambda: markers and any(
        m.ns == "goal" and m.pose.position.x == -3.0 for m in markers[-1].markers))
    shapes = [m.type for m in markers[-1].markers if m.action == Marker.ADD]
    assert shapes.count(Marker.CUBE) == 5  # four walls and the crate
    assert shapes.count(Marker.CYLINDER) == 2  # the post and the goal


def test_episodes_follow_the_seed_and_sensor_changes_rebuild_the_engine(shared_sim):
    client = shared_sim.client
    goals = client.collect("/goal_pose", PoseStamped, LATCHED)
    scans = client.collect("/scan", LaserScan, qos_profile_sensor_data)

    def reset(values: dict) -> tuple[float, float]:
        n = len(goals)
        results = client.set_parameters("/sim", values) if values else []
        assert all(r.successful for r in results), [r.reason for r in results]
        client.call(Empty, "/reset_world")
        assert client.spin_until(lambda: len(goals) > n)
        return goals[-1].pose.position.x, goals[-1].pose.position.y

    first = reset({"seed": 5})
    assert reset({}) != first  # no new seed: the previous episode's seed + 1
    assert reset({"seed": 5}) == first  # the same seed, set again: the same episode
    try:
        reset({"lidar.beams": 90})
        t0 = stamp_ns(goals[-1].header.stamp)
        assert len(latest_at(client, scans, t0).ranges) == 90
    finally:
        reset({"lidar.beams": 360})


def test_parameter_changes_are_checked_before_they_are_accepted(shared_sim):
    client = shared_sim.client
    cases = {
        "start_pose": [3.0, 3.0, 0.0],  # inside the crate
        "goal": [1.0],
        "clock_mode": "fast",
        "world": "indor",
        "control_dt_s": -1.0,
    }
    for key, value in cases.items():
        (result,) = client.set_parameters("/sim", {key: value})
        assert not result.successful, key
        assert key in result.reason
    (result,) = client.set_parameters("/sim", {"start_pose": [math.nan, 0.0, 0.0]})
    assert not result.successful and "start_pose" in result.reason
    (result,) = client.set_parameters("/sim", {"world": "indor"})
    assert "did you mean 'indoor'" in result.reason


def test_pause_stops_time_and_unpause_resumes_it(shared_sim):
    client = shared_sim.client
    stepper = Stepper(client)
    stepper.step(twist())
    t = stepper.now_ns
    client.call(Empty, "/pause_physics")
    for _ in range(3):
        stepper.pub.publish(twist(0.5))
    client.spin_for(0.5)
    assert stepper.now_ns == t
    assert client.spin_until(lambda: "paused" in shared_sim.sim.output, 2.0)
    client.call(Empty, "/unpause_physics")
    stepper.step(twist())
    assert stepper.now_ns == t + CONTROL_DT_NS  # the dropped commands left no steps behind


def test_nan_and_absurd_commands_step_safely_with_a_warning(shared_sim):
    client = shared_sim.client
    stepper = Stepper(client)
    truth = client.collect("/ground_truth", Odometry)
    reset_to(client, [-2.0, 0.0, 0.0], [3.0, -3.0])
    assert client.spin_until(lambda: len(stepper.clock) > 0)
    t = stepper.now_ns
    stepper.step(twist(math.nan, math.inf, -math.inf))
    stepper.step(twist(1e9, 1e9, -1e9), 5)
    assert stepper.now_ns > t
    last = latest_at(client, truth, stepper.now_ns)
    values = [last.pose.pose.position.x, last.pose.pose.position.y,
              last.twist.twist.linear.x, last.twist.twist.angular.z]
    assert all(math.isfinite(v) for v in values)
    assert abs(last.twist.twist.linear.x) <= 2.0 + 1e-6  # the Jackal's limits
    assert abs(last.twist.twist.angular.z) <= 4.0 + 1e-6
    assert client.spin_until(lambda: "non-finite command" in shared_sim.sim.output, 2.0)
    assert shared_sim.sim.proc.poll() is None


def test_realtime_clock_follows_the_real_time_factor(shared_sim):
    client = shared_sim.client
    clock = client.collect("/clock", Clock)
    truth = client.collect("/ground_truth", Odometry)
    factor = 4.0
    results = client.set_parameters("/sim", {"clock_mode": "realtime",
                                             "real_time_factor": factor})
    assert all(r.successful for r in results)
    pub = client.node.create_publisher(Twist, "/cmd_vel", 10)
    try:
        assert client.spin_until(lambda: pub.get_subscription_count() > 0 and len(clock) > 2)
        pub.publish(twist(1.0))
        sim0, wall0 = stamp_ns(clock[-1].clock), time.monotonic()
        client.spin_for(1.5)
        sim1, wall1 = stamp_ns(clock[-1].clock), time.monotonic()
    finally:
        client.node.destroy_publisher(pub)
    # Loose: timers on a busy 2-core machine run late, never early.
    assert (sim1 - sim0) * 1e-9 / (wall1 - wall0) == pytest.approx(factor, rel=0.35)
    # The command is 6 s of sim time old: replaced by a stop after cmd_timeout_s (0.5 s).
    assert abs(truth[-1].twist.twist.linear.x) < 0.01

    client.call(Empty, "/pause_physics")
    client.spin_for(0.2)
    n = len(clock)
    client.spin_for(0.5)
    assert len(clock) == n  # paused: the timer does not step
    client.call(Empty, "/unpause_physics")
    assert client.spin_until(lambda: len(clock) > n + 2, 2.0)

    (result,) = client.set_parameters("/sim", {"clock_mode": "lockstep"})
    assert result.successful
    client.spin_for(0.2)
    n = len(clock)
    client.spin_for(0.5)
    assert len(clock) == n  # lockstep again: no command, no time


def test_two_namespaced_sims_run_side_by_side(start_sim, ros_client, domain, arena_mjcf):
    for ns in ("robot1", "robot2"):
        start_sim(sim_command("-r", f"__ns:=/{ns}", "-p", f"world:={arena_mjcf}",
                              "-p", "start_pose:=[-2.0, 0.0, 0.0]", "-p", "goal:=[3.0, -3.0]"),
                  domain)
    client = ros_client(domain)
    robot1, robot2 = Stepper(client, "/robot1"), Stepper(client, "/robot2")
    truth1 = client.collect("/robot1/ground_truth", Odometry)
    truth2 = client.collect("/robot2/ground_truth", Odometry)
    robot1.step(twist(0.5), 10)
    client.spin_for(0.3)
    assert robot1.now_ns == 10 * CONTROL_DT_NS
    assert latest_at(client, truth1, robot1.now_ns).pose.pose.position.x > -2.0 + 0.3
    assert not robot2.clock and not truth2  # robot2 did not step
    robot2.step(twist())
    assert robot2.now_ns == CONTROL_DT_NS
    assert latest_at(client, truth2, CONTROL_DT_NS).pose.pose.position.x == pytest.approx(-2.0)


@pytest.mark.bad_input
@pytest.mark.parametrize(("line", "expected"), [
    ("lidar.beems: 3", "unknown key 'lidar.beems'; did you mean 'lidar.beams'?"),
    ("control_dt_s: -1", "control_dt_s: -1.0 is invalid"),
    ("lidar.beams: many", "lidar.beams: 'many' is invalid"),
])
def test_a_bad_params_file_stops_the_node_with_one_line(start_sim, domain, tmp_path, arena_mjcf,
                                                        line, expected):
    params = tmp_path / "bad.yaml"
    params.write_text(f"/**:\n  ros__parameters:\n    world: {arena_mjcf}\n    {line}\n")
    sim = start_sim(sim_command("--params-file", str(params)), domain)
    assert sim.wait(60) == 2
    assert expected in sim.output
    assert "Traceback" not in sim.output
    assert len(sim.output.strip().splitlines()) == 1


@pytest.mark.bad_input
@pytest.mark.parametrize(("rule", "expected"), [
    ("lidar.beams:=abc", "lidar.beams: 'abc' is invalid; expected an integer"),
    ("lidar.beams:=2.5", "lidar.beams: 2.5 is invalid; expected an integer"),
    ("seed:=abc", "seed: 'abc' is invalid; expected an integer"),
])
@pytest.mark.parametrize("with_file", [True, False])
def test_a_wrong_typed_rule_is_refused_whether_or_not_a_params_file_sets_it(
        start_sim, domain, tmp_path, arena_mjcf, rule, expected, with_file):
    """rcl silently drops a ``-p`` whose type differs from the file's value for that key."""
    params = tmp_path / "sim.yaml"
    params.write_text(f"/**:\n  ros__parameters:\n    world: {arena_mjcf}\n    seed: 3\n"
                      "    lidar.beams: 90\n")
    files = ["--params-file", str(params)] if with_file else ["-p", f"world:={arena_mjcf}"]
    sim = start_sim(sim_command(*files, "-p", rule), domain)
    assert sim.wait(60) == 2
    assert sim.output.strip() == f"pic4rl-sim: {expected}"


def test_every_config_file_starts_and_publishes_its_main_sensor(start_sim, ros_client, domain):
    main_sensor = {
        "sim_indoor_jackal.yaml": ("scan", LaserScan),
        "sim_indoor_jackal_depth.yaml": ("camera/depth/image_raw", Image),
        "sim_vineyard_jackal_depth.yaml": ("camera/depth/image_raw", Image),
        "sim_person_omni.yaml": ("scan", LaserScan),
    }
    for i, name in enumerate(main_sensor):
        start_sim(sim_command("-r", f"__ns:=/cfg{i}", "--params-file", str(CONFIG_DIR / name)),
                  domain)
    client = ros_client(domain)
    for i, (topic, msg_type) in enumerate(main_sensor.values()):
        inbox = client.collect(f"/cfg{i}/{topic}", msg_type, qos_profile_sensor_data, 30.0)
        stepper = Stepper(client, f"/cfg{i}")
        stepper.step(twist(0.2))
        msg = latest_at(client, inbox, stepper.now_ns)
        if msg_type is Image:
            assert (msg.encoding, msg.width, msg.height) == ("32FC1", 80, 60)
            assert len(msg.data) == 4 * 80 * 60
        else:
            assert len(msg.ranges) == 360
    info = client.collect("/cfg1/camera/depth/camera_info", CameraInfo, qos_profile_sensor_data)
    person = client.collect("/cfg3/person/pose", PoseStamped)
    Stepper(client, "/cfg1").step(twist())
    Stepper(client, "/cfg3").step(twist())
    assert client.spin_until(lambda: info and person)
    assert (info[-1].width, info[-1].height) == (80, 60) and info[-1].k[0] > 0
    assert person[-1].header.frame_id == "world"
