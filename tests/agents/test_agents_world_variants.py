"""Training on many worlds (``episodes.world_variants``): the evaluation env walks its own
held-out worlds, a BARN training or evaluation env with a test world is refused before
anything runs, and a test env runs the test world whatever the agent trained on."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import pytest
from agents_helpers import imitation_on

from pic4rl_agents.runs.config import EvalConfig
from pic4rl_agents.training.envs import check_no_test_world, eval_env_config, make_vec_env
from pic4rl_agents.testing import plan as testplan
from pic4rl_bridge.config import load_env_config
from pic4rl_bridge.errors import ConfigError
from pic4rl_bridge.scenario import Scenario

ROOT = Path(__file__).resolve().parents[2]
BARN = ROOT / "config" / "env_barn.yaml"


def _barn(variants: str = "", world_variant: int = 1):
    config = load_env_config(BARN, **{"episodes.world_variants": variants})
    return dataclasses.replace(config, sim_params={**config.sim_params,
                                                   "world_variant": world_variant})


def test_the_evaluation_walks_its_own_worlds_in_order() -> None:
    train = _barn("1:300:6,2:300:6")
    evaluation = eval_env_config(train, EvalConfig(pair_kind="any", world_variants="5,11"))
    assert evaluation.episodes.world_variants == "5,11" and evaluation.episodes.ordered
    plain = eval_env_config(train, EvalConfig(pair_kind="any"))
    assert plain.episodes.world_variants == "" and not plain.episodes.ordered
    check_no_test_world(Scenario(train))
    check_no_test_world(Scenario(evaluation))


@pytest.mark.bad_input
@pytest.mark.parametrize(("variants", "world_variant", "message"), [
    ("1:300:6,0:300:6", 1, "episodes.world_variants: holds BARN test world(s) 0, 6, 12, 18, "
                           "24 ...; train and evaluate on the 250 others"),
    ("", 6, "sim world_variant: holds BARN test world(s) 6; train"),
])
def test_a_barn_test_world_is_refused_for_training(variants: str, world_variant: int,
                                                   message: str) -> None:
    config = _barn(variants, world_variant)
    with pytest.raises(ConfigError) as err:
        make_vec_env(config, n_envs=1, vec_env="dummy")
    assert str(err.value).startswith(message)


def test_a_test_env_runs_its_own_world_not_the_training_worlds(tmp_path: Path) -> None:
    """An agent whose run trained on many worlds is tested in the test env's world_variant."""
    run = tmp_path / "run"
    run.mkdir()
    text = BARN.read_text().replace("world_variant: 0", "world_variant: 1").replace(
        "    transport: inprocess", "    transport: inprocess\n    episodes:\n"
        "      world_variants: \"1:300:6\"")
    (run / "config.yaml").write_text(text)
    (run / "model.zip").write_bytes(b"")
    plan = testplan.TestPlan(agents=(str(run),), algorithm="td3",
                             sim_overrides={"world_variant": 6})
    spec = testplan.resolve_agents(plan)[0]
    assert spec.run.env.episodes.world_variants == ""
    assert spec.run.env.sim_params["world_variant"] == 6


def test_the_experts_drive_with_the_params_files_baselines_section(tmp_path: Path) -> None:
    """The recipe's ``baselines:`` section (the explorer's BARN tuning) reaches the expert, as
    it reaches ``--baseline explorer``; a file without one leaves the defaults."""
    from pic4rl_agents.runs.config import ImitationConfig, load_run_config
    from pic4rl_bridge.settings.baselines import ExplorerConfig

    recipe = ROOT / "config" / "train_barn_td3_memory.yaml"
    run = load_run_config([recipe], train={"buffer_size": 100, "learning_starts": 10})
    env = make_vec_env(run.env, n_envs=1, seed=0, vec_env="dummy")
    try:
        config = ImitationConfig(enabled=True, expert="explorer", bc_steps=10)
        tuned = imitation_on(run, env, config, sources=(str(recipe),)).experts[0].config
        plain = imitation_on(run, env, config).experts[0].config
    finally:
        env.close()
    assert (tuned.max_linear_m_s, tuned.squeeze_radius_m) == (1.0, 0.27)
    assert plain == ExplorerConfig()
