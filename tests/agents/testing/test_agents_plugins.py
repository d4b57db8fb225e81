"""Policy plugins (``pic4rl_bridge.control.plugin``): a controller this project never saw,
written into ``tmp_path``, judged by ``pic4rl-test`` under its own name with no package file
edited; one that raises, returns NaN or the wrong shape ends that episode ``aborted`` naming
it and its error while the next episode runs; path, module and entry-point references; a bench
suite naming a plugin; the example gap follower into BARN's table."""

from __future__ import annotations

import json
import textwrap
from pathlib import Path

import numpy as np
import pytest

from pic4rl_agents.testing import policies, tester
from pic4rl_agents.testing.plan import TestPlan, resolve_agents
from pic4rl_agents.testing.tester import drive_and_judge
from pic4rl_bridge.errors import ConfigError
from pic4rl_metrics import read_episode
from pic4rl_metrics.cli import commands as cli

REPO = Path(__file__).resolve().parents[3]
GOTO = str(REPO / "config" / "env_goto_lidar.yaml")
BARN = str(REPO / "config" / "env_barn.yaml")
STEPS = 25  # each episode's budget: the tests drive a few short episodes

#: A user's controller, as they would write it: the public protocol module only. It drives at
#: (V, W) and writes what ``reset`` told it beside itself; ``FAIL`` breaks episode 0's step 3.
PLUGIN = '''
import json, math
from pathlib import Path
from pic4rl_bridge.control.plugin import Policy

V, W, FAIL = 0.25, 0.1, {fail!r}

class Mine(Policy):
    observes = "frame"
    acts = "velocity"
    name = "my_ctl"

    def __init__(self):
        self.episode, self.step = -1, 0

    def reset(self, robot, task):
        self.episode, self.step = self.episode + 1, 0
        Path(__file__).with_name("seen.json").write_text(json.dumps(
            {{"max_linear": robot.max_linear_m_s, "tolerance": task.goal_tolerance_m,
              "task": task.name}}))

    def act(self, frame):
        self.step += 1
        if self.episode == 0 and self.step == 3:
            if FAIL == "raise":
                raise RuntimeError("lost my map")
            if FAIL == "nan":
                return math.nan, 0.0
            if FAIL == "shape":
                return (V, W, 0.0)
        assert len(frame.scan.ranges) == len(frame.scan.angles())
        return V, W
'''


def _plugin(folder: Path, fail: str = "") -> Path:
    path = folder / "my_ctl.py"
    path.write_text(PLUGIN.format(fail=fail))
    return path


def _plan(tmp_path: Path, agent: str, episodes: int = 2, env: str = GOTO, **kw) -> TestPlan:
    return TestPlan(agents=(agent,), episodes=episodes, bags_dir=tmp_path / "bags", run="r",
                    params_files=(env,), env_overrides={"episode_max_steps": STEPS},
                    progress=False, **kw)


def _bags(run_dir: Path, agent: str) -> list[Path]:
    return sorted((run_dir / agent).glob("episode_*"))


def test_a_plugin_never_seen_is_judged_under_its_name(tmp_path: Path) -> None:
    path = _plugin(tmp_path)
    result = drive_and_judge(_plan(tmp_path, f"{path}:Mine"))
    assert list(result.outcomes) == ["my_ctl"] and len(result.outcomes["my_ctl"]) == 2
    assert list(result.table.index) == ["my_ctl"] and not result.failed
    seen = json.loads((tmp_path / "seen.json").read_text())
    spec = resolve_agents(_plan(tmp_path, f"{path}:Mine"))[0]
    assert seen["tolerance"] == spec.run.env.goal_tolerance_m and seen["task"] == "goToPose"
    for bag in _bags(result.run_dir, "my_ctl"):
        episode = read_episode(bag)
        assert episode.facts.agent == "my_ctl"
        cmd = episode.inputs["cmd"]  # (v, ω) in m/s, rad/s through the normalised action
        np.testing.assert_allclose(cmd.vx, 0.25, atol=1e-5)
        np.testing.assert_allclose(cmd.wz, 0.1, atol=1e-5)
    assert seen["max_linear"] >= 0.25


