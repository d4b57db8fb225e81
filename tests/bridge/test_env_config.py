"""The env's config: ``load_env_config`` reads the env's and the sim's sections of a ROS 2
parameter file (nested mappings as dotted names, dotted overrides on top), names the key and
value of every bad entry, round-trips through ``to_params``; ``Scenario`` derives the robot the
tasks see (footprint, LiDAR mount, the env's velocity limits within the robot's)."""

from __future__ import annotations

import math
import re
from pathlib import Path
from typing import Any

import pytest
import yaml

from pic4rl_base.geometry import Footprint, Pose2D
from pic4rl_base.schema import param_names
from pic4rl_bridge.config import EnvConfig, env_config_from_params, load_env_config
from pic4rl_bridge.errors import ConfigError
from pic4rl_bridge.scenario import Scenario
from pic4rl_sim.interfaces import RECORDED

REPO = Path(__file__).resolve().parents[2]
CONFIGS = sorted((REPO / "config").glob("env_*.yaml"))
SIM_ONLY = REPO / "config" / "sim_indoor_jackal.yaml"


def write(tmp_path: Path, data: Any, name: str = "env.yaml") -> Path:
    """``data`` as a YAML file in ``tmp_path`` (a string is written as it is)."""
    path = tmp_path / name
    path.write_text(data if isinstance(data, str) else yaml.safe_dump(data))
    return path


def env_file(tmp_path: Path, params: dict[str, Any], **sections: Any) -> Path:
    """A file with a ``nav_env`` section holding ``params`` (plus other ``sections``)."""
    return write(tmp_path, {"nav_env": {"ros__parameters": params}, **sections})


# --- sections ---------------------------------------------------------------------------------


def test_the_shipped_configs_load_with_both_sections() -> None:
    """Every config/env_*.yaml has a sim section and an env section that differs from the
    defaults."""
    assert len(CONFIGS) >= 4
    for path in CONFIGS:
        config = load_env_config(path)
        data = yaml.safe_load(path.read_text())
        assert config.sim_params == data["sim"]["ros__parameters"], path.name
        assert config.episode_max_steps == data["nav_env"]["ros__parameters"][
            "episode_max_steps"], path.name


@pytest.mark.parametrize("section", ["nav_env", "/nav_env", "/**/nav_env"])
def test_env_section_under_any_ros_name(tmp_path: Path, section: str) -> None:
    """The env's section may be named as a node, an absolute node or any-namespace node."""
    path = write(tmp_path, {section: {"ros__parameters": {"episode_max_steps": 7}}})
    config = load_env_config(path)
    assert config.episode_max_steps == 7
    assert config.sim_params == {}


def test_first_matching_section_wins(tmp_path: Path) -> None:
    """``nav_env`` is read before ``/nav_env`` when a file has both."""
    path = write(tmp_path, {"/nav_env": {"ros__parameters": {"episode_max_steps": 9}},
                            "nav_env": {"ros__parameters": {"episode_max_steps": 3}}})
    assert load_env_config(path).episode_max_steps == 3


def test_custom_node_name(tmp_path: Path) -> None:
    """``node=`` reads another node's section."""
    path = write(tmp_path, {"my_env": {"ros__parameters": {"goal_tolerance_m": 0.25}}})
    assert load_env_config(path, node="my_env").goal_tolerance_m == 0.25
    with pytest.raises(ConfigError, match="no section for 'nav_env' or 'sim'"):
        load_env_config(path)


def test_sim_section_is_kept_flat(tmp_path: Path) -> None:
    """The ``sim`` section becomes ``sim_params`` with nested mappings as dotted names."""
    path = env_file(tmp_path, {"task": "goToPose"},
                    sim={"ros__parameters": {"robot": "husky", "lidar": {"beams": 90}}})
    config = load_env_config(path)
    assert config.sim_params == {"robot": "husky", "lidar.beams": 90}


def test_sim_only_file_is_the_sim_section() -> None:
    """A sim-only file (``/**``) gives the sim's parameters and the env's defaults."""
    config = load_env_config(SIM_ONLY)
    data = yaml.safe_load(SIM_ONLY.read_text())["/**"]["ros__parameters"]
    assert config.sim_params == data
    assert config.sim_params["robot"] == "jackal"
    assert config == EnvConfig()


