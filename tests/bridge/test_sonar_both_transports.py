"""The sonar ring through both transports (issue 40 item 3): the sim node with
``sonar.enabled`` publishes one ``sensor_msgs/Range`` per cone, a bag records them when
``record.topics`` names them, they equal the in-process engine's for one seed and one command
sequence, and the bridge's reading ``sonar_<i>`` decodes them to the engine's own value."""

from __future__ import annotations

import math
import tempfile
from pathlib import Path

import numpy as np
from rosbags.rosbag2 import Reader
from rosbags.typesys import Stores, get_typestore

from pic4rl_base.geometry import Pose2D
from pic4rl_bridge.readings.sensor_table import BY_NAME
from pic4rl_bridge.recording import make_env
from pic4rl_sim.interfaces import RECORDED

ROOT = Path(__file__).resolve().parents[2]
CONFIG = ROOT / "config" / "env_goto_lidar.yaml"
STORE = get_typestore(Stores.ROS2_JAZZY)
SONAR = {"sonar.enabled": True, "sonar.count": 6}
TOPICS = [*RECORDED, *(f"sonar/cone{i}" for i in range(8))]


def _sonar(make, bags: str, run: str) -> tuple[list[np.ndarray], list[float], float | None]:
    """Each step's six cone ranges of one 12-step episode, the first cone's decoded by the
    bridge's reading, and (in process) the engine's own reading of cone 0 at the episode's
    end."""
    env = make({"record.enabled": True, "record.bags_dir": bags, "record.run": run,
                "record.storage": "sqlite3", "record.topics": TOPICS,
                "episode_max_steps": 12})
    rng = np.random.default_rng(4)
    engine_value = None
    try:
        env.reset(seed=9)
        for _ in range(12):
            _, _, terminated, truncated, _ = env.step(
                rng.uniform(-1, 1, env.action_space.shape).astype(np.float32))
            if terminated or truncated:
                break
        engine = getattr(env.unwrapped.transport, "engine", None)
        if engine is not None:
            engine_value = BY_NAME["sonar_0"].read(engine, Pose2D(0.0, 0.0, 0.0))
    finally:
        env.close()
    steps: dict[int, dict[int, float]] = {}
    decoded = []
    with Reader(Path(bags) / run / "episode_0000") as reader:
        topics = {c.topic for c in reader.connections}
        assert "/sonar/cone6" not in topics and "/sonar/cone7" not in topics  # a ring of six
        for conn, stamp, raw in reader.messages():
            if conn.topic.startswith("/sonar/cone"):
                assert conn.msgtype == "sensor_msgs/msg/Range"
                msg = STORE.deserialize_cdr(raw, conn.msgtype)
                cone = int(conn.topic.removeprefix("/sonar/cone"))
                assert msg.header.frame_id == f"sonar_{cone}"
                assert msg.radiation_type == 0  # ULTRASOUND
                assert math.isclose(msg.field_of_view, math.radians(30.0), rel_tol=1e-6)
                steps.setdefault(stamp, {})[cone] = msg.range
                if cone == 0:
                    decoded.append(BY_NAME["sonar_0"].decode(msg, Pose2D(0, 0, 0), conn.topic))
    ranges = [np.array([cones[i] for i in range(6)], np.float32)
              for _, cones in sorted(steps.items())]
    return ranges, decoded, engine_value


def test_the_sonar_ring_is_published_recorded_and_decoded_alike_by_both_transports(
        domain: int, start_sim) -> None:
    start_sim(domain, "--params-file", str(CONFIG), "-p", "sonar.enabled:=true",
              "-p", "sonar.count:=6")
    with tempfile.TemporaryDirectory() as bags:
        ros, ros_decoded, _ = _sonar(
            lambda o: make_env(CONFIG, transport="ros", overrides={**o, "ros.domain_id": domain}),
            bags, "ros")
        local, local_decoded, engine_value = _sonar(
            lambda o: make_env(CONFIG, overrides=o, sim=SONAR), bags, "local")
    assert len(ros) == len(local) >= 10
    for i, (a, b) in enumerate(zip(ros, local)):
        np.testing.assert_array_equal(a, b, err_msg=f"sonar ranges differ at step {i}")
    stacked = np.stack(ros)
    assert np.isfinite(stacked).any()  # the ring sees the world's walls
    assert ros_decoded == [float(r[0]) for r in ros] == local_decoded
    assert engine_value == local_decoded[-1]  # the in-process read: the published value
