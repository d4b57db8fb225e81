"""The classical baselines: DWA and the privileged planner go round a wall that the
proportional controller drives into; DWA never commands beyond the robot's velocity and acceleration limits, and a baseline that does
not fit the task is refused before anything runs.

The wall world is analytic: the 10 m walled arena of ``tests/ros_helpers.py`` without its
furniture and a 0.2 × 2 m wall across the straight line from the start (-2, 0) to the goal
(2, 0).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from world_helpers import walled_square_mjcf

from pic4rl_base import params_file
from pic4rl_base.geometry import Footprint, Pose2D
from pic4rl_bridge.baselines.dwa import DwaController
from pic4rl_bridge.baselines.registry import make_baseline
from pic4rl_bridge.config import EnvConfig, load_env_config
from pic4rl_bridge.control.actions import planar_command
from pic4rl_bridge.env import NavEnv
from pic4rl_bridge.errors import ConfigError
from pic4rl_bridge.readings.frame import ScanData, SensorFrame
from pic4rl_bridge.robot_info import RobotInfo
from pic4rl_bridge.settings.baselines import BASELINES_NODE, DwaConfig, baselines_config
from pic4rl_sim.engine.geometry import Twist2D

ROOT = Path(__file__).resolve().parents[3]
CONFIG = ROOT / "config" / "env_goto_lidar.yaml"
WALL_MJCF = walled_square_mjcf(
    5.0, '<geom name="wall" type="box" pos="0 0 0.5" size="0.1 1.0 0.5"/>', model="wall")
EPISODE = {"start": [-2.0, 0.0, 0.0], "goal": [2.0, 0.0]}
#: The Jackal of env_goto_lidar.yaml: v in [0, 0.5] m/s, |ω| <= 1 rad/s, 3 m/s², 6 rad/s².
JACKAL = RobotInfo(name="jackal", footprint=Footprint(length_m=0.508, width_m=0.430), omni=False,
                   min_linear_m_s=0.0, max_linear_m_s=0.5, max_angular_rad_s=1.0,
                   max_lateral_m_s=0.0, control_dt_s=0.1,
                   mounts={"lidar": Pose2D(0.12, 0.0, 0.0)},
                   max_linear_accel_m_s2=3.0, max_angular_accel_rad_s2=6.0)


@pytest.fixture(scope="module")
def wall(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("world") / "wall.xml"
    path.write_text(WALL_MJCF)
    return path


def drive(name: str, world: Path) -> tuple[str, list[Twist2D]]:
    """One episode of baseline ``name`` from (-2, 0) to (2, 0); its outcome and commands."""
    env = NavEnv(CONFIG, sim={"world": str(world)}, overrides={"episode_max_steps": 300})
    commands: list[Twist2D] = []
    try:
        controller = make_baseline(name, env.config, env.scenario.robot, env.scenario.world)
        env.reset(seed=0, options=EPISODE)
        controller.reset()
        done, info = False, {}
        while not done:
            action = controller.action(env.frame)
            commands.append(env.task.command(action))
            _, _, terminated, truncated, info = env.step(action)
            done = terminated or truncated
    finally:
        env.close()
    return info["outcome"], commands


def test_dwa_goes_round_the_wall_the_proportional_controller_hits(wall):
    assert drive("proportional", wall)[0] == "collision"
    outcome, commands = drive("dwa", wall)
    assert outcome == "goal"
    window = [(abs(b.vx - a.vx), abs(b.wz - a.wz)) for a, b in zip(commands, commands[1:])]
    assert max(dv for dv, _ in window) <= 3.0 * 0.1 + 1e-6  # within the acceleration window
    assert max(dw for _, dw in window) <= 6.0 * 0.1 + 1e-6


def test_the_planner_goes_round_the_wall_through_its_own_map(wall):
    """The privileged planner knows the wall from the world, not from the scan: it reaches the
    goal round the wall with the clearance its plan keeps."""
    outcome, commands = drive("planner", wall)
    assert outcome == "goal"
    assert max(abs(c.wz) for c in commands) <= 1.0 + 1e-9
    assert all(0.0 <= c.vx <= 0.5 + 1e-9 for c in commands)
    assert min(c.vx for c in commands[:3]) >= 0.0


def test_the_planner_needs_a_simulated_world():
    with pytest.raises(ConfigError, match="map"):
        make_baseline("planner", EnvConfig(), JACKAL)


def _scan(ranges: list[float]) -> ScanData:
    values = np.asarray(ranges, np.float32)
    return ScanData(values, -math.pi, 2 * math.pi / len(values), 0.1, 10.0, JACKAL.lidar_mount)


@settings(max_examples=60, deadline=None)
@given(ranges=st.lists(st.one_of(st.floats(0.05, 10.0), st.just(math.inf)), min_size=8,
                       max_size=72),
       goal=st.tuples(st.floats(-8, 8), st.floats(-8, 8)),
       start=st.tuples(st.floats(-0.5, 0.5), st.floats(-1.0, 1.0)),
       steps=st.integers(1, 6))
def test_dwa_never_commands_beyond_the_robots_limits(ranges, goal, start, steps):
    """From any commanded (v, ω), over random scans and goals, each command stays within the
    velocity ranges and one control period's acceleration of the one before, and the env's
    action map gives back the same velocities."""
    dwa = DwaController(JACKAL, DwaConfig(), collision_tolerance_m=0.05)
    dwa.reset()
    dwa._last = (min(max(start[0], 0.0), 0.5), start[1])  # the window's centre: a past command
    previous = dwa._last
    for k in range(steps):
        frame = SensorFrame(k, Pose2D(0.0, 0.0, 0.0), Twist2D(), goal=goal,
                            scan=_scan(np.roll(ranges, k).tolist()))
        v, w = dwa.command(frame)
        assert 0.0 <= v <= 0.5 and abs(w) <= 1.0
        assert abs(v - previous[0]) <= 0.3 + 1e-9 and abs(w - previous[1]) <= 0.6 + 1e-9
        dwa._last = (v, w)
        command = planar_command(dwa.action(frame), JACKAL)
        assert command.vx == pytest.approx(dwa._last[0], abs=1e-6)
        assert command.wz == pytest.approx(dwa._last[1], abs=1e-6)
        previous = dwa._last


def test_a_baseline_that_does_not_fit_the_task_is_refused():
    with pytest.raises(ConfigError, match="personMonitoring"):
        make_baseline("proportional", EnvConfig(task="personMonitoring"), JACKAL)
    robot = RobotInfo(name="bare", footprint=Footprint(radius_m=0.2), omni=False,
                      min_linear_m_s=0.0, max_linear_m_s=0.5, max_angular_rad_s=1.0,
                      max_lateral_m_s=0.0, control_dt_s=0.1)
    with pytest.raises(ConfigError, match="acceleration limits"):
        make_baseline("dwa", EnvConfig(), robot)


def test_the_baselines_settings_are_their_own_section(tmp_path):
    """``baselines:`` beside ``nav_env:`` sets the DWA baseline; the env refuses the old
    ``baselines.*`` keys with where they went; the person follower's DWA is ``person.dwa``."""
    path = tmp_path / "p.yaml"
    path.write_text("nav_env:\n  ros__parameters: {task: goToPose}\n"
                    "baselines:\n  ros__parameters: {dwa.horizon_s: 2.0, dwa.linear_samples: 5}\n")
    section = params_file.load([path], (BASELINES_NODE, "nav_env"))[BASELINES_NODE]
    chosen = baselines_config(section, {"dwa.linear_samples": 9}, where=str(path))
    assert (chosen.dwa.horizon_s, chosen.dwa.linear_samples) == (2.0, 9)
    dwa = make_baseline("dwa", load_env_config(path), JACKAL, settings=chosen)
    assert isinstance(dwa, DwaController) and dwa.config is chosen.dwa
    assert len(dwa.window(0.2, 0.0)[0]) == 9
    with pytest.raises(ConfigError, match=r"'baselines.dwa.horizon_s' is no env parameter: "
                                          r"baseline settings are the params file's "
                                          r"'baselines:' section \(dwa.horizon_s\)"):
        EnvConfig().replace(**{"baselines.dwa.horizon_s": 2.0})
    with pytest.raises(ConfigError, match=r"baselines.dwa.rollout_dt_s: 3.0 is invalid; "
                                          r"expected at most baselines.dwa.horizon_s=1.5"):
        baselines_config({}, {"dwa.rollout_dt_s": 3.0})
    with pytest.raises(ConfigError, match=r"person.dwa.horizon_s: -1.0 is invalid"):
        EnvConfig().replace(**{"person.dwa.horizon_s": -1.0, "person.dwa.rollout_dt_s": 0.0})
    assert EnvConfig().replace(**{"person.dwa.horizon_s": 2.5}).person.dwa.horizon_s == 2.5


