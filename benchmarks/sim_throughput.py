"""Control steps per second of the simulator: engine, bare MuJoCo, and lockstep through ROS 2.

One run, one model (Jackal in the seeded ``indoor`` world, 360-beam LiDAR, 10 Hz control,
5 ms physics), three loops:

- bare: ``mj_step`` × substeps + one ``mj_multiRay`` of 360 beams — the floor under any
  MuJoCo simulator of this robot;
- engine: ``Engine.step`` + ``Engine.scan`` + ``Engine.wheel_odometry`` — what the node does
  per step, in-process;
- ROS 2 lockstep: the ``sim`` node in another process; this process publishes ``cmd_vel``
  and waits for the step's ``scan`` and ``odom``.

Bare and engine run interleaved (best of ``--repeat``); the ROS loop runs after them. The
real-time factor is simulated seconds per wall second. The last lines are
``RESULT <name> <value>``, one per figure, for ``docs/performance.md``; the CPU per lockstep
step of the node and of this client move less with a shared machine's load than the rates.

    .venv/bin/python benchmarks/sim_throughput.py
"""

from __future__ import annotations

import argparse
import math
import random
import sys
import time
from collections.abc import Callable

import mujoco
import numpy as np
from _sim import cpu_s, start_sim, stop_sim

from pic4rl_sim.engine.core import Engine, EngineConfig
from pic4rl_sim.engine.geometry import Twist2D
from pic4rl_sim.engine.robot_specs import JACKAL, LidarSpec
from pic4rl_sim.engine.worlds.generators import make_world

CONTROL_DT_S = 0.1
PHYSICS_DT_S = 0.005
BEAMS = 360
WORLD = "indoor"
SEED = 0


def make_engine() -> Engine:
    robot = JACKAL.with_sensors(lidar=LidarSpec(beams=BEAMS, mount_xyz_m=(0.12, 0.0, 0.3)))
    config = EngineConfig(physics_dt_s=PHYSICS_DT_S, control_dt_s=CONTROL_DT_S)
    return Engine(robot, make_world(WORLD, seed=SEED), config, seed=SEED)


def commands(n: int) -> list[Twist2D]:
    """Gentle random commands: the robot wanders and bumps into things like an early policy."""
    rng = np.random.default_rng(SEED)
    return [Twist2D(float(v), 0.0, float(w))
            for v, w in zip(rng.uniform(-0.3, 0.8, n), rng.uniform(-1.0, 1.0, n))]


def engine_loop(steps: int) -> float:
    """Seconds for ``steps`` engine control steps with a scan and odometry each."""
    engine = make_engine()
    cmds = commands(steps)
    start = time.perf_counter()
    for cmd in cmds:
        engine.step(cmd)
        engine.scan()
        engine.wheel_odometry()
    return time.perf_counter() - start


def bare_loop(steps: int) -> float:
    """Seconds for ``steps`` of bare ``mj_step`` × substeps + one 360-ray ``mj_multiRay``."""
    engine = make_engine()  # the same compiled model, robot and world
    model, data, ids = engine.model, mujoco.MjData(engine.model), engine.ids
    data.qpos[[ids.qpos_x, ids.qpos_y, ids.qpos_yaw]] = engine.start
    angles = np.arange(BEAMS) * (2 * math.pi / BEAMS) - math.pi
    vec = np.zeros((BEAMS, 3))
    geomid = np.zeros(BEAMS, dtype=np.int32)
    dist = np.zeros(BEAMS)
    substeps = engine.config.substeps
    cmds = commands(steps)
    start = time.perf_counter()
    for cmd in cmds:
        data.ctrl[ids.act_vx], data.ctrl[ids.act_wz] = cmd.vx, cmd.wz
        mujoco.mj_step(model, data, nstep=substeps)
        x, y, yaw = data.qpos[ids.qpos_x], data.qpos[ids.qpos_y], data.qpos[ids.qpos_yaw]
        vec[:, 0] = np.cos(angles + yaw)
        vec[:, 1] = np.sin(angles + yaw)
        mujoco.mj_multiRay(model, data, np.array([x, y, 0.3]), vec.ravel(), None, 1,
                           ids.robot_body, geomid, dist, None, BEAMS, 10.0)
    return time.perf_counter() - start


def best_of(repeat: int, loops: dict[str, Callable[[int], float]], steps: int) -> dict[str, float]:
    """Best (shortest) seconds of each loop, run interleaved so drift hits all alike."""
    best = {name: math.inf for name in loops}
    for _ in range(repeat):
        for name, loop in loops.items():
            best[name] = min(best[name], loop(steps))
    return best


