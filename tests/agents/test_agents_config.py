"""The trainer's configuration and command line: the shipped training files load, several
files merge key by key, every bad key or value is named, RL-Zoo ``key:value`` overrides and
ROS ``--ros-args`` are parsed as the docs say, a run's ``config.yaml`` loads back as it was,
and ``-p`` items go to the trainer or the env by their key."""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

import pytest
import yaml
from agents_helpers import CONFIG, LIDAR_TD3

from pic4rl_agents.runs.config import RunConfig, TrainConfig, load_run_config, train_config_from_params
from pic4rl_agents.runs.overrides import parse_overrides
from pic4rl_agents.launch.rosargs import RosArgs, split_ros_args
from pic4rl_agents.training.args import route_params
from pic4rl_bridge.errors import ConfigError

SHIPPED = {
    "train_goto_lidar_td3.yaml": ("td3", "lidar", "td3_lidar"),
    "train_goto_lidar_sac.yaml": ("sac", "lidar", "sac_lidar"),
    "train_goto_depth_td3.yaml": ("td3", "depth", "td3_depth"),
    "train_goto_depth_sac.yaml": ("sac", "depth", "sac_depth"),
    "train_goto_plan_td3.yaml": ("td3", "lidar", "td3_plan"),
    "train_goto_lidar_td3_imitation.yaml": ("td3", "lidar", "td3_lidar_imitation"),
    "train_goto_lidar_sac_imitation.yaml": ("sac", "lidar", "sac_lidar_imitation"),
    "train_goto_lidar_td3_memory.yaml": ("td3", "lidar", "td3_lidar_memory"),
    "train_goto_lidar_td3_history.yaml": ("td3", "lidar", "td3_lidar_history"),
    "train_barn_td3_memory.yaml": ("td3", "lidar", "barn_td3_memory"),
    "train_goto_lidar_td3_explorer.yaml": ("td3", "lidar", "td3_lidar_explorer"),
    "train_goto_lidar_sac_explorer.yaml": ("sac", "lidar", "sac_lidar_explorer"),
    "train_goto_depth_td3_explorer.yaml": ("td3", "depth", "td3_depth_explorer"),
    "train_goto_depth_sac_explorer.yaml": ("sac", "depth", "sac_depth_explorer"),
    "train_barn_td3_explorer.yaml": ("td3", "lidar", "barn_td3_explorer"),
    "train_person_hybrid_sac.yaml": ("sac", "lidar", "sac_person_hybrid"),
    "train_person_hybrid_td3.yaml": ("td3", "lidar", "td3_person_hybrid"),
    "train_person_e2e_sac.yaml": ("sac", "lidar", "sac_person_e2e"),
    "train_vineyard_sac.yaml": ("sac", "depth", "vineyard_sac"),
    "train_vineyard_td3.yaml": ("td3", "depth", "vineyard_td3"),
    "train_fusion_td3_explorer.yaml": ("td3", "lidar", "fusion_fused"),
    "train_goto_uwb_td3.yaml": ("td3", "lidar", "td3_uwb"),
    "train_crowd_td3_history.yaml": ("td3", "lidar", "crowd_td3_history"),
    "train_crowd_td3_lidar.yaml": ("td3", "lidar", "crowd_td3_lidar"),
    "train_dynbarn_td3_history.yaml": ("td3", "lidar", "dynbarn_td3_history"),
    "train_dynbarn_td3_predictive.yaml": ("td3", "lidar", "dynbarn_td3_predictive"),
}


def write(path: Path, sections: dict[str, dict[str, Any]]) -> Path:
    """A params file with a ``ros__parameters`` mapping per node section."""
    path.write_text(yaml.safe_dump({node: {"ros__parameters": params}
                                    for node, params in sections.items()}))
    return path


# --- loading the shipped files ------------------------------------------------------------------


def test_every_shipped_training_file_is_listed_here() -> None:
    assert sorted(p.name for p in CONFIG.glob("train_*.yaml")) == sorted(SHIPPED)


@pytest.mark.parametrize("name", sorted(SHIPPED))
def test_a_shipped_training_file_loads_with_its_algorithm_and_sensor(name: str) -> None:
    path = CONFIG / name
    run = load_run_config([path])
    algorithm, sensor, run_name = SHIPPED[name]
    assert (run.train.algorithm, run.env.sensor) == (algorithm, sensor)
    raw = yaml.safe_load(path.read_text())
    trainer = raw["trainer"]["ros__parameters"]
    assert run.name == trainer["run"] == run_name
    assert run.train.max_steps == trainer["max_steps"]
    assert run.train.policy.net_arch == tuple(trainer["policy"]["net_arch"])
    assert run.train.epsilon.initial == trainer.get("epsilon", {}).get("initial", 0.0)
    assert run.train.reward_scale == trainer.get("reward_scale", 1.0)
    assert run.train.off_policy
    assert dict(run.env.sim_params) == raw["sim"]["ros__parameters"]
    assert run.env.sim_params["depth.enabled"] is ("depth" in run.env.observed)
    assert run.sources == (str(path),)