def test_the_baseline_table_drives_every_registered_task_and_no_other() -> None:
    from pic4rl_bridge.baselines.registry import BASELINE_TABLE
    from pic4rl_bridge.settings.tasks import TASK_TABLE

    driven = {t for spec in BASELINE_TABLE.values() for t in spec.tasks}
    assert driven == set(TASK_TABLE)


def test_every_expert_is_a_baseline_of_the_table_that_drives_its_task() -> None:
    """Imitation's experts come from the baseline table: each ``TASK_TABLE`` expert name is one
    baseline's ``expert``, made by that baseline's own maker, and a name no baseline answers
    to is refused in one line."""
    from pic4rl_bridge.baselines.follow import HeadingController
    from pic4rl_bridge.baselines.registry import BASELINE_TASKS, EXPERT_BASELINES, make_expert
    from pic4rl_bridge.settings.tasks import EXPERT_TASKS

    assert EXPERT_BASELINES == {"planner": "planner", "explorer": "explorer",
                                "predictive": "predictive",
                                "centerline": "centerline", "dwa_heading": "dwa_heading"}
    assert set(EXPERT_BASELINES) == set(EXPERT_TASKS)
    for expert, baseline in EXPERT_BASELINES.items():
        assert EXPERT_TASKS[expert] in BASELINE_TASKS[baseline]
    person = EnvConfig().replace(task="personMonitoring")
    assert isinstance(make_expert("dwa_heading", person, JACKAL, None), HeadingController)
    with pytest.raises(ConfigError, match="imitation.expert: 'dwa' is no baseline's expert; "
                                          "expected one of planner, predictive, explorer, "
                                          "centerline, "
                                          "dwa_heading"):
        make_expert("dwa", EnvConfig(), JACKAL, None)
