"""The task registry: each entry of ``TASK_TABLE`` drives its env ids, the task built, its reward
scales, its section and its experts; nothing else lists tasks (a baseline names the tasks it
drives in its own table)."""

from __future__ import annotations

import dataclasses

import gymnasium as gym
import numpy as np
import pytest

import pic4rl_bridge
from pic4rl_base.geometry import Footprint
from pic4rl_base.schema import param_names
from pic4rl_bridge.baselines.registry import BASELINE_TASKS, check_fits
from pic4rl_bridge.config import EnvConfig, env_config_from_params
from pic4rl_bridge.errors import ConfigError
from pic4rl_bridge.robot_info import RobotInfo
from pic4rl_bridge.settings.tasks import (TASK_TABLE, EnvId, ExploreConfig, GoToPoseReward,
                                          PersonConfig, PersonReward,
                                          TaskName, TaskSpec, VineyardConfig, VineyardReward,
                                          env_ids, task_spec)
from pic4rl_bridge.tasks import make_task
from pic4rl_bridge.tasks.goto import GoToPoseLidar, GoToPoseSensors
from pic4rl_sim.engine.robot_specs import DepthCameraSpec, LidarSpec

JACKAL = RobotInfo(name="jackal", footprint=Footprint(length_m=0.5, width_m=0.43),
                   omni=False, min_linear_m_s=0.0, max_linear_m_s=0.5,
                   max_angular_rad_s=1.0, max_lateral_m_s=0.0, control_dt_s=0.1,
                   specs={"lidar": LidarSpec(), "depth": DepthCameraSpec()})


def test_the_registered_ids_are_the_entries_ids_with_their_sensor_and_sim_defaults():
    assert pic4rl_bridge.ENV_IDS == {
        "pic4rl/GoToPoseLidar-v0": {"task": "goToPose", "sensor": "lidar"},
        "pic4rl/GoToPoseDepth-v0": {"task": "goToPose", "sensor": "depth",
                                    "sim_defaults": {"depth.enabled": True}},
        "pic4rl/GoToPoseLidarDepth-v0": {"task": "goToPose", "sensor": "lidar",
                                         "sim_defaults": {"depth.enabled": True},
                                         "sensors": ["lidar", "depth"]},
        "pic4rl/Vineyard-v0": {"task": "vineyard", "sensor": "depth",
                               "sim_defaults": {"world": "vineyard", "depth.enabled": True}},
        "pic4rl/PersonMonitoring-v0": {"task": "personMonitoring", "sensor": "lidar",
                                       "sim_defaults": {"robot": "omni", "world": "person"}},
        "pic4rl/ExploreLidar-v0": {"task": "explore", "sensor": "lidar"},
        "pic4rl/ExploreDepth-v0": {"task": "explore", "sensor": "depth",
                                   "sim_defaults": {"depth.enabled": True}},
    }
    for env_id, kwargs in pic4rl_bridge.ENV_IDS.items():
        assert gym.spec(env_id).kwargs == kwargs
        spec = TASK_TABLE[kwargs["task"]]
        assert {kwargs["sensor"], *kwargs.get("sensors", ())} <= set(spec.sensors)


def test_an_entry_alone_adds_an_id(monkeypatch):
    """A new entry's ids come out of ``env_ids`` with its task, sensor and sim defaults."""
    toy = TaskSpec("toy", (EnvId("pic4rl/Toy-v0", "depth", {"world": "person"}),),
                   sensors=("depth",), reward=GoToPoseReward,
                   build="pic4rl_bridge.tasks.goto:build")
    monkeypatch.setitem(TASK_TABLE, "toy", toy)
    assert env_ids()["pic4rl/Toy-v0"] == {"task": "toy", "sensor": "depth",
                                         "sim_defaults": {"world": "person"}}
    # its build is found by name: goToPose's, through the config's sensor
    task = toy.make(EnvConfig(sensor="depth"), JACKAL, None)
    assert isinstance(task, GoToPoseSensors) and task.required == {"goal", "depth"}


def test_an_entrys_ids_observe_through_its_sensors():
    with pytest.raises(ConfigError, match=r"task 'toy': id 'pic4rl/Toy-v0' observes through "
                                          r"'lidar'; expected one of depth"):
        TaskSpec("toy", (EnvId("pic4rl/Toy-v0", "lidar"),), sensors=("depth",),
                 reward=VineyardReward, build="pic4rl_bridge.tasks.vineyard:build")