def ros_lockstep(steps: int, timeout_s: float) -> tuple[float, int, float, float]:
    """Seconds for ``steps`` lockstep steps through a ``sim`` node in another process, the
    number of steps whose scan or odometry never came (best-effort QoS may drop), and the CPU
    seconds of this client and of the node over those steps."""
    import rclpy
    from geometry_msgs.msg import Twist
    from nav_msgs.msg import Odometry
    from rclpy.experimental import EventsExecutor
    from rclpy.qos import qos_profile_sensor_data
    from sensor_msgs.msg import LaserScan

    domain = random.randint(1, 100)
    sim = start_sim(domain, "-p", f"world:={WORLD}", "-p", f"world_variant:={SEED}",
                    "-p", "robot:=jackal", "-p", "clock_mode:=lockstep",
                    "-p", f"lidar.beams:={BEAMS}", "-p", f"control_dt_s:={CONTROL_DT_S}",
                    "-p", f"physics_dt_s:={PHYSICS_DT_S}", "-p", "depth.enabled:=false",
                    "-p", f"seed:={SEED}")
    context = rclpy.Context()
    rclpy.init(context=context, domain_id=domain)
    try:
        node = rclpy.create_node("sim_throughput", context=context)
        executor = EventsExecutor(context=context)
        executor.add_node(node)
        latest = {"scan": -1, "odom": -1}

        def stamp_of(key: str) -> Callable[[object], None]:
            def store(msg) -> None:  # type: ignore[no-untyped-def]
                latest[key] = msg.header.stamp.sec * 10**9 + msg.header.stamp.nanosec
            return store

        node.create_subscription(LaserScan, "scan", stamp_of("scan"), qos_profile_sensor_data)
        node.create_subscription(Odometry, "odom", stamp_of("odom"), 10)
        cmd_vel = node.create_publisher(Twist, "cmd_vel", 10)
        deadline = time.monotonic() + 60.0
        while cmd_vel.get_subscription_count() == 0 or node.count_publishers("scan") == 0:
            if sim.poll() is not None or time.monotonic() > deadline:
                raise RuntimeError(f"the sim did not come up: {sim.stderr.read().decode()}")
            executor.spin_once(timeout_sec=0.1)
        time.sleep(0.5)  # let discovery settle both ways
        msg = Twist()

        def run(n: int) -> int:
            missed = 0
            for cmd in commands(n):
                before = (latest["scan"], latest["odom"])
                msg.linear.x, msg.angular.z = cmd.vx, cmd.wz
                cmd_vel.publish(msg)
                until = time.monotonic() + timeout_s
                while latest["scan"] == before[0] or latest["odom"] == before[1]:
                    executor.spin_once(timeout_sec=timeout_s)
                    if time.monotonic() > until:
                        missed += 1
                        break
            return missed

        run(100)  # warm up both processes
        own, node_cpu = time.process_time(), cpu_s(sim.pid)
        start = time.perf_counter()
        missed = run(steps)
        seconds = time.perf_counter() - start
        return (seconds, missed, time.process_time() - own, cpu_s(sim.pid) - node_cpu)
    finally:
        rclpy.shutdown(context=context)
        stop_sim(sim)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=2000, help="control steps per loop")
    parser.add_argument("--repeat", type=int, default=5, help="runs of bare and engine loops")
    parser.add_argument("--timeout", type=float, default=1.0, help="s to wait for one step")
    args = parser.parse_args(argv)

    best = best_of(args.repeat, {"bare": bare_loop, "engine": engine_loop}, args.steps)
    ros_s, missed, client_cpu_s, node_cpu_s = ros_lockstep(args.steps, args.timeout)
    rate = {name: args.steps / seconds for name, seconds in best.items()}
    rate["ros"] = args.steps / ros_s
    print(f"model: jackal in {WORLD} (seed {SEED}), {BEAMS}-beam LiDAR, "
          f"control {CONTROL_DT_S} s, physics {PHYSICS_DT_S} s; {args.steps} steps per loop")
    for name, label in (("bare", "bare mj_step + mj_multiRay"), ("engine", "engine in-process"),
                        ("ros", "ROS 2 lockstep (cmd_vel -> scan + odom)")):
        print(f"  {label:42s} {rate[name]:9.0f} steps/s   "
              f"real-time factor {rate[name] * CONTROL_DT_S:7.0f}")
    if missed:
        print(f"  ROS 2 lockstep: {missed} of {args.steps} steps lost a message (best effort)")
    print(f"RESULT sim_engine_steps_per_s {rate['engine']:.0f}")
    print(f"RESULT sim_bare_steps_per_s {rate['bare']:.0f}")
    print(f"RESULT sim_engine_vs_bare_ratio {rate['engine'] / rate['bare']:.2f}")
    print(f"RESULT sim_ros_lockstep_steps_per_s {rate['ros']:.0f}")
    print(f"RESULT sim_ros_vs_engine_ratio {rate['ros'] / rate['engine']:.2f}")
    print(f"RESULT sim_ros_real_time_factor {rate['ros'] * CONTROL_DT_S:.0f}")
    print(f"RESULT sim_ros_lost_steps {missed}")
    print(f"RESULT sim_ros_node_cpu_us_per_step {1e6 * node_cpu_s / args.steps:.0f}")
    print(f"RESULT sim_ros_client_cpu_us_per_step {1e6 * client_cpu_s / args.steps:.0f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