def test_nested_and_dotted_names_are_the_same(tmp_path: Path) -> None:
    """``reward: {goal: 5}`` and ``reward.collision: -3`` both set reward fields; ints
    become floats where a float is wanted."""
    path = env_file(tmp_path, {"reward": {"goal": 5}, "reward.collision": -3,
                               "lidar": {"sectors": 12}, "record.topics": ["scan", "odom"]})
    config = load_env_config(path)
    assert config.reward.goal == 5.0 and isinstance(config.reward.goal, float)
    assert config.reward.collision == -3.0
    assert config.lidar.sectors == 12
    assert config.record.topics == ("scan", "odom")


def test_dotted_overrides_win_over_the_file(tmp_path: Path) -> None:
    """Keyword overrides (dotted names) replace the file's values and are checked too."""
    path = env_file(tmp_path, {"reward": {"goal": 5.0}, "episode_max_steps": 10})
    config = load_env_config(path, **{"reward.goal": 42.0, "ros.step_mode": "rate"})
    assert config.reward.goal == 42.0
    assert config.ros.step_mode == "rate"
    assert config.episode_max_steps == 10
    with pytest.raises(ConfigError, match=r"did you mean 'reward\.goal'"):
        load_env_config(path, **{"reward.gaol": 1.0})


# --- errors -----------------------------------------------------------------------------------


@pytest.mark.parametrize(("params", "message"), [
    ({"reward": {"gaol": 1.0}}, r"unknown key 'reward\.gaol'; did you mean 'reward\.goal'\?"),
    ({"episode_max_step": 5}, (r"unknown key 'episode_max_step'; did you mean "
                               r"'episode_max_steps'\?")),
    ({"zzzz": 1}, r"unknown key 'zzzz'; known keys: .*episode_max_steps"),
])
def test_unknown_keys_are_named(tmp_path: Path, params: dict[str, Any], message: str) -> None:
    """An unknown key names the file and the key, with the closest known key when one is."""
    path = env_file(tmp_path, params)
    with pytest.raises(ConfigError, match=message) as err:
        load_env_config(path)
    assert str(err.value).startswith(f"{path}: nav_env parameters:")


@pytest.mark.parametrize(("old", "new"), [
    ("lidar.beams", "lidar.sectors"), ("lidar.max_range_m", "lidar.clip_m"),
    ("depth.max_depth_m", "depth.clip_m"), ("depth.width", "depth.obs_width"),
    ("depth.height", "depth.obs_height"),
])
def test_the_envs_old_sensor_keys_are_refused_with_their_new_names(
        tmp_path: Path, old: str, new: str) -> None:
    """The env's observation keys once spelled as the sim's sensor keys (rays vs sectors, the
    sensor's range vs the observation's clip): the old key in the env's section is one line
    naming the new one, while the sim's section keeps it."""
    path = env_file(tmp_path, {old: 12}, sim={"ros__parameters": {old: 12}})
    with pytest.raises(ConfigError) as err:
        load_env_config(path)
    assert str(err.value) == f"{path}: nav_env parameters: key {old!r} is renamed {new!r}"
    config = load_env_config(env_file(tmp_path, {new: 12}, sim={"ros__parameters": {old: 12}}))
    assert config.to_params()[new] == 12 and config.sim_params == {old: 12}


@pytest.mark.parametrize(("params", "message"), [
    ({"episode_max_steps": "ten"}, r"episode_max_steps: 'ten' is invalid; expected an integer"),
    ({"episode_max_steps": 2.5}, r"episode_max_steps: 2\.5 is invalid; expected an integer"),
    ({"episode_max_steps": True}, r"episode_max_steps: True is invalid; expected an integer"),
    ({"goal_tolerance_m": "far"}, r"goal_tolerance_m: 'far' is invalid; expected a number"),
    ({"reward": {"goal": False}}, r"reward\.goal: False is invalid; expected a number"),
    ({"record": {"enabled": "yes"}},
     r"record\.enabled: 'yes' is invalid; expected true or false"),
    ({"task": 3}, r"task: 3 is invalid; expected a string"),
    ({"record": {"topics": "scan"}}, r"record\.topics: 'scan' is invalid; expected a list"),
    ({"record": {"topics": ["scan", 4]}},
     r"record\.topics: \['scan', 4\] is invalid; expected a list of strings"),
])
def test_wrong_types_name_key_and_value(tmp_path: Path, params: dict[str, Any],
                                        message: str) -> None:
    """A value of the wrong type names the key, the value and the type expected."""
    with pytest.raises(ConfigError, match=message):
        load_env_config(env_file(tmp_path, params))


