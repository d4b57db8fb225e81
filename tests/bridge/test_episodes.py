"""Goals-and-poses files as PIC4rl-gym writes them, and the episode schedule built on them."""

from __future__ import annotations

import itertools
import json
import re
from pathlib import Path

import numpy as np
import pytest

from pic4rl_bridge.config import EpisodesConfig
from pic4rl_bridge.episodes import EpisodeSchedule, GoalsAndPoses, load_goals_and_poses
from pic4rl_bridge.errors import ConfigError
from pic4rl_bridge.transports.transport import EpisodeRequest
from pic4rl_base.geometry import Pose2D

EXAMPLE = {"initial_pose": [5.0, -2.0, 0.0],
           "goals": [[4.0, 0.0], [8.5, 1.5], [-8.0, 1.0], [-5.0, -4.0], [8.5, 1.5]],
           "poses": [[-6.0, -3.0, 0.0], [0.0, -4.0, 1.57], [4.0, -3.0, 0.0],
                     [1.5, 4.5, -1.57], [-4.5, 1.0, -1.57]]}


def write(tmp_path: Path, data: object, name: str = "goals_and_poses.json") -> Path:
    path = tmp_path / name
    path.write_text(data if isinstance(data, str) else json.dumps(data))
    return path


@pytest.fixture
def pairs(tmp_path: Path) -> GoalsAndPoses:
    return load_goals_and_poses(write(tmp_path, EXAMPLE))


def pair_index(pairs: GoalsAndPoses, request: EpisodeRequest) -> int:
    """The pair a request uses (pairs 1 and 4 share a goal, so match the start too)."""
    return next(i for i in range(len(pairs.goals))
                if (pairs.poses[i], pairs.goals[i]) == (request.start, request.goal))


# -- loading ---------------------------------------------------------------------------------


def test_loads_the_example_exactly(pairs: GoalsAndPoses) -> None:
    assert pairs.initial_pose == Pose2D(5.0, -2.0, 0.0)
    assert pairs.goals == ((4.0, 0.0), (8.5, 1.5), (-8.0, 1.0), (-5.0, -4.0), (8.5, 1.5))
    assert pairs.poses == (Pose2D(-6.0, -3.0, 0.0), Pose2D(0.0, -4.0, 1.57),
                           Pose2D(4.0, -3.0, 0.0), Pose2D(1.5, 4.5, -1.57),
                           Pose2D(-4.5, 1.0, -1.57))
    assert all(isinstance(p, Pose2D) for p in pairs.poses)


def test_initial_pose_is_optional_in_the_file(tmp_path: Path) -> None:
    data = {k: v for k, v in EXAMPLE.items() if k != "initial_pose"}
    assert load_goals_and_poses(write(tmp_path, data)).initial_pose is None


BAD = [
    ("[1, 2]", "expected an object"),
    ({"poses": EXAMPLE["poses"]}, "missing key 'goals'"),
    ({"goals": EXAMPLE["goals"]}, "missing key 'poses'"),
    ({**EXAMPLE, "goals": []}, "goals: .* non-empty list"),
    ({**EXAMPLE, "poses": {"a": 1}}, "poses: .* non-empty list"),
    ({**EXAMPLE, "goals": [[4.0, 0.0, 1.0]] * 5}, re.escape("goals[0]: ") + ".*[x, y]"),
    ({**EXAMPLE, "poses": [[1.0, 2.0]] * 5}, re.escape("poses[0]: ") + ".*yaw"),
    ({**EXAMPLE, "initial_pose": [5.0, -2.0]}, "initial_pose: .*yaw"),
    ({**EXAMPLE, "goals": [[1.0, "2"]] * 5}, re.escape("goals[0]: ") + ".*numbers"),
    ({**EXAMPLE, "poses": EXAMPLE["poses"][:4]}, "'goals' has 5 entries but 'poses' has 4"),
    ('{"goals": [[1.0, NaN]], "poses": [[0.0, 0.0, 0.0]]}', re.escape("goals[0]: ")),
    ('{"goals": [[1.0, 2.0]], "poses": [[0.0, 0.0, 1e999]]}', re.escape("poses[0]: ")),
    ("{not json", "not valid JSON"),
]