def test_the_run_name_defaults_to_algorithm_and_sensor(tmp_path: Path) -> None:
    over = write(tmp_path / "over.yaml", {"trainer": {"run": ""}})
    assert load_run_config([LIDAR_TD3, over]).name == "td3_lidar"
    assert load_run_config([LIDAR_TD3, over], train={"algorithm": "sac"}).name == "sac_lidar"


def test_later_files_win_key_by_key_in_every_section(tmp_path: Path) -> None:
    """As ROS merges several --params-file: only the keys the second file names change, nested
    mappings included (``curriculum.up`` changes, ``curriculum.down`` stays)."""
    over = write(tmp_path / "over.yaml", {
        "trainer": {"learning_rate": 0.01, "curriculum": {"up": 0.9}},
        "nav_env": {"reward": {"goal": 500.0}},
        "sim": {"world_variant": 3},
    })
    base = load_run_config([LIDAR_TD3])
    merged = load_run_config([LIDAR_TD3, over])
    assert merged.train.learning_rate == 0.01
    assert merged.train.curriculum.up == 0.9
    assert merged.train.curriculum.down == base.train.curriculum.down == 0.3
    assert merged.train.max_steps == base.train.max_steps
    assert merged.env.reward.goal == 500.0
    assert merged.env.reward.collision == base.env.reward.collision
    assert merged.env.sim_params["world_variant"] == 3
    assert merged.env.sim_params["robot"] == "jackal"
    # the order matters: the base file last puts its values back
    assert load_run_config([over, LIDAR_TD3]).train.learning_rate == base.train.learning_rate


def test_dotted_overrides_apply_after_the_files() -> None:
    run = load_run_config([LIDAR_TD3], train={"epsilon.initial": 0.0, "max_steps": 7},
                          env={"reward.goal": 1.0}, sim={"world_variant": 2})
    assert run.train.epsilon.initial == 0.0 and run.train.max_steps == 7
    assert run.env.reward.goal == 1.0 and run.env.sim_params["world_variant"] == 2


def test_a_sim_only_file_with_a_wildcard_section_sets_the_sim() -> None:
    run = load_run_config([LIDAR_TD3, CONFIG / "sim_indoor_jackal_depth.yaml"])
    assert run.env.sim_params["depth.enabled"] is True


# --- bad keys and values ------------------------------------------------------------------------


def test_an_unknown_trainer_key_suggests_the_close_one(tmp_path: Path) -> None:
    bad = write(tmp_path / "bad.yaml", {"trainer": {"learning_rat": 0.1}})
    with pytest.raises(ConfigError, match=r"unknown key 'learning_rat'; did you mean "
                                          r"'learning_rate'") as err:
        load_run_config([LIDAR_TD3, bad])
    assert str(bad) in str(err.value) and "trainer" in str(err.value)


def test_an_unknown_nested_trainer_key_suggests_the_close_one() -> None:
    with pytest.raises(ConfigError, match=r"'epsilon.decya'; did you mean 'epsilon.decay'"):
        load_run_config([LIDAR_TD3], train={"epsilon.decya": 0.9})


@pytest.mark.parametrize(("key", "value"), [
    ("algorithm", "foo"),
    ("epsilon.initial", 1.5),
    ("epsilon.initial", -0.1),
    ("epsilon.decay", 0.0),
    ("epsilon.min", 2.0),
    ("policy.net_arch", []),
    ("policy.critic_arch", [64, 0]),
    ("policy.cnn_channels", []),
    ("policy.activation", "sigmoid"),
    ("batch_size", 0),
    ("max_steps", -5),
    ("learning_starts", -1),
    ("gamma", 1.5),
    ("tau", 0.0),
    ("device", "tpu"),
    ("learning_rate", "fast"),
    ("n_envs", 1.5),
])
def test_a_bad_value_is_an_error_naming_its_key(key: str, value: Any) -> None:
    with pytest.raises(ConfigError, match=rf"{re.escape(key)}: {re.escape(repr(value))}") as err:
        load_run_config([LIDAR_TD3], train={key: value})
    assert str(LIDAR_TD3) in str(err.value)