@pytest.mark.parametrize(("key", "value", "choices"), [
    ("task", "goToPos", "goToPose, vineyard, personMonitoring"),
    ("sensor", "radar", "lidar, depth, sonar, stereo"),
    ("transport", "dds", "inprocess, ros"),
    ("ros.step_mode", "fast", "lockstep, rate"),
    ("record.storage", "bag", "sqlite3, mcap"),
    ("depth.encoding", "uint16", "uint8, float32"),
    ("ros.cmd_vel_type", "Twist3", "Twist, TwistStamped"),
])
def test_bad_choices_list_the_valid_ones(tmp_path: Path, key: str, value: str,
                                         choices: str) -> None:
    """An enumerated parameter with another value names it and the valid values."""
    with pytest.raises(ConfigError, match=rf"{re.escape(key)}: '{value}' is invalid; "
                                          rf"expected (one of )?{re.escape(choices)}"):
        load_env_config(env_file(tmp_path, {key: value}))


@pytest.mark.parametrize(("key", "value"), [
    ("episode_max_steps", 0), ("episode_max_steps", -3), ("goal_tolerance_m", 0.0),
    ("goal_tolerance_m", -0.4), ("lidar.sectors", 0), ("lidar.clip_m", float("nan")),
    ("collision_steps", 0), ("ros.timeout_s", float("inf")), ("depth.obs_width", 0),
])
def test_non_positive_values_are_refused(tmp_path: Path, key: str, value: float) -> None:
    """Counts, tolerances and ranges must be positive and finite."""
    with pytest.raises(ConfigError, match=rf"{re.escape(key)}: .* is invalid; "
                                          r"expected a positive number"):
        load_env_config(env_file(tmp_path, {key: value}))


@pytest.mark.parametrize(("key", "value"), [
    ("collision_tolerance_m", -0.01), ("max_linear_m_s", -1.0), ("control_dt_s", -0.1),
    ("record.flush_interval_s", float("nan")), ("episodes.starting_episodes", -1),
])
def test_negative_values_are_refused(tmp_path: Path, key: str, value: float) -> None:
    """Tolerances, limits and periods where 0 means "default" must still be >= 0."""
    with pytest.raises(ConfigError, match=rf"{re.escape(key)}: .* is invalid; "
                                          r"expected a number >= 0"):
        load_env_config(env_file(tmp_path, {key: value}))


def test_non_finite_min_linear_is_refused(tmp_path: Path) -> None:
    """``min_linear_m_s`` must be finite like every other velocity limit."""
    with pytest.raises(ConfigError, match="min_linear_m_s"):
        load_env_config(env_file(tmp_path, {"min_linear_m_s": float("nan")}))


def test_vineyard_centerline_needs_two_points(tmp_path: Path) -> None:
    """A centre line is empty or x0, y0, x1, y1, ... with two or more points."""
    with pytest.raises(ConfigError, match=r"vineyard\.centerline: \(1\.0, 2\.0\) is invalid"):
        load_env_config(env_file(tmp_path, {"vineyard": {"centerline": [1.0, 2.0]}}))
    config = load_env_config(env_file(tmp_path, {"vineyard.centerline": [0, 0, 5, 0]}))
    assert config.vineyard.centerline == (0.0, 0.0, 5.0, 0.0)


def test_a_missing_file_is_named(tmp_path: Path) -> None:
    path = tmp_path / "nope.yaml"
    with pytest.raises(ConfigError, match=rf"{re.escape(str(path))}: cannot read the config"):
        load_env_config(path)


def test_a_non_yaml_file_is_named(tmp_path: Path) -> None:
    path = write(tmp_path, "nav_env: {ros__parameters: [unclosed\n")
    with pytest.raises(ConfigError, match=rf"{re.escape(str(path))}: not valid YAML"):
        load_env_config(path)


@pytest.mark.parametrize("data", [[1, 2, 3], "just text", None])
def test_a_file_that_is_no_mapping_is_refused(tmp_path: Path, data: Any) -> None:
    """A YAML list, scalar or empty file holds no node sections."""
    path = write(tmp_path, yaml.safe_dump(data))
    with pytest.raises(ConfigError, match="expected a mapping of node sections"):
        load_env_config(path)