@pytest.mark.parametrize(("data", "message"), BAD)
def test_bad_files_name_the_file_and_key(tmp_path: Path, data: object, message: str) -> None:
    path = write(tmp_path, data, "bad_goals.json")
    with pytest.raises(ConfigError, match=re.escape(str(path)) + ".*" + message):
        load_goals_and_poses(path)


def test_unreadable_file_is_named(tmp_path: Path) -> None:
    path = tmp_path / "missing.json"
    with pytest.raises(ConfigError, match=re.escape(str(path)) + ": cannot read"):
        load_goals_and_poses(path)


def test_starting_episodes_need_an_initial_pose(tmp_path: Path) -> None:
    data = {k: v for k, v in EXAMPLE.items() if k != "initial_pose"}
    no_initial = load_goals_and_poses(write(tmp_path, data))
    config = EpisodesConfig(file="gp.json", starting_episodes=3)
    with pytest.raises(ConfigError, match="gp.json: missing key 'initial_pose'"):
        EpisodeSchedule(config, pairs=no_initial)
    with pytest.raises(ConfigError, match="episodes.file.*'initial_pose'"):
        EpisodeSchedule(EpisodesConfig(starting_episodes=3))
    EpisodeSchedule(EpisodesConfig(starting_episodes=0), pairs=no_initial)  # fine without


# -- the schedule -----------------------------------------------------------------------------


def test_without_pairs_the_simulator_samples_from_the_seed() -> None:
    schedule, rng = EpisodeSchedule(EpisodesConfig()), np.random.default_rng(7)
    requests = [schedule.next_request(e, rng) for e in range(20)]
    assert all(r.start is None and r.goal is None for r in requests)
    assert all(0 <= r.seed < 2**31 - 1 for r in requests)
    assert len({r.seed for r in requests}) == 20
    assert requests[0].seed == int(np.random.default_rng(7).integers(0, 2**31 - 1))


def test_starting_episodes_start_at_initial_pose_near_it(pairs: GoalsAndPoses) -> None:
    config = EpisodesConfig(starting_episodes=50, starting_goal_range_m=2.9)
    schedule, rng = EpisodeSchedule(config, pairs=pairs), np.random.default_rng(1)
    requests = [schedule.next_request(e, rng) for e in range(51)]
    starting, after = requests[:50], requests[50]
    assert all(r.start == Pose2D(5.0, -2.0, 0.0) for r in starting)
    dx = np.array([r.goal[0] - 5.0 for r in starting])
    dy = np.array([r.goal[1] + 2.0 for r in starting])
    assert np.all(np.abs(dx) <= 2.9) and np.all(np.abs(dy) <= 2.9)
    assert dx.min() < -1.5 and dx.max() > 1.5 and dy.min() < -1.5 and dy.max() > 1.5
    assert len({r.goal for r in starting}) == 50
    assert (after.start, after.goal) in set(zip(pairs.poses, pairs.goals))


def test_random_pair_held_for_n_episodes(pairs: GoalsAndPoses) -> None:
    config = EpisodesConfig(change_goal_and_pose=4, starting_episodes=3)
    schedule, rng = EpisodeSchedule(config, pairs=pairs), np.random.default_rng(3)
    for e in range(3):
        schedule.next_request(e, rng)
    indices = [pair_index(pairs, schedule.next_request(e, rng)) for e in range(3, 3 + 80)]
    blocks = [indices[b:b + 4] for b in range(0, 80, 4)]
    assert all(len(set(block)) == 1 for block in blocks)  # changes only at multiples of 4
    assert len({block[0] for block in blocks}) == 5  # every pair drawn at some point
    assert sum(a[0] != b[0] for a, b in itertools.pairwise(blocks)) >= 5