@pytest.mark.parametrize(("fail", "error"), [
    ("raise", "policy my_ctl: act() raised RuntimeError: lost my map"),
    ("nan", "policy my_ctl: act() returned a non-finite action (nan, 0.0)"),
    ("shape", "policy my_ctl: act() returned shape (3,); expected (v, ω)"),
])
def test_a_failing_plugin_aborts_that_episode_and_the_next_runs(tmp_path: Path, fail: str,
                                                                error: str) -> None:
    path = _plugin(tmp_path, fail)
    result = drive_and_judge(_plan(tmp_path, f"{path}:Mine"))
    outcomes = result.outcomes["my_ctl"]
    assert outcomes[0] == "aborted" and outcomes[1] != "aborted"
    first, second = (read_episode(b) for b in _bags(result.run_dir, "my_ctl"))
    assert first.facts.outcome == "aborted" and first.facts.end_reason == error
    assert len(first.inputs["cmd"].vx) == 2  # stopped at the failing step
    assert second.facts.outcome != "aborted"
    assert len(second.inputs["cmd"].vx) > 2  # the next episode drove on past that step
    assert int(result.table.loc["my_ctl", "n_aborted"]) == 1


def test_path_module_and_entry_point_references_resolve(tmp_path: Path,
                                                        monkeypatch: pytest.MonkeyPatch) -> None:
    package = tmp_path / "labpkg"
    package.mkdir()
    (package / "__init__.py").write_text("")
    _plugin(package)
    monkeypatch.syspath_prepend(str(tmp_path))

    class EntryPoint:
        name, value = "lab_ctl", "labpkg.my_ctl:Mine"

        def load(self) -> object:
            from labpkg.my_ctl import Mine  # type: ignore[import-not-found]

            return Mine

    monkeypatch.setattr(policies, "entry_points", lambda group: (
        [EntryPoint()] if group == policies.ENTRY_POINTS else []))
    for ref in (f"{package / 'my_ctl.py'}:Mine", "labpkg.my_ctl:Mine", "lab_ctl"):
        assert policies.is_plugin(ref), ref
        spec = resolve_agents(_plan(tmp_path, ref))[0]
        assert (spec.name, spec.plugin, spec.model) == ("my_ctl", ref, None)
    renamed = resolve_agents(_plan(tmp_path, "ours=labpkg.my_ctl:Mine"))[0]
    assert renamed.name == "ours" and renamed.run.env.agent == "ours"
    assert not policies.is_plugin(str(tmp_path))  # a run directory stays a model


@pytest.mark.bad_input
@pytest.mark.parametrize(("ref", "message"), [
    ("{d}/nope.py:Mine", "--agent {d}/nope.py:Mine: no such file {d}/nope.py"),
    ("{d}/my_ctl.py:Mien", "--agent {d}/my_ctl.py:Mien: {d}/my_ctl.py has no 'Mien'; did you "
                           "mean 'Mine'?"),
    ("{d}/bad.py:Bad", "--agent {d}/bad.py:Bad: observes = 'lidar' is invalid; expected "
                       "'frame' or 'observation'"),
    ("no_such_pkg_38.mod:X", "--agent no_such_pkg_38.mod:X: cannot import no_such_pkg_38.mod"),
])
def test_a_bad_reference_is_one_line_naming_it(tmp_path: Path, ref: str, message: str) -> None:
    _plugin(tmp_path)
    (tmp_path / "bad.py").write_text("class Bad:\n    observes = 'lidar'\n    acts = 'velocity'\n"
                                     "    def reset(self, r, t): pass\n"
                                     "    def act(self, f): return 0, 0\n")
    with pytest.raises(ConfigError) as err:
        resolve_agents(_plan(tmp_path, ref.format(d=tmp_path)))
    assert str(err.value).startswith(message.format(d=tmp_path))


