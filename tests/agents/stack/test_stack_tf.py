"""TF as a tf2 user sees it during ``pic4rl-run stack`` (lockstep): a separate plain rclpy
process, importing nothing of this project, keeps a tf2-style buffer of ``/tf`` (by stamp) and
``/tf_static``, and for each scan looks up ``odom → base_link`` at the scan's stamp and composes
it with ``base_link → <the scan's frame>``. It runs beside the example node, both started by the
stack's command (a launcher, as a launch file would), in the run's ROS domain."""

from __future__ import annotations

import json
import math
import sys
from pathlib import Path

import pytest
import yaml

from pic4rl_sim.engine.robot_specs import load_robot

REPO = Path(__file__).resolve().parents[3]
PAIRS = REPO / "pic4rl_agents" / "data" / "goals_indoor_test.json"
NODE = REPO / "examples" / "ros_gap_follower_node.py"

CONSUMER = '''
import json, math, os, sys, time
import rclpy
from nav_msgs.msg import Odometry
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy, qos_profile_sensor_data
from sensor_msgs.msg import LaserScan
from tf2_msgs.msg import TFMessage

def ns(stamp): return stamp.sec * 10**9 + stamp.nanosec
def mul(a, b):
    ax, ay, az, aw = a; bx, by, bz, bw = b
    return (aw*bx + ax*bw + ay*bz - az*by, aw*by - ax*bz + ay*bw + az*bx,
            aw*bz + ax*by - ay*bx + az*bw, aw*bw - ax*bx - ay*by - az*bz)
def rotate(q, v):
    x, y, z, _ = mul(mul(q, (*v, 0.0)), (-q[0], -q[1], -q[2], q[3]))
    return (x, y, z)
def compose(a, b):  # parent->mid then mid->child: parent->child
    (ta, qa), (tb, qb) = a, b
    r = rotate(qa, tb)
    return (tuple(p + d for p, d in zip(ta, r)), mul(qa, qb))
def pose(t):
    return ((t.translation.x, t.translation.y, t.translation.z),
            (t.rotation.x, t.rotation.y, t.rotation.z, t.rotation.w))

rclpy.init()
node = rclpy.create_node("tf2_style_consumer")
dynamic, static, odoms = {}, {}, {}  # (parent, child) -> {stamp: pose}; (parent, child) -> pose
out = {"scans": 0, "found": 0, "static": [], "composed": [], "odom_vs_tf_m": 0.0, "odoms": 0}
def on_tf(msg, into_static=False):
    for t in msg.transforms:
        key = (t.header.frame_id, t.child_frame_id)
        if into_static:
            static[key] = pose(t.transform)
        else:
            dynamic.setdefault(key, {})[ns(t.header.stamp)] = pose(t.transform)
def on_odom(msg):
    p = msg.pose.pose.position
    odoms[ns(msg.header.stamp)] = (msg.header.frame_id, msg.child_frame_id, (p.x, p.y, p.z))
pending = []  # scans waiting for their stamp's transforms
def on_scan(msg):
    out["scans"] += 1
    pending.append((ns(msg.header.stamp), msg.header.frame_id))
def resolve(stamp, sensor):
    """lookupTransform(odom, sensor, stamp): False until every transform it needs is here."""
    mount = next(((parent, p) for (parent, child), p in static.items() if child == sensor), None)
    if mount is None:
        return False
    base = mount[0]
    at = next((((parent, stamps[stamp]) for (parent, child), stamps in dynamic.items()
                if child == base and stamp in stamps)), None)
    if at is None:
        return False
    (frame, at), found = at, out["found"] + 1
    (x, y, z), q = compose(at, mount[1])
    if stamp in odoms:  # the tf's pose against the odometry message's of that stamp
        out["odoms"] += 1
        gap = math.dist(at[0], odoms[stamp][2])
        out["odom_vs_tf_m"] = max(out["odom_vs_tf_m"], gap)
    out["found"] = found
    out["composed"].append([frame, base, sensor, x, y, z, *q, *at[0], *at[1]])
    out["static"] = sorted([p, c, *t] for (p, c), (t, _) in static.items())
    return True
def write():
    tmp = sys.argv[1] + ".tmp"
    with open(tmp, "w") as f:
        json.dump(out, f)
    os.replace(tmp, sys.argv[1])
latched = QoSProfile(depth=100, reliability=ReliabilityPolicy.RELIABLE,
                     durability=DurabilityPolicy.TRANSIENT_LOCAL)  # as tf2's static listener
node.create_subscription(TFMessage, "/tf", on_tf, QoSProfile(depth=100))
node.create_subscription(TFMessage, "/tf_static", lambda m: on_tf(m, True), latched)
node.create_subscription(Odometry, "odom", on_odom, qos_profile_sensor_data)
node.create_subscription(LaserScan, "scan", on_scan, qos_profile_sensor_data)
written = time.monotonic()
try:  # until the run stops the stack's process group (SIGINT)
    while rclpy.ok():
        rclpy.spin_once(node, timeout_sec=0.1)
        pending[:] = [(stamp, sensor) for stamp, sensor in pending if not resolve(stamp, sensor)]
        if time.monotonic() > written + 0.5:
            write()
            written = time.monotonic()
except KeyboardInterrupt:
    pass
finally:
    write()
'''

