"""The sim node's parameter table and the configs built from it, without a ROS graph."""

from __future__ import annotations

import dataclasses
import math
import re
import subprocess
import sys

import pytest

from pic4rl_base.errors import ConfigError
from pic4rl_base.geometry import Footprint, Pose2D
from pic4rl_base.schema import param_names
from pic4rl_sim.config import (ROBOT, ClockMode, ParamType, build_config, parameter_table,
                               parse_goal, parse_start, resolve)
from pic4rl_sim.engine.robot_specs import ROBOT_TABLE, BURGER, JACKAL, OMNI, robot_from_mapping
from pic4rl_sim.engine.sensors import SENSOR_TABLE
from pic4rl_sim.engine.worlds.generators import WORLD_TABLE

RCLPY_OWN = ("use_sim_time", "start_type_description_service")


def values_for(robot_name: str = "jackal", **overrides) -> dict:
    overrides = {k.replace("__", "."): v for k, v in overrides.items()}
    return resolve(parameter_table(ROBOT_TABLE[robot_name]), {"robot": robot_name, **overrides})


@pytest.mark.parametrize("robot", sorted(ROBOT_TABLE))
def test_the_defaults_build_a_valid_config_for_every_robot(robot):
    config = build_config(values_for(robot))
    assert config.robot == ROBOT_TABLE[robot]  # the robot's own sensors are the defaults
    assert config.clock.mode is ClockMode.LOCKSTEP
    assert config.episode.start is None and config.episode.goal is None
    assert config.world.build().name == "indoor"


@pytest.mark.parametrize("kind", sorted(WORLD_TABLE))
def test_every_world_generator_builds_from_its_parameters(kind):
    config = build_config(values_for(world=kind))
    assert set(dict(config.world.params)) == set(param_names(WORLD_TABLE[kind].params))
    assert config.world.build().name == kind


def test_every_parameter_is_described_typed_and_within_its_own_range():
    table = parameter_table(JACKAL)
    names = [spec.name for spec in table]
    assert names[0] == "robot" and len(names) == len(set(names))
    for spec in table:
        assert spec.description.strip(), spec.name
        assert spec.check(spec.default) == spec.default, spec.name
    world_params = {name for name in names if name.startswith("world.")}
    assert world_params == {f"world.{kind}.{p}" for kind in WORLD_TABLE
                            for p in param_names(WORLD_TABLE[kind].params)}


@pytest.mark.parametrize("spec", [s for s in parameter_table(JACKAL) if s.range],
                         ids=lambda s: s.name)
def test_ranges_reject_values_outside(spec):
    lo, hi = spec.range
    step = 1 if spec.type is ParamType.INTEGER else 1e-3 * max(1.0, hi - lo)
    below, above = type(spec.default)(lo - step), type(spec.default)(hi + step)
    for value in (below, above):
        with pytest.raises(ConfigError, match=rf"^{spec.name}: .* expected a value in"):
            spec.check(value)
    assert spec.check(type(spec.default)(hi)) == hi


def test_open_bounds_are_checked_by_the_configs():
    with pytest.raises(ConfigError, match="real_time_factor: 0.0 is invalid"):
        build_config(values_for(real_time_factor=0.0))
    with pytest.raises(ConfigError, match="lidar.fov_deg"):
        build_config(values_for(lidar__fov_deg=0.0))
    with pytest.raises(ConfigError, match="control_dt_s: 0.007 .* whole multiple"):
        build_config(values_for(control_dt_s=0.007))


def test_typos_get_a_did_you_mean():
    with pytest.raises(ConfigError, match=r"unknown key 'lidar.beems'; did you mean 'lidar.beams'"):
        values_for(lidar__beems=3)
    with pytest.raises(ConfigError, match=r"world: 'indor' .* did you mean 'indoor'"):
        build_config(values_for(world="indor"))
    with pytest.raises(ConfigError, match=r"robot: unknown key 'jackle'; did you mean 'jackal'"):
        build_config(values_for(robot="jackal") | {"robot": "jackle"})
    with pytest.raises(ConfigError, match="world.obstacles.cont"):
        values_for(**{"world.obstacles.cont": 3})


def test_rclpy_own_parameters_are_not_unknown():
    values = resolve(parameter_table(JACKAL), {"use_sim_time": False}, also_known=RCLPY_OWN)
    assert "use_sim_time" not in values


@pytest.mark.parametrize(("name", "value", "expected"), [
    ("lidar.beams", 3.0, "an integer"),
    ("lidar.beams", True, "an integer"),
    ("lidar.enabled", 1, "true or false"),
    ("world", 3, "a string"),
    ("start_pose", "here", "a list of numbers"),
    ("goal", [1.0, "x"], "a list of numbers"),
    ("clock_mode", "fast", "one of lockstep, realtime"),
])
def test_wrong_types_and_choices_are_rejected_naming_the_key(name, value, expected):
    message = f"{name}: {value!r} is invalid; expected {expected}"
    with pytest.raises(ConfigError, match=f"^{re.escape(message)}$"):
        values_for(**{name: value})


def test_integers_where_numbers_are_wanted_become_floats():
    values = values_for(control_dt_s=1, start_pose=[1, 2, 0], goal=[3, 4])
    assert values["control_dt_s"] == 1.0 and isinstance(values["control_dt_s"], float)
    config = build_config(values | {"physics_dt_s": 0.01})
    assert config.episode.start == Pose2D(1.0, 2.0, 0.0)
    assert config.episode.goal == (3.0, 4.0)


