"""Records part of an episode, then waits to be killed (test_recorder's SIGKILL test).

Usage: ``python recorder_victim.py BAGS_DIR RUN N_POSES``. Writes the facts and ``N_POSES``
Odometry messages on ``/ground_truth`` (0.5 m/s along +x, 10 Hz) with a commit after every
write, prints the bag directory and ``READY``, and sleeps without ever closing the bag.
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

from pic4rl_bridge.recorder import RunRecorder
from pic4rl_bridge.transports.transport import RawMessage
from pic4rl_metrics.contract import parse_facts, typestore

T0_NS = 1_700_000_000_000_000_000
DT_NS = 100_000_000  # 10 Hz
SPEED_MPS = 0.5
ODOMETRY = "nav_msgs/msg/Odometry"


def odometry(ns: int, x: float) -> RawMessage:
    """An Odometry at ``(x, 0)`` heading +x at ``SPEED_MPS``, stamped ``ns``."""
    t = typestore().types
    sec, nanosec = divmod(ns, 1_000_000_000)
    header = t["std_msgs/msg/Header"](t["builtin_interfaces/msg/Time"](sec, nanosec), "odom")
    pose = t["geometry_msgs/msg/Pose"](t["geometry_msgs/msg/Point"](x, 0.0, 0.0),
                                       t["geometry_msgs/msg/Quaternion"](0.0, 0.0, 0.0, 1.0))
    vec = t["geometry_msgs/msg/Vector3"]
    twist = t["geometry_msgs/msg/Twist"](vec(SPEED_MPS, 0.0, 0.0), vec(0.0, 0.0, 0.0))
    msg = t[ODOMETRY](
        header, "base_link",
        t["geometry_msgs/msg/PoseWithCovariance"](pose, np.zeros(36)),
        t["geometry_msgs/msg/TwistWithCovariance"](twist, np.zeros(36)),
    )
    return RawMessage("/ground_truth", ODOMETRY, bytes(typestore().serialize_cdr(msg, ODOMETRY)),
                      ns)


def main() -> None:
    bags_dir, run, n_poses = Path(sys.argv[1]), sys.argv[2], int(sys.argv[3])
    bag = RunRecorder(bags_dir, run, flush_interval_s=0.0).begin()
    facts, _ = parse_facts({"start": [0.0, 0.0, 0.0], "goal": [2.0, 0.0],
                            "footprint": {"radius_m": 0.2}}, source="victim")
    bag.facts(facts, T0_NS)
    for i in range(n_poses):
        bag.write(odometry(T0_NS + i * DT_NS, SPEED_MPS * i * DT_NS * 1e-9))
    print(bag.path, flush=True)
    print("READY", flush=True)
    time.sleep(600)


if __name__ == "__main__":
    main()