def test_the_task_choice_is_the_registry():
    assert [t.value for t in TaskName] == ["goToPose", "vineyard", "personMonitoring",
                                           "explore"]
    with pytest.raises(ConfigError, match=r"task: 'toy' is invalid; expected one of goToPose, "
                                          r"vineyard, personMonitoring, explore"):
        env_config_from_params({"task": "toy"})
    with pytest.raises(ConfigError, match="task: 'toy' is invalid"):
        task_spec("toy")


@pytest.mark.parametrize("sensor, cls, shape", [("lidar", GoToPoseLidar, (40,)),
                                                ("depth", GoToPoseSensors, None)])
def test_make_task_builds_through_the_entry(sensor, cls, shape):
    task = make_task(EnvConfig(sensor=sensor), JACKAL)
    assert type(task) is cls
    if shape is not None:
        assert task.observation_space.shape == shape


def test_each_task_reads_its_own_reward_scales_from_the_one_reward_section():
    reward = env_config_from_params({"reward.progress": 7.0, "reward.facing": 3.0,
                                     "reward.goal": 500.0, "reward.collision": -9.0}).reward
    for cls in (GoToPoseReward, VineyardReward, PersonReward):
        assert isinstance(reward, cls)
    assert (reward.goal, reward.progress, reward.facing, reward.collision) == (
        500.0, 7.0, 3.0, -9.0)
    own = {spec.name: {f.name for f in dataclasses.fields(spec.reward)} for spec in TASK_TABLE.values()}
    assert own["vineyard"] == {"collision", "step", "progress", "centering", "row_end"}
    assert own["explore"] == {"collision", "step", "area"}
    assert own["personMonitoring"] == {"collision", "step", "facing", "person_distance",
                                       "bearing"}
    assert "goal" in own["goToPose"] and "progress" not in own["goToPose"]
    # the table holds every task's scales once, and no other
    keys = {n.split(".", 1)[1] for n in param_names(EnvConfig) if n.startswith("reward.")}
    assert keys == set().union(*own.values())
    with pytest.raises(ConfigError, match=r"unknown key 'reward.progres'; did you mean "
                                          r"'reward.progress'\?"):
        env_config_from_params({"reward.progres": 1.0})


def test_a_tasks_section_is_its_entrys():
    sections = {spec.section for spec in TASK_TABLE.values() if spec.section is not None}
    assert sections == {("vineyard", VineyardConfig), ("person", PersonConfig),
                        ("explore", ExploreConfig)}
    config = env_config_from_params({"task": "personMonitoring", "person.distance_m": 1.5,
                                     "vineyard.end_tolerance_m": 0.2})
    assert config.person == PersonConfig(distance_m=1.5)
    assert config.vineyard.end_tolerance_m == 0.2
    with pytest.raises(ConfigError, match=r"vineyard.centerline: \(1.0, 2.0\) is invalid"):
        EnvConfig(vineyard=VineyardConfig(centerline=(1.0, 2.0)))


def test_the_baselines_come_from_their_table_and_the_facts_from_the_entries():
    assert BASELINE_TASKS == {"proportional": ("goToPose",), "dwa": ("goToPose",),
                              "planner": ("goToPose",), "predictive": ("goToPose",),
                              "explorer": ("goToPose",),
                              "orca": ("goToPose",), "centerline": ("vineyard",),
                              "row_follower": ("vineyard",),
                              "dwa_heading": ("personMonitoring",),
                              "frontier": ("explore",), "random_walk": ("explore",)}
    check_fits("centerline", EnvConfig(task="vineyard"))
    with pytest.raises(ConfigError, match=r"--baseline dwa: it drives goToPose; this env's "
                                          r"task is 'vineyard'\. Test it with --baseline "
                                          r"centerline or row_follower"):
        check_fits("dwa", EnvConfig(task="vineyard"))
    assert TASK_TABLE["goToPose"].fact_name("depth") == "goToPose/depth"
    assert TASK_TABLE["vineyard"].fact_name("depth") == "vineyard"
    assert [s.name for s in TASK_TABLE.values() if s.uses_world] == ["vineyard"]


def test_make_task_refuses_what_the_entry_cannot_build():
    with pytest.raises(ConfigError, match="'personMonitoring' needs an omnidirectional robot"):
        make_task(EnvConfig(task="personMonitoring"), JACKAL)
    with pytest.raises(ConfigError, match=r"vineyard.centerline: \[\] is invalid for task "
                                          r"'vineyard' \(no world\)"):
        make_task(EnvConfig(task="vineyard"), JACKAL)
    task = make_task(EnvConfig(task="vineyard", vineyard=VineyardConfig(
        centerline=(0.0, 0.0, 5.0, 0.0))), JACKAL)
    assert np.allclose(task.lanes[0], [[0.0, 0.0], [5.0, 0.0]])