def test_ppo_refuses_epsilon_greedy() -> None:
    with pytest.raises(ConfigError, match=r"epsilon.initial: 0.2 is invalid; expected 0 for ppo"):
        load_run_config([LIDAR_TD3], train={"algorithm": "ppo", "epsilon.initial": 0.2})
    run = load_run_config([LIDAR_TD3], train={"algorithm": "ppo", "epsilon.initial": 0.0})
    assert run.train.algorithm == "ppo" and not run.train.off_policy


def test_an_unknown_env_key_is_named_with_the_file(tmp_path: Path) -> None:
    bad = write(tmp_path / "bad.yaml", {"nav_env": {"rewrd": {"goal": 1.0}}})
    with pytest.raises(ConfigError, match=r"unknown key 'rewrd.goal'") as err:
        load_run_config([LIDAR_TD3, bad])
    assert str(bad) in str(err.value)


def test_a_missing_params_file_is_named(tmp_path: Path) -> None:
    with pytest.raises(ConfigError, match=re.escape(str(tmp_path / "nope.yaml"))):
        load_run_config([tmp_path / "nope.yaml"])


# --- key:value overrides ------------------------------------------------------------------------


def test_overrides_are_read_as_yaml() -> None:
    items = ["learning_rate:0.001", "policy.net_arch:[64,64]", "algorithm:sac",
             "tensorboard:false", "run:", "max_steps:100"]
    assert parse_overrides(items, flag="--hyperparams") == {
        "learning_rate": 0.001, "policy.net_arch": [64, 64], "algorithm": "sac",
        "tensorboard": False, "run": "", "max_steps": 100}


def test_an_override_value_may_hold_colons() -> None:
    assert parse_overrides(["episodes.file:/a:b.json"], flag="--env-kwargs") == {
        "episodes.file": "/a:b.json"}


@pytest.mark.parametrize("item", ["learning_rate", ":0.1", "  :1"])
def test_an_override_without_key_and_colon_is_refused(item: str) -> None:
    with pytest.raises(ConfigError, match=rf"--hyperparams {re.escape(repr(item))}: expected "
                                          r"key:value"):
        parse_overrides([item], flag="--hyperparams")


def test_an_override_that_is_not_yaml_is_refused() -> None:
    with pytest.raises(ConfigError, match=r"--env-kwargs 'x:\[1,': the value is not valid YAML"):
        parse_overrides(["x:[1,"], flag="--env-kwargs")


def test_an_override_in_exponent_notation_is_a_number() -> None:
    params = parse_overrides(["learning_rate:1e-3"], flag="--hyperparams")
    assert load_run_config([LIDAR_TD3], train=params).train.learning_rate == 0.001


def test_replace_applies_dotted_overrides_and_validates() -> None:
    config = TrainConfig()
    changed = config.replace(**{"epsilon.decay": 0.5, "batch_size": 8})
    assert changed.epsilon.decay == 0.5 and changed.batch_size == 8
    assert config.epsilon.decay == 0.9999  # frozen: the original is untouched
    with pytest.raises(ConfigError, match="batch_size"):
        config.replace(batch_size=0)


# --- a run's config.yaml ------------------------------------------------------------------------


def test_to_yaml_loads_back_as_the_same_run(tmp_path: Path) -> None:
    run = load_run_config([CONFIG / "train_goto_depth_sac.yaml"],
                          train={"policy.net_arch": [8, 4], "epsilon.decay": 0.9,
                                 "checkpoint.replay_buffer": True, "run": "back"},
                          env={"reward.distance": 3.0, "episodes.ordered": True},
                          sim={"world_variant": 4})
    path = tmp_path / "config.yaml"
    path.write_text(run.to_yaml())
    data = yaml.safe_load(path.read_text())
    assert list(data) == ["sim", "nav_env", "trainer"]
    back = load_run_config([path])
    assert isinstance(back, RunConfig)
    assert back.train == run.train
    assert back.env == run.env
    assert dict(back.env.sim_params) == dict(run.env.sim_params)  # not part of ==
    assert back.env.sim_params["world_variant"] == 4
    assert back.train.policy.net_arch == (8, 4) and back.env.reward.distance == 3.0


def test_train_config_params_round_trip() -> None:
    config = train_config_from_params({"algorithm": "ppo", "epsilon": {"initial": 0.0},
                                       "ppo": {"n_steps": 64}})
    assert config.ppo.n_steps == 64
    assert train_config_from_params(config.to_params()) == config


# --- -p items: trainer or env -------------------------------------------------------------------


def test_p_items_are_routed_by_their_key() -> None:
    train, env = route_params({"learning_rate": 0.01, "epsilon.decay": 0.9,
                               "transport": "ros", "reward.goal": 10.0, "runs_dir": "/x"})
    assert train == {"learning_rate": 0.01, "epsilon.decay": 0.9, "runs_dir": "/x"}
    assert env == {"transport": "ros", "reward.goal": 10.0}