def test_an_observation_plugin_acting_normalised(tmp_path: Path) -> None:
    """``observes = "observation"``: the task's vector; ``acts = "normalized"``: [1, -1] is
    the robot's top speed turning right at its top rate."""
    (tmp_path / "vec.py").write_text(textwrap.dedent('''
        import numpy as np
        from pic4rl_bridge.control.plugin import Policy

        class Vec(Policy):
            observes, acts = "observation", "normalized"

            def reset(self, robot, task):
                self.shape = task.observation_shape

            def act(self, obs):
                assert np.asarray(obs).shape == self.shape
                return np.array([1.0, -1.0])
    '''))
    result = drive_and_judge(_plan(tmp_path, f"{tmp_path / 'vec.py'}:Vec", episodes=1))
    spec = resolve_agents(_plan(tmp_path, f"{tmp_path / 'vec.py'}:Vec"))[0]
    from pic4rl_bridge.scenario import Scenario

    robot = Scenario(spec.run.env).robot
    cmd = read_episode(_bags(result.run_dir, "Vec")[0]).inputs["cmd"]
    np.testing.assert_allclose(cmd.vx, robot.max_linear_m_s, rtol=1e-6)
    np.testing.assert_allclose(cmd.wz, -robot.max_angular_rad_s, rtol=1e-6)


def test_a_bench_suite_naming_a_plugin_runs_its_cell(tmp_path: Path) -> None:
    from pic4rl_agents.suites import runner as bench
    from pic4rl_agents.suites.suite import load_suite

    (tmp_path / "lab").mkdir()
    _plugin(tmp_path / "lab")
    suite_file = tmp_path / "suite.yaml"
    suite_file.write_text(textwrap.dedent(f"""
        suite: plug
        bags: bags
        transport: inprocess
        retries: 0
        tasks:
          - name: goto
            env: {GOTO}
            agents: {{mine: lab/my_ctl.py:Mine}}
            pairs: [{{episodes: 1}}]
    """))
    suite = load_suite(suite_file)
    (cell,) = suite.cells
    assert cell.agent_path == f"{tmp_path / 'lab' / 'my_ctl.py'}:Mine"  # absolute, for workers
    table = bench.bench_suite(suite, workers=1, local=True, progress=False)
    rows = [dict(zip(table.header, r)) for r in table.rows]
    assert [r["agent"] for r in rows] == ["mine"]
    bag = next((tmp_path / "bags" / "plug" / cell.name / "mine").glob("episode_*"))
    assert read_episode(bag).facts.agent == "mine"


def test_the_example_gap_follower_enters_barns_table(tmp_path: Path,
                                                     capsys: pytest.CaptureFixture[str]) -> None:
    """The README's route: ``pic4rl-test --agent examples/gap_follower.py:GapFollower`` in
    process, then ``pic4rl-metrics compare --table barn`` on its bags."""
    bags = tmp_path / "bags"
    code = tester.main(["--agent", str(REPO / "examples" / "gap_follower.py") + ":GapFollower",
                        "--baseline", "dwa", "--episodes", "2", "--bags", str(bags),
                        "--run", "gaps", "--no-progress", "--ros-args", "--params-file", BARN,
                        "-p", "episode_max_steps:=150"])
    assert code == 0
    for bag in _bags(bags / "gaps", "gap_follower"):
        assert read_episode(bag).facts.agent == "gap_follower"
    capsys.readouterr()
    assert cli.main(["compare", str(bags / "gaps"), "--table", "barn", "--format", "csv"]) == 0
    out = capsys.readouterr().out
    rows = {line.split(",")[0]: line for line in out.splitlines()[1:] if line}
    assert {"gap_follower", "dwa"} <= set(rows)
    n = out.splitlines()[0].split(",").index("n")
    assert rows["gap_follower"].split(",")[n] == "2"


def test_the_example_suite_puts_the_plugin_beside_the_agent_and_the_planner(
        tmp_path: Path) -> None:
    """``pic4rl-bench examples/suite_gap_follower.yaml``: BARN's 50 test worlds, one run each,
    one row per agent in one BARN table; the plugin's file made absolute for the workers."""
    from pic4rl_agents.suites.suite import load_suite

    suite = load_suite(REPO / "examples" / "suite_gap_follower.yaml", bags_dir=tmp_path)
    assert suite.table == "barn" and len(suite.cells) == 3 * 50
    plugin = [c for c in suite.cells if c.agent == "gap_follower"]
    assert [c.variant for c in plugin] == list(range(0, 300, 6))
    assert {c.agent_path for c in plugin} == {
        f"{REPO / 'examples' / 'gap_follower.py'}:GapFollower"}
    assert {c.agent for c in suite.cells} == {"barn_td3_explorer", "gap_follower", "planner"}