def test_start_and_goal_arrays_are_parsed_or_rejected():
    assert parse_start([]) is None and parse_goal([]) is None
    with pytest.raises(ConfigError, match=r"^start_pose: \[1.0, 2.0\] is invalid"):
        parse_start([1.0, 2.0])
    with pytest.raises(ConfigError, match=r"^start_pose: .*nan"):
        parse_start([math.nan, 0.0, 0.0])
    with pytest.raises(ConfigError, match=r"^goal: \[1.0, 2.0, 3.0, 4.0\] is invalid"):
        parse_goal([1.0, 2.0, 3.0, 4.0])
    with pytest.raises(ConfigError, match=r"^goal: \[1.0\] is invalid"):
        parse_goal([1.0])
    assert parse_goal([1, 2]) == (1.0, 2.0) and parse_goal([1, 2]).yaw is None
    assert parse_goal([1.0, 2.0, 0.5]).yaw == 0.5


def test_sensor_parameters_override_the_robots_sensors():
    burger = parameter_table(BURGER)
    assert next(s for s in burger if s.name == "lidar.range_max_m").default == 3.5
    config = build_config(values_for(lidar__beams=90, lidar__noise_std_m=0.01,
                                     odometry__linear_scale_error=0.02))
    assert config.robot.lidar == dataclasses.replace(JACKAL.lidar, beams=90, noise_std_m=0.01)
    assert config.robot.odometry.linear_scale_error == 0.02
    assert config.robot.depth is None

    config = build_config(values_for(lidar__enabled=False, depth__enabled=True, depth__width=32))
    assert config.robot.lidar is None
    assert (config.robot.depth.width, config.robot.depth.height) == (32, 60)
    with pytest.raises(ConfigError, match="lidar.range_max_m"):
        build_config(values_for(lidar__range_min_m=5.0, lidar__range_max_m=4.0))
    assert build_config(values_for("omni")).robot == OMNI


def test_a_robot_holds_one_spec_per_sensor_kind():
    """``RobotSpec.sensors`` has every ``SENSOR_TABLE`` kind in order (the typed accessors read
    it); a robot file writes each at the top level; a wrong kind or spec is named."""
    assert list(JACKAL.sensors) == [k.name for k in SENSOR_TABLE]
    assert JACKAL.lidar is JACKAL.sensors["lidar"] and JACKAL.depth is None
    refined = robot_from_mapping({"base": "jackal", "depth": {"width": 10},
                                  "lidar": {"beams": 9}})
    assert refined.depth.width == 10 and refined.depth.height == 60
    assert refined.lidar == dataclasses.replace(JACKAL.lidar, beams=9)
    assert robot_from_mapping({"base": "jackal", "lidar": None}).lidar is None
    with pytest.raises(ConfigError, match=r"unknown key 'lidr'; did you mean 'lidar'"):
        robot_from_mapping({"base": "jackal", "lidr": {}})
    with pytest.raises(ConfigError, match=r"unknown key 'sensors'"):
        robot_from_mapping({"base": "jackal", "sensors": {}})
    with pytest.raises(ConfigError, match=r"unknown key 'radar'"):
        JACKAL.with_sensors(radar=None)
    with pytest.raises(ConfigError, match=r"robot.imu: None is invalid; expected ImuSpec$"):
        JACKAL.with_sensors(imu=None)


def test_a_robots_footprint_is_a_circle_or_a_whole_rectangle():
    """A robot file refines the footprint (the episode facts' ``Footprint`` class) to a circle
    or a whole rectangle; half a rectangle, or a circle with a side, is refused."""
    box = robot_from_mapping({"base": "burger",
                              "footprint": {"radius_m": None, "length_m": 0.6, "width_m": 0.8}})
    assert box.footprint == Footprint(length_m=0.6, width_m=0.8) and not box.footprint.is_circle
    assert box.footprint.bounding_radius_m == pytest.approx(0.5)
    assert BURGER.footprint.is_circle and BURGER.footprint.bounding_radius_m == 0.105
    expected = r" is invalid; expected radius_m, or length_m and width_m$"
    with pytest.raises(ConfigError, match=r"^footprint: Footprint\(radius_m=0\.105, length_m=0\.6, "
                       r"width_m=None\)" + expected):
        robot_from_mapping({"base": "burger", "footprint": {"length_m": 0.6}})
    with pytest.raises(ConfigError, match=r"^footprint: Footprint\(radius_m=None, length_m=None, "
                       r"width_m=0\.8\)" + expected):
        Footprint(width_m=0.8)
    with pytest.raises(ConfigError, match=r"^footprint\.width_m: -0\.4 is invalid; expected a "
                       r"positive number of metres$"):
        robot_from_mapping({"base": "jackal", "footprint": {"width_m": -0.4}})


def test_only_robot_world_sensor_and_timing_changes_need_a_new_engine():
    base = build_config(values_for())
    for same in ({"seed": 7}, {"start_pose": [0.0, 0.0, 0.0]}, {"clock_mode": "realtime"}):
        assert build_config(values_for(**same)).build_key == base.build_key
    for other in ({"world_variant": 1}, {"lidar__beams": 10}, {"control_dt_s": 0.05},
                  {"robot": "burger"}, {"world__indoor__rooms_x": 2}):
        assert build_config(values_for(**other)).build_key != base.build_key


def test_the_robot_parameter_comes_first_and_is_a_string():
    assert ROBOT.type is ParamType.STRING and ROBOT.default in ROBOT_TABLE


def test_params_does_not_import_rclpy():
    code = "import sys, pic4rl_sim.config; sys.exit('rclpy' in sys.modules)"
    assert subprocess.run([sys.executable, "-c", code], check=False).returncode == 0
