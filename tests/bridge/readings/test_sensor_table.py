"""The frame's sensor table (``pic4rl_bridge.readings.sensor_table``): one entry per reading of
``SensorFrame``, one place that builds frames, and for each sensor the in-process engine read
bit-identical to decoding the sim node's message (what makes both transports' frames equal)."""

from __future__ import annotations

import ast
import dataclasses
from pathlib import Path

import numpy as np
import pytest
from pic4rl_sim.engine.core import Engine
from pic4rl_sim.engine.crowd.params import CrowdParams
from pic4rl_sim.engine.engine_config import EngineConfig
from pic4rl_base.geometry import Pose2D
from pic4rl_sim.engine.geometry import Twist2D
from pic4rl_sim.engine.robot_specs import OMNI, DepthCameraSpec, LidarSpec
from pic4rl_sim.engine.sensor_kinds.sonar import SonarSpec
from pic4rl_sim.engine.sensor_kinds.stereo import StereoCameraSpec
from pic4rl_sim.engine.sensor_kinds.uwb import UwbSpec
from pic4rl_sim.engine.worlds.generators import make_world
from pic4rl_sim.node.messages import StateMessages, plan_message

from pic4rl_bridge.config import EnvConfig, env_config_from_params
from pic4rl_bridge.errors import ConfigError
from pic4rl_bridge.readings.frame import ScanData, SensorFrame
from pic4rl_bridge.readings.sensor_table import READING_TABLE, FrameSensor, build_frame

BRIDGE = Path(__file__).resolve().parents[3] / "pic4rl_bridge"
#: The fields every frame has; the sensors' are its ``readings``.
ALWAYS = ("stamp_ns", "pose", "twist", "goal")


def test_a_frame_holds_the_tables_sensors_as_readings() -> None:
    """A frame's fields are the ones every frame has, ``readings`` and a simulator's
    ``contact`` (no sensor's: what the robot touched); each sensor of the table is a reading by
    its name (the stock ones also a typed accessor), so a new sensor needs no new field."""
    fields = [f.name for f in dataclasses.fields(SensorFrame)]
    assert fields == [*ALWAYS, "readings", "contact"]
    names = [s.name for s in READING_TABLE]
    frame = build_frame(1, (Pose2D(0.0, 0.0, 0.0), Twist2D()), None, names[::-1],
                        lambda sensor: f"value of {sensor.name}")
    assert list(frame.readings) == names
    typed = [n for n in names if isinstance(getattr(SensorFrame, n, None), property)]
    assert typed == ["scan", "depth", "person", "plan"]
    assert [getattr(frame, n) for n in typed] == [frame.readings[n] for n in typed]
    fewer = dataclasses.replace(frame, scan=None, goal=(1.0, 2.0))
    assert list(fewer.readings) == names[1:] and fewer.goal == (1.0, 2.0)
    empty = build_frame(1, (Pose2D(0.0, 0.0, 0.0), Twist2D()), None, names, lambda sensor: None)
    assert dict(empty.readings) == {} and empty.scan is None


def test_each_sensor_has_its_topic_parameter_with_the_tables_default() -> None:
    """``topics:`` holds one parameter per sensor of the table (with its sim topic as the
    default), which the params file sets and the schema checks like any other."""
    default = EnvConfig()
    for sensor in READING_TABLE:
        assert getattr(default.topics, sensor.name) == sensor.interface.name
        remapped = env_config_from_params({f"topics.{sensor.name}": f"/robot2/{sensor.name}"})
        assert getattr(remapped.topics, sensor.name) == f"/robot2/{sensor.name}"
    with pytest.raises(ConfigError, match="did you mean 'topics.scan'"):
        env_config_from_params({"topics.scna": "/front/scan"})


def test_only_build_frame_constructs_a_sensor_frame() -> None:
    """No transport (nor any other bridge module) builds a ``SensorFrame`` its own way."""
    builders = []
    for path in sorted(BRIDGE.rglob("*.py")):
        for node in ast.walk(ast.parse(path.read_text(), str(path))):
            if (isinstance(node, ast.Call) and isinstance(node.func, ast.Name)
                    and node.func.id == "SensorFrame"):
                builders.append(path.relative_to(BRIDGE).as_posix())
    assert builders == ["readings/sensor_table.py"]


def test_build_frame_fills_only_the_wanted_sensors() -> None:
    frame = build_frame(7, (Pose2D(1.0, 2.0, 0.5), Twist2D(0.1)), (3.0, 4.0), {"person", "x"},
                        lambda sensor: f"value of {sensor.name}")
    assert frame.stamp_ns == 7 and frame.goal == (3.0, 4.0) and frame.pose.x == 1.0
    assert frame.person == "value of person"
    assert frame.scan is None and frame.depth is None and frame.plan is None


@pytest.fixture(scope="module")
def engine() -> Engine:
    """An omni robot with a noisy LiDAR, a depth camera, a sonar ring, a UWB tag ranging to
    four anchors and the goal and a stereo camera, next to a walking person and a crowd of
    three."""
    robot = OMNI.with_sensors(lidar=LidarSpec(beams=90, noise_std_m=0.01),
                              depth=DepthCameraSpec(width=16, height=12, noise_std_m=0.01),
                              sonar=SonarSpec(noise_std_m=0.01),
                              uwb=UwbSpec(anchors_xy_m=(1.0, 1.0, -1.0, 1.0, 1.0, -1.0, 0.0, 5.0),
                                          dropout_prob=0.1),
                              stereo=StereoCameraSpec(width=16, height=12))
    return Engine(robot, make_world("person", seed=3),
                  EngineConfig(crowd=CrowdParams(count=3)), seed=5)


def replay(engine: Engine) -> None:
    """The same episode state, with fresh noise streams: three steps from the seed's start."""
    engine.reset(seed=5)
    for _ in range(3):
        engine.step(Twist2D(0.3, 0.1, 0.2))


@pytest.mark.parametrize("sensor", READING_TABLE, ids=lambda s: s.name)
def test_the_engine_read_equals_the_decoded_message(engine: Engine, sensor: FrameSensor) -> None:
    mount = Pose2D(0.1, 0.0, 0.0)
    messages = StateMessages(engine)
    held = {t.name: msg for t, msg in messages.published}
    replay(engine)  # the same noise draws for the read and for the message
    read = sensor.read(engine, mount)
    replay(engine)
    messages.fill(engine, 123)
    msg = held.get(sensor.interface.name)
    if msg is None:  # an episodic topic: the node publishes it at reset
        msg = plan_message(engine.plan(), 123)
    decoded = sensor.decode(msg, mount, sensor.interface.name)
    assert read is not None
    if isinstance(read, ScanData):
        assert dataclasses.astuple(read)[1:] == dataclasses.astuple(decoded)[1:]
        assert read.ranges.dtype == decoded.ranges.dtype == np.float32
        np.testing.assert_array_equal(read.ranges, decoded.ranges)
    elif isinstance(read, np.ndarray):
        assert read.dtype == decoded.dtype and read.shape == decoded.shape
        np.testing.assert_array_equal(read, decoded)
    else:
        assert read == decoded
