"""``pic4rl-test --pairs``: ``--random N`` draws N pairs of the paper's kind by default (4-8 m
apart, detour <= 1.3, the recorded facts say so), ``--pairs any`` the simulator's, and the
tester prints which set it used; ``--pairs`` with a pairs file is refused."""

from __future__ import annotations

import contextlib
import io
from pathlib import Path

import pytest
from agents_helpers import LIDAR_TD3, ROOT

from pic4rl_agents.testing import tester
from pic4rl_metrics.tables.batch import compute

SHORT = ["--baseline", "proportional", "--no-progress", "--env-kwargs", "episode_max_steps:5",
         "--ros-args", "--params-file", str(LIDAR_TD3)]


def run_main(argv: list[str]) -> tuple[int, str]:
    err = io.StringIO()
    with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(err):
        code = tester.main(argv)
    return code, err.getvalue()


def straight_and_shortest(run: Path) -> list[tuple[float, float]]:
    result = compute([run])
    assert not result.failed
    return [(e.facts.straight_line_m, e.facts.shortest_path_m) for e in result.episodes]


@pytest.mark.parametrize("pairs", [[], ["--pairs", "paper"]])
def test_random_pairs_are_of_the_paper_kind_by_default(tmp_path: Path, pairs: list[str]) -> None:
    code, err = run_main(["--random", "3", "--seed", "4", *pairs, "--bags", str(tmp_path),
                          "--run", "r", *SHORT])
    assert code == 0, err
    assert "episodes: 3 random pairs of kind 'paper' with seed 4" in err
    lengths = straight_and_shortest(tmp_path / "r")
    assert len(lengths) == 3
    for straight, shortest in lengths:
        assert 4.0 <= straight <= 8.0 and straight <= shortest <= 1.3 * straight


def test_pairs_any_draws_the_simulators_pairs_and_a_pairs_file_is_named(
        tmp_path: Path) -> None:
    code, err = run_main(["--random", "4", "--pairs", "any", "--bags", str(tmp_path),
                          "--run", "a", *SHORT])
    assert code == 0, err
    assert "episodes: 4 random pairs of kind 'any' with seed 0" in err
    straight = [s for s, _ in straight_and_shortest(tmp_path / "a")]
    assert min(straight) >= 1.0 and not all(4.0 <= s <= 8.0 for s in straight)

    code, err = run_main(["--episodes", "1", "--bags", str(tmp_path), "--run", "d", *SHORT])
    assert code == 0, err
    named = (Path(LIDAR_TD3).parent / "../../../config/goals_indoor_train.json").resolve()
    assert f"episodes: pairs file {named}" in err


def test_pairs_without_random_is_refused_when_a_file_gives_the_pairs(tmp_path: Path) -> None:
    code, err = run_main(["--pairs", "paper", "--bags", str(tmp_path), *SHORT])
    assert code == 2
    assert "--pairs paper: the test pairs come from" in err and "--random N" in err
    assert not list(tmp_path.rglob("*.db3"))


def test_a_baseline_drives_the_robot_full_speed_range(tmp_path):
    """An agent's speed floor (min_linear_m_s) is not imposed on the baselines beside it."""
    from pic4rl_agents.launch.rosargs import split_ros_args
    from pic4rl_agents.testing.tester import build_parser, build_plan
    from pic4rl_agents.testing.plan import resolve_agents

    def specs(*extra: str) -> list:
        plain, ros = split_ros_args(["--agent", str(ROOT / "checkpoints" / "td3_lidar"),
                                     "--baseline", "dwa", *extra])
        return resolve_agents(build_plan(build_parser().parse_args(plain), ros))

    agent, dwa = specs()
    assert agent.run.env.min_linear_m_s == 0.1 and dwa.run.env.min_linear_m_s == 0.0
    # A floor given on the command line is the baselines' too (the agent's must agree).
    assert [s.run.env.min_linear_m_s for s in specs("--env-kwargs", "min_linear_m_s:0.1")] == [
        0.1, 0.1]