def test_an_unknown_p_item_is_refused_with_a_suggestion() -> None:
    with pytest.raises(ConfigError, match=r"-p parameters: unknown key 'transprt'; did you mean "
                                          r"'transport'"):
        route_params({"transprt": "ros"})
    with pytest.raises(ConfigError, match=r"'epsilon.inital'; did you mean 'epsilon.initial'"):
        route_params({"epsilon.inital": 0.1})


# --- --ros-args ---------------------------------------------------------------------------------


def test_ros_args_are_taken_out_of_the_command_line() -> None:
    plain, ros = split_ros_args([
        "-n", "10", "--ros-args", "--params-file", "a.yaml", "-p", "learning_rate:=0.001",
        "--param", "policy.net_arch:=[8, 8]", "-p", "transport:=ros", "-p", "tensorboard:=false",
        "-p", "run:=", "--params-file", "b.yaml", "--", "--run", "x"])
    assert plain == ["-n", "10", "--run", "x"]
    assert ros.params_files == ["a.yaml", "b.yaml"]
    assert ros.params == {"learning_rate": 0.001, "policy.net_arch": [8, 8], "transport": "ros",
                          "tensorboard": False, "run": ""}
    assert isinstance(ros.params["learning_rate"], float)
    assert ros.rest == []


def test_other_ros_args_are_kept_with_their_values() -> None:
    plain, ros = split_ros_args(["--ros-args", "-r", "__ns:=/robot1", "--log-level", "debug",
                                 "--enable-rosout-logs", "-p", "a:=1"])
    assert plain == []
    assert ros.rest == ["-r", "__ns:=/robot1", "--log-level", "debug", "--enable-rosout-logs"]
    assert ros.params == {"a": 1}


def test_without_a_double_dash_the_segment_runs_to_the_end_and_may_repeat() -> None:
    plain, ros = split_ros_args(["--ros-args", "-p", "a:=1", "--", "--x", "--ros-args", "-p",
                                 "b:=two", "--log-level", "warn"])
    assert plain == ["--x"]
    assert ros.params == {"a": 1, "b": "two"}
    assert ros.rest == ["--log-level", "warn"]


@pytest.mark.bad_input
@pytest.mark.parametrize("command", ["test", "train"])
def test_a_commands_flag_inside_ros_args_is_refused_in_one_line(
        command: str, capsys: pytest.CaptureFixture[str]) -> None:
    """``--no-progress`` after ``--params-file FILE`` is inside the ROS segment: refused (exit
    2, one line saying where it belongs), never silently dropped; after ``--`` it counts."""
    from pic4rl_agents.testing import tester
    from pic4rl_agents.training import train

    main = tester.main if command == "test" else train.main
    code = main(["--ros-args", "--params-file", "x.yaml", "--no-progress"])
    assert code == 2
    assert capsys.readouterr().err.splitlines() == [
        f"pic4rl-{command}: --no-progress: not a ROS argument, but inside --ros-args (which "
        "runs to a lone -- or to the end of the line); give the command's own flags before "
        "--ros-args or after --"]
    plain, _ = split_ros_args(["--ros-args", "--params-file", "x.yaml", "--", "--no-progress"])
    assert plain == ["--no-progress"]


@pytest.mark.parametrize(("argv", "message"), [
    (["--ros-args", "--params-file"], "--params-file: expected a file name"),
    (["--ros-args", "-p"], "-p: expected key:=value"),
    (["--ros-args", "-p", "learning_rate=0.1"], "-p: expected key:=value"),
    (["--ros-args", "--param", "x"], "--param: expected key:=value"),
    (["--ros-args", "-p", "x:=[1,"], "not valid YAML"),
])
def test_a_ros_arg_without_its_value_is_refused(argv: list[str], message: str) -> None:
    with pytest.raises(ConfigError, match=re.escape(message)):
        split_ros_args(argv)


def test_ros_args_survive_a_round_trip_through_as_args() -> None:
    ros = RosArgs(params_files=["a.yaml", "dir/b c.yaml"],
                  params={"learning_rate": 0.001, "policy.net_arch": [64, 64], "transport": "ros",
                          "tensorboard": True, "run": "", "episodes.file": "/x:y.json",
                          "seed": 3, "agent": "123", "record.topics": ["scan", "odom"]},
                  rest=["-r", "__ns:=/r1", "--log-level", "warn"])
    args = ros.as_args()
    assert args[0] == "--ros-args"
    plain, back = split_ros_args(["--run", "z", *args])
    assert plain == ["--run", "z"]
    assert back == ros
    assert back.params["agent"] == "123"  # a string that looks like a number stays a string
