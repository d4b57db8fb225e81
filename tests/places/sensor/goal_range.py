"""A user's sensor, written outside pic4rl: a goal range finder (the distance from the robot
to the episode's goal, m, with white noise), published as ``sensor_msgs/msg/Range`` on
``goal_range`` each step and read into ``SensorFrame.readings["goal_range"]``.

Its four parts are made by functions that pic4rl's tables call when they load their entry
points (``pyproject.toml`` beside it): ``kind`` (the sim's ``SENSOR_TABLE``: its spec, its
read and its step message), ``topic`` (the sim's ``INTERFACE_TABLE``), ``reading`` (the
bridge's ``READING_TABLE``: its decoder and its in-process read, a float32 as the message
holds it) and ``observation`` (the env's ``OBSERVED_TABLE``: ``sensors: [lidar, goal_range]``
observes it as a Dict key, its ``part`` the value: the range, no obstacle points). Each
imports pic4rl's class when called, so the module loads before any of those tables does."""

import math
from dataclasses import dataclass

import numpy as np

from pic4rl_base.schema import Range, check, param

NAME = "goal_range"
MAX_RANGE_M = 100.0


@dataclass(frozen=True)
class GoalRangeSpec:
    noise_std_m: float = param(0.0, doc="standard deviation of the goal range's white noise",
                               unit="m", range=Range(0.0, 10.0))

    def __post_init__(self):
        check(self, f"{NAME}.")


class GoalRange:
    """The sensor on the engine's robot."""

    frame_id = "base_link"

    def __init__(self, spec):
        self.spec = spec


def _read(sensor, engine, rng):
    pose = engine.robot_pose()
    distance = math.hypot(engine.goal[0] - pose.x, engine.goal[1] - pose.y)
    if sensor.spec.noise_std_m > 0:
        distance += sensor.spec.noise_std_m * float(rng.standard_normal())
    return distance


class _Messages:
    """Its step message: a ``Range`` on the robot's base, refilled each step."""

    def __init__(self, engine, stamp):
        from sensor_msgs.msg import Range as RangeMsg
        from std_msgs.msg import Header

        self.msg = RangeMsg(header=Header(stamp=stamp, frame_id=GoalRange.frame_id),
                            radiation_type=RangeMsg.INFRARED, field_of_view=2 * math.pi,
                            min_range=0.0, max_range=MAX_RANGE_M)
        self.held = {topic(): self.msg}

    def fill(self, engine):
        self.msg.range = engine.read(NAME)


def kind():
    from pic4rl_sim.engine.sensors import SensorKind

    return SensorKind(NAME, GoalRangeSpec, lambda model, spec, body: GoalRange(spec), _read,
                      messages=_Messages)


def topic():
    from pic4rl_sim.interfaces import Cadence, Direction, Interface, QosKind

    return Interface(NAME, "sensor_msgs/msg/Range", Direction.PUB, QosKind.SENSOR_DATA,
                     "the distance to the goal (m)", Cadence.STEP, record_order=12)


def reading():
    from pic4rl_bridge.readings.sensor_table import FrameSensor

    return FrameSensor(NAME, topic(), lambda msg, mount, topic: float(msg.range),
                       lambda engine, mount: float(np.float32(engine.read(NAME))), kind=NAME)


def part():
    from gymnasium.spaces import Box

    from pic4rl_bridge.perception.sensor_parts import SensorPart

    return SensorPart(lambda robot: frozenset({NAME}),
                      lambda config, robot: Box(0.0, MAX_RANGE_M, (1,), np.float32),
                      lambda config, robot, frame, extra: np.array([frame.readings[NAME]],
                                                                   np.float32),
                      lambda frame, robot: None)


def observation():
    from pic4rl_bridge.settings.observations import ObservedSensor

    return ObservedSensor(NAME, NAME, "goal_range:part")
