"""A world per episode (``episodes.world_variants``): the variant list's syntax, one seed
giving one sequence of worlds, the in-process engine and the bag's facts (world name, BARN's
reference path, the challenge's start and goal) following each episode's world, and the
combinations refused in one line."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from pic4rl_metrics.bags.reader import read_episode
from pic4rl_sim.engine.worlds.barn import barn_data

from pic4rl_bridge.baselines import make_baseline
from pic4rl_bridge.env import NavEnv
from pic4rl_bridge.recording import make_env
from pic4rl_bridge.errors import ConfigError
from pic4rl_bridge.scenario import parse_variants

ROOT = Path(__file__).resolve().parents[2]
BARN = ROOT / "config" / "env_barn.yaml"
LIDAR = ROOT / "config" / "env_goto_lidar.yaml"


def test_variants_are_numbers_and_ranges_in_order() -> None:
    assert parse_variants("") == ()
    assert parse_variants("7") == (7,)
    assert parse_variants("1:13:6, 4,2:4") == (1, 7, 4, 2, 3)
    assert len(parse_variants("1:300:6,2:300:6,3:300:6,4:300:6,5:300:6")) == 250


@pytest.mark.bad_input
@pytest.mark.parametrize("text", ["x", "1:x", "5:5", "1:2:3:4", "0:10:0", "1,,2:2"])
def test_a_bad_variant_list_names_the_key_and_the_item(text: str) -> None:
    with pytest.raises(ConfigError, match=r"^episodes\.world_variants: '.*' is invalid; "
                                          r"expected a variant N or a range START:STOP\[:STEP\]"):
        parse_variants(text)


@pytest.mark.bad_input
def test_a_refused_world_index_fails_when_the_env_is_made() -> None:
    with pytest.raises(ConfigError) as err:
        NavEnv(BARN, overrides={"episodes.world_variants": "1:300:6,300"})
    assert str(err.value) == ("episodes.world_variants: world_variant: 300 is invalid; expected a "
                              "BARN world index in [0, 299] (world: barn)")


@pytest.mark.bad_input
@pytest.mark.parametrize(("overrides", "message"), [
    ({"episodes.file": str(ROOT / "pic4rl_agents" / "data" / "goals_indoor_test.json")},
     "no episodes.file"),
    ({"task": "vineyard", "sensor": "depth"}, "a task that knows no world's map"),
])
def test_a_world_per_episode_refuses_one_worlds_pairs_and_map_tasks(overrides: dict,
                                                                    message: str) -> None:
    with pytest.raises(ConfigError, match=f"^episodes.world_variants: .*{message}"):
        NavEnv(LIDAR, overrides={"episodes.world_variants": "0:3", **overrides})


@pytest.mark.bad_input
def test_map_aware_baselines_refuse_a_world_per_episode() -> None:
    env = NavEnv(BARN, overrides={"episodes.world_variants": "1,2"})
    try:
        with pytest.raises(ConfigError, match=r"^--baseline planner: it drives on one world's "
                                              r"map; .*\(episodes\.world_variants\): unset it$"):
            make_baseline("planner", env.config, env.scenario.robot, env.scenario.world)
        make_baseline("explorer", env.config, env.scenario.robot)  # mapless: it fits
    finally:
        env.close()


def test_the_top_view_draws_each_episodes_own_world() -> None:
    """The still picture (the world's obstacles) is the episode's world's: two variants, two
    pictures, and a variant met again gives its picture again."""
    env = NavEnv(BARN, overrides={"episodes.world_variants": "1,2"}, render_mode="rgb_array")
    try:
        stills: dict[str, list] = {}
        for i in range(6):
            env.reset(seed=5 if i == 0 else None)
            assert env.render().shape[2] == 3
            stills.setdefault(env.transport.world_name, []).append(env._view.background.copy())
        assert len(stills) == 2
        (a, *a_again), (b, *_) = stills.values()
        assert (a != b).any()
        assert all((a == other).all() for other in a_again)
    finally:
        env.close()


def _worlds(env: NavEnv, seed: int, episodes: int) -> list[tuple[str, int]]:
    out = []
    for i in range(episodes):
        _, info = env.reset(seed=seed if i == 0 else None)
        out.append((env.transport.world_name, info["seed"]))
    return out


def test_one_seed_one_sequence_of_worlds_and_the_engine_follows() -> None:
    env = NavEnv(BARN, overrides={"episodes.world_variants": "1:300:6,5:300:6"})
    try:
        first, again = _worlds(env, 4, 6), _worlds(env, 4, 6)
        other = _worlds(env, 5, 6)
        assert first == again and first != other
        names = {name for name, _ in first + other}
        assert len(names) > 3 and all(int(n.split(":")[1]) % 6 in (1, 5) for n in names)
        # the engine runs the named world: its cylinders are that BARN world's
        variant = int(env.transport.world_name.split(":")[1])
        world = env.transport.engine.world
        assert world.params["reference_path_length_m"] == (
            barn_data()["worlds"][variant]["reference_path_length_m"])
        assert env.scenario.world is world and env.scenario.world_name == f"barn:{variant}"
    finally:
        env.close()


def test_ordered_walks_the_worlds_in_turn() -> None:
    env = NavEnv(BARN, overrides={"episodes.world_variants": "5,11,17",
                                  "episodes.ordered": True})
    try:
        assert [name for name, _ in _worlds(env, 0, 4)] == [
            "barn:5", "barn:11", "barn:17", "barn:5"]
    finally:
        env.close()


def test_each_bag_records_its_episodes_world(tmp_path: Path) -> None:
    """Three short recorded episodes, each in its own BARN world: the bag's world fact and the
    reference path (BARN's score) are that world's, the start and goal the challenge's."""
    env = make_env(BARN, overrides={"episodes.world_variants": "1,2,3", "episodes.ordered": True,
                                    "episode_max_steps": 3, "record.enabled": True,
                                    "record.bags_dir": str(tmp_path), "record.run": "worlds"})
    try:
        for i in range(3):
            env.reset(seed=0 if i == 0 else None)
            done = False
            while not done:
                *_, terminated, truncated, _ = env.step(np.zeros(2, dtype=np.float32))
                done = terminated or truncated
    finally:
        env.close()
    worlds = barn_data()["worlds"]
    for i, variant in enumerate((1, 2, 3)):
        facts = read_episode(tmp_path / "worlds" / f"episode_{i:04d}").facts
        assert facts.world == f"barn:{variant}"
        assert facts.reference_path_m == worlds[variant]["reference_path_length_m"]
        assert facts.start[:2] == pytest.approx((-2.25, 3.0)) and facts.goal == (-2.25, 13.0)
    assert len({worlds[v]["reference_path_length_m"] for v in (1, 2, 3)}) == 3