def test_a_file_with_neither_section_is_refused(tmp_path: Path) -> None:
    path = write(tmp_path, {"other_node": {"ros__parameters": {"x": 1}}})
    with pytest.raises(ConfigError, match=r"no section for 'nav_env' or 'sim'") as err:
        load_env_config(path)
    assert str(err.value).startswith(str(path))


@pytest.mark.parametrize("section", [{"ros__parameters": [1]}, {"params": {}}, "text"])
def test_a_section_without_parameters_is_refused(tmp_path: Path, section: Any) -> None:
    path = write(tmp_path, {"nav_env": section})
    with pytest.raises(ConfigError, match=r"section 'nav_env' needs a 'ros__parameters'"):
        load_env_config(path)


# --- round trip -------------------------------------------------------------------------------


@pytest.mark.parametrize("path", CONFIGS, ids=lambda p: p.name)
def test_to_params_round_trips(path: Path) -> None:
    """``to_params`` lists every parameter once, and builds the same config back."""
    config = load_env_config(path)
    params = config.to_params()
    assert set(params) == set(param_names(EnvConfig))
    back = env_config_from_params(params, sim_params=config.sim_params)
    assert back == config and back.sim_params == config.sim_params


def test_to_params_round_trips_through_yaml(tmp_path: Path) -> None:
    """Non-default values of every kind (tuples, bools, nested) survive a params file."""
    config = EnvConfig(task="vineyard", sensor="depth", robot="husky", episode_max_steps=17,
                       ).replace(**{"vineyard.centerline": [0.0, 1.0, 9.0, 1.0],
                                    "record.enabled": True, "record.topics": ["scan"],
                                    "reward.step": -0.5, "ros.namespace": "robot1"})
    assert config.record.topics == ("scan",) and config.vineyard.centerline[2] == 9.0
    path = write(tmp_path, {"nav_env": {"ros__parameters": config.to_params()},
                            "sim": {"ros__parameters": {"robot": "husky"}}})
    back = load_env_config(path)
    assert back == config
    assert back.sim_params == {"robot": "husky"}
    assert back != EnvConfig()


def test_replace_checks_its_overrides() -> None:
    """``replace`` applies dotted overrides and validates them like a file."""
    config = EnvConfig().replace(**{"reward.goal": 1.0})
    assert config.reward.goal == 1.0 and EnvConfig().reward.goal == 1000.0
    with pytest.raises(ConfigError, match="did you mean 'reward.goal'"):
        EnvConfig().replace(**{"reward.gaol": 1.0})
    assert EnvConfig().record.topics == RECORDED


# --- Scenario ---------------------------------------------------------------------------------


def test_scenario_reads_the_robot_from_the_sim_section() -> None:
    """The Jackal of env_goto_lidar.yaml: its box footprint, its LiDAR mount, and the env's
    tighter limits (0.5 m/s, 1 rad/s) within the robot's (2 m/s, 4 rad/s)."""
    scenario = Scenario(load_env_config(REPO / "config" / "env_goto_lidar.yaml"))
    robot = scenario.robot
    assert robot.name == "jackal" and not robot.omni
    assert robot.footprint == Footprint(length_m=0.508, width_m=0.430)
    assert robot.lidar_mount == Pose2D(0.12, 0.0, 0.0)
    assert robot.depth_mount is None
    assert (robot.min_linear_m_s, robot.max_linear_m_s) == (0.0, 0.5)
    assert robot.max_angular_rad_s == 1.0 and robot.max_lateral_m_s == 0.0
    assert robot.control_dt_s == pytest.approx(0.1)
    assert scenario.world_name == "indoor:0"


@pytest.mark.parametrize(("env_limits", "expected"), [
    ({}, (0.0, 2.0, 4.0)),  # 0: the robot's limits
    ({"max_linear_m_s": 5.0, "max_angular_rad_s": 9.0}, (0.0, 2.0, 4.0)),  # capped
    ({"max_linear_m_s": 0.3, "min_linear_m_s": -0.1}, (-0.1, 0.3, 4.0)),
    ({"max_linear_m_s": 0.3, "min_linear_m_s": -7.0}, (-0.3, 0.3, 4.0)),  # >= -max
])
def test_velocity_limits_are_the_env_within_the_robot(
        env_limits: dict[str, float], expected: tuple[float, float, float]) -> None:
    """Each limit is min(env limit, robot limit); min_linear is kept above -max_linear."""
    config = EnvConfig(**env_limits, sim_params={"robot": "jackal"})
    robot = Scenario(config).robot
    assert (robot.min_linear_m_s, robot.max_linear_m_s, robot.max_angular_rad_s) == expected