LAUNCHER = '''
import subprocess, sys
procs = [subprocess.Popen([sys.executable, arg] + rest) for arg, *rest in
         ([sys.argv[1]], [sys.argv[2], sys.argv[3]])]
sys.exit(max(p.wait() for p in procs))
'''


@pytest.mark.integration
def test_a_tf2_style_consumer_composes_odom_base_link_and_the_scans_frame(
        tmp_path: Path, domain: int, monkeypatch: pytest.MonkeyPatch,
        capfd: pytest.CaptureFixture[str]) -> None:
    from pic4rl_agents.launch import run

    (tmp_path / "consumer.py").write_text(CONSUMER)
    (tmp_path / "launch.py").write_text(LAUNCHER)
    out = tmp_path / "tf.json"
    assert "pic4rl" not in CONSUMER  # it knows the topics and frames only
    env = tmp_path / "env.yaml"
    env.write_text(yaml.safe_dump({
        "sim": {"ros__parameters": {"robot": "jackal", "world": "indoor", "world_variant": 0}},
        "nav_env": {"ros__parameters": {"task": "goToPose", "sensor": "lidar",
                                        "episode_max_steps": 200}}}))
    monkeypatch.setenv("ROS_DOMAIN_ID", str(domain))  # the lease takes one after it
    code = run.main(["stack", "--command", f"{sys.executable} {tmp_path / 'launch.py'} {NODE} "
                     f"{tmp_path / 'consumer.py'} {out}", "--name", "tf_stack",
                     "--params-file", str(env), "--pairs", str(PAIRS), "--episodes", "1",
                     "--bags", str(tmp_path / "bags"), "--clock", "lockstep"])
    assert code == 0, capfd.readouterr()
    assert capfd.readouterr().out.strip().splitlines()[-1] == "tf_stack episode 0: goal"

    seen = json.loads(out.read_text())
    mount = load_robot("jackal").sensors["lidar"].mount_xyz_m
    statics = {(p, c): tuple(t) for p, c, *t in seen["static"]}
    assert statics[("base_link", "laser")] == pytest.approx(mount)
    assert ("base_link", "imu_link") in statics
    # nearly every scan resolved at its own stamp (the first may come before tf is matched)
    assert seen["found"] >= 20 and seen["found"] >= 0.9 * seen["scans"], seen["found"]
    assert seen["odoms"] >= 0.5 * seen["found"]
    assert seen["odom_vs_tf_m"] < 1e-9  # tf is the odometry, stamped alike
    frames = {tuple(c[:3]) for c in seen["composed"]}
    assert frames == {("odom", "base_link", "laser")}
    for c in seen["composed"]:
        x, y, z, qx, qy, qz, qw, bx, by, bz, *base_q = c[3:]
        yaw = 2 * math.atan2(base_q[2], base_q[3])
        # the laser in odom: the base's pose, then the mount turned by the base's yaw
        assert (x, y, z) == pytest.approx(
            (bx + math.cos(yaw) * mount[0] - math.sin(yaw) * mount[1],
             by + math.sin(yaw) * mount[0] + math.cos(yaw) * mount[1], bz + mount[2]), abs=1e-9)
        assert math.hypot(qx, qy, qz, qw) == pytest.approx(1.0)
    first, last = seen["composed"][0], seen["composed"][-1]
    assert math.dist(first[3:5], last[3:5]) > 0.5  # the robot drove: not the identity