def test_ordered_walks_the_pairs_and_cycles(pairs: GoalsAndPoses) -> None:
    config = EpisodesConfig(change_goal_and_pose=2)
    schedule, rng = EpisodeSchedule(config, pairs=pairs, ordered=True), np.random.default_rng(0)
    indices = [pair_index(pairs, schedule.next_request(e, rng)) for e in range(12)]
    assert indices == [0, 0, 1, 1, 2, 2, 3, 3, 4, 4, 0, 0]


def test_same_seed_same_sequence(pairs: GoalsAndPoses) -> None:
    config = EpisodesConfig(starting_episodes=3, change_goal_and_pose=2)

    def run(seed: int) -> list[EpisodeRequest]:
        schedule, rng = EpisodeSchedule(config, pairs=pairs), np.random.default_rng(seed)
        out = []
        for e in range(30):
            out.extend(schedule.attempts(schedule.next_request(e, rng), rng))
        return out

    assert run(11) == run(11)
    assert run(11) != run(12)


def test_redraw_a_starting_goal(pairs: GoalsAndPoses) -> None:
    config = EpisodesConfig(starting_episodes=2, starting_goal_range_m=1.0)
    schedule, rng = EpisodeSchedule(config, pairs=pairs), np.random.default_rng(5)
    first = schedule.next_request(0, rng)
    again = schedule.redraw(first, rng)
    assert again.goal != first.goal and (again.seed, again.start) == (first.seed, first.start)
    assert abs(again.goal[0] - 5.0) <= 1.0 and abs(again.goal[1] + 2.0) <= 1.0


def test_redraw_a_random_pair_draws_another(pairs: GoalsAndPoses) -> None:
    config = EpisodesConfig(change_goal_and_pose=10)
    schedule, rng = EpisodeSchedule(config, pairs=pairs), np.random.default_rng(9)
    request = schedule.next_request(0, rng)
    seen = {pair_index(pairs, request)}
    for _ in range(40):
        again = schedule.redraw(request, rng)
        assert pair_index(pairs, again) != pair_index(pairs, request)
        assert again.seed == request.seed
        request = again
        seen.add(pair_index(pairs, request))
    assert seen == set(range(5))
    held = schedule.next_request(1, rng)  # the redrawn pair is kept for the rest of the block
    assert pair_index(pairs, held) == pair_index(pairs, request)


def test_redraw_an_ordered_pair_takes_the_next(pairs: GoalsAndPoses) -> None:
    config = EpisodesConfig(change_goal_and_pose=1)
    schedule, rng = EpisodeSchedule(config, pairs=pairs, ordered=True), np.random.default_rng(0)
    first = schedule.next_request(0, rng)
    assert pair_index(pairs, schedule.redraw(first, rng)) == 1
    assert pair_index(pairs, schedule.next_request(1, rng)) == 2  # the walk goes on from there


def test_redraw_a_sampled_episode_gives_a_new_seed() -> None:
    schedule, rng = EpisodeSchedule(EpisodesConfig()), np.random.default_rng(2)
    first = schedule.next_request(0, rng)
    again = schedule.redraw(first, rng)
    assert again.seed != first.seed and again.start is None and again.goal is None


def test_attempts_give_max_attempts_requests(pairs: GoalsAndPoses) -> None:
    config = EpisodesConfig(max_attempts=4, starting_episodes=1)
    schedule, rng = EpisodeSchedule(config, pairs=pairs), np.random.default_rng(4)
    first = schedule.next_request(0, rng)
    tries = list(schedule.attempts(first, rng))
    assert len(tries) == 4 and tries[0] is first
    assert len({t.goal for t in tries}) == 4


def test_negative_episode_is_refused() -> None:
    with pytest.raises(ValueError, match="episode: -1"):
        EpisodeSchedule(EpisodesConfig()).next_request(-1, np.random.default_rng(0))