def test_omni_robot_reverses_and_strafes() -> None:
    """The omni platform: min_linear = -max_linear whatever min_linear_m_s says, and a
    lateral limit of its own."""
    config = load_env_config(REPO / "config" / "env_person_omni.yaml",
                             min_linear_m_s=0.0, max_linear_m_s=0.8, max_lateral_m_s=0.4)
    robot = Scenario(config).robot
    assert robot.omni and robot.name == "omni"
    assert robot.footprint == Footprint(radius_m=0.25)
    assert (robot.min_linear_m_s, robot.max_linear_m_s) == (-0.8, 0.8)
    assert robot.max_lateral_m_s == 0.4
    assert robot.lidar_mount == Pose2D(0.0, 0.0, 0.0)


def test_env_robot_overrides_the_sim_robot() -> None:
    """``robot`` in the env's section replaces the sim section's robot."""
    config = load_env_config(REPO / "config" / "env_goto_lidar.yaml", robot="husky")
    scenario = Scenario(config)
    assert scenario.robot.name == "husky"
    assert scenario.sim is not None and scenario.sim.robot.name == "husky"
    assert scenario.robot.lidar_mount == Pose2D(0.3, 0.0, 0.0)


def test_control_period_comes_from_the_sim_unless_set() -> None:
    config = EnvConfig(sim_params={"control_dt_s": 0.05, "physics_dt_s": 0.005})
    assert Scenario(config).robot.control_dt_s == pytest.approx(0.05)
    assert Scenario(config.replace(control_dt_s=0.2)).robot.control_dt_s == 0.2


def test_real_robot_config_needs_a_robot() -> None:
    """Without a sim section (ROS transport) the robot must be named; no world then."""
    with pytest.raises(ConfigError, match=r"robot: '' is invalid; expected a robot name"):
        Scenario(EnvConfig(transport="ros"))
    scenario = Scenario(EnvConfig(transport="ros", robot="burger"))
    assert scenario.sim is None and scenario.world is None and scenario.world_name == ""
    assert scenario.robot.footprint == Footprint(radius_m=0.105)
    assert scenario.robot.max_linear_m_s == pytest.approx(0.22)
    assert scenario.robot.control_dt_s == pytest.approx(0.1)
    with pytest.raises(ConfigError, match=r"^robot: "):
        Scenario(EnvConfig(transport="ros", robot="no_such_robot"))


def test_bad_sim_parameters_are_config_errors() -> None:
    """A sim section pic4rl_sim refuses is a ConfigError naming the sim's parameter."""
    with pytest.raises(ConfigError, match=r"^sim parameters: .*lidar\.beams"):
        Scenario(EnvConfig(sim_params={"lidar.beams": "many"}))
    assert math.isclose(Scenario(EnvConfig()).robot.max_linear_m_s, 2.0)


def test_gym_make_finds_a_relative_episodes_file_beside_the_params_file(tmp_path, monkeypatch):
    """``episodes.file`` relative to the params file is found from any working directory, by
    ``gym.make`` as by ``pic4rl-train`` (one loader: ``pic4rl_base.params_file``)."""
    import gymnasium as gym

    import pic4rl_bridge  # noqa: F401  (registers the ids)

    folder = tmp_path / "cfg"
    folder.mkdir()
    pairs = Path(__file__).resolve().parents[2] / "config" / "goals_indoor_train.json"
    (folder / "pairs.json").write_text(pairs.read_text())
    params = folder / "env.yaml"
    params.write_text(yaml.safe_dump({"nav_env": {"ros__parameters": {
        "episodes": {"file": "pairs.json"}}}}))
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    monkeypatch.chdir(elsewhere)
    env = gym.make("pic4rl/GoToPoseLidar-v0", config="../cfg/env.yaml")
    try:
        assert Path(env.unwrapped.config.episodes.file) == (folder / "pairs.json").resolve()
        env.reset(seed=0)
    finally:
        env.close()
