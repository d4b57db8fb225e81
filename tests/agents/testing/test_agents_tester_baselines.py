"""Where ``pic4rl-test``'s baselines run: it prints each baseline's env and step budget (an
agent's env gives DWA the agent's 300 steps, a params file its own 500), and a baseline runs in
the test env's one world as the agent does (a world per episode is unset for it too)."""

from __future__ import annotations

import contextlib
import io
from pathlib import Path

from agents_helpers import ROOT

from pic4rl_agents.testing import tester
from pic4rl_agents.testing import plan as testplan

TD3_LIDAR, BARN = ROOT / "checkpoints" / "td3_lidar", ROOT / "checkpoints" / "barn_td3_explorer"
ENV = ROOT / "config" / "env_goto_lidar.yaml"
# A walled 12 m square with one crate: a world of the user's own (MJCF).
MJCF = """<mujoco><worldbody><geom type="plane" size="10 10 .1"/>
<geom type="box" size="0.5 0.5 0.5" pos="3 3 0.5"/>
<geom type="box" size="6 0.1 0.5" pos="0 6 0.5"/><geom type="box" size="6 0.1 0.5" pos="0 -6 0.5"/>
<geom type="box" size="0.1 6 0.5" pos="6 0 0.5"/><geom type="box" size="0.1 6 0.5" pos="-6 0 0.5"/>
</worldbody></mujoco>"""


def test_each_baseline_says_which_env_it_runs_in_and_its_step_budget() -> None:
    agent_dwa = testplan.resolve_agents(testplan.TestPlan(agents=(str(TD3_LIDAR),),
                                                          baselines=("dwa",)))[1]
    assert agent_dwa.env_line == (
        f"dwa runs in the env of agent td3_lidar (sensor lidar, from {TD3_LIDAR / 'config.yaml'}) "
        "at the robot's full speed range: 300 steps an episode (episode_max_steps)")
    file_dwa, = testplan.resolve_agents(testplan.TestPlan(baselines=("dwa",),
                                                          params_files=(str(ENV),)))
    assert file_dwa.env_line == (f"dwa runs in the params files' env (sensor lidar, from {ENV}): "
                                 "500 steps an episode (episode_max_steps)")


def test_the_tester_prints_the_baselines_env_line(tmp_path: Path) -> None:
    err = io.StringIO()
    with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(err):
        code = tester.main(["--baseline", "proportional", "--episodes", "1", "--bags",
                            str(tmp_path), "--no-progress", "--env-kwargs",
                            "episode_max_steps:4", "--ros-args", "--params-file", str(ENV)])
    assert code == 0, err.getvalue()
    lines = err.getvalue().splitlines()
    assert lines.count(f"proportional runs in the params files' env (sensor lidar, from {ENV} + "
                       "command line): 4 steps an episode (episode_max_steps)") == 1


def test_a_map_aware_baseline_beside_a_world_per_episode_agent_runs_in_the_test_world(
        tmp_path: Path) -> None:
    """barn_td3_explorer trained on a world per episode (episodes.world_variants); the test
    env unsets it for the agent, and now for the planner beside it too."""
    world = tmp_path / "box.xml"
    world.write_text(MJCF)
    specs = testplan.resolve_agents(testplan.TestPlan(
        agents=(str(BARN),), baselines=("planner",), sim_overrides={"world": str(world)}))
    assert [s.name for s in specs] == ["barn_td3_explorer", "planner"]
    for spec in specs:
        assert spec.run.env.episodes.world_variants == ""
        assert spec.run.env.sim_params["world"] == str(world)
