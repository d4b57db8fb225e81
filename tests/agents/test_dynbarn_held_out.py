"""The dynamic BARN's 60 test scenes are refused to training and evaluation envs as BARN's test
worlds are (``pic4rl_sim.engine.worlds.held_out``), naming only the test scenes among the
variants given, and other variants are accepted."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import pytest

from pic4rl_agents.training.envs import check_no_test_world, make_vec_env
from pic4rl_bridge.config import load_env_config
from pic4rl_bridge.errors import ConfigError
from pic4rl_bridge.scenario import Scenario
from pic4rl_sim.engine.worlds.dynbarn import TEST_SCENES

ROOT = Path(__file__).resolve().parents[2]


def _dynbarn(variants: str = "", world_variant: int = 1):
    config = load_env_config(ROOT / "config" / "env_barn.yaml",
                             **{"episodes.world_variants": variants})
    return dataclasses.replace(config, sim_params={**config.sim_params, "world": "dynbarn",
                                                   "world_variant": world_variant})


def test_variants_outside_the_test_scenes_are_accepted() -> None:
    check_no_test_world(Scenario(_dynbarn("1:300:5,2:300:5")))
    check_no_test_world(Scenario(_dynbarn(world_variant=301)))


@pytest.mark.bad_input
@pytest.mark.parametrize(("variants", "world_variant", "message"), [
    ("1:300:5,0:300:5", 1, ("episodes.world_variants: holds dynamic BARN test world(s) 0, 5, "
                            "10, 15, 20 ...; train and evaluate on other variants")),
    ("", TEST_SCENES[-1], "sim world_variant: holds dynamic BARN test world(s) 295; train"),
])
def test_a_dynamic_barn_test_scene_is_refused_for_training(variants: str, world_variant: int,
                                                           message: str) -> None:
    with pytest.raises(ConfigError) as err:
        make_vec_env(_dynbarn(variants, world_variant), n_envs=1, vec_env="dummy")
    assert str(err.value).startswith(message)
