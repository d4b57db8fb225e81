"""docs/bridge.md against the code: the parameter table lists every ``nav_env`` parameter with
the code's type and default, every registered id and shipped config file is named (with the
id's task, sensor and sim defaults), and every ``info`` key and reward term the env emits is
documented. The envs run in process for two steps each; no ROS graph is started.

After changing a parameter, print the table's first three columns and update docs/bridge.md:

    PYTHONPATH=tests .venv/bin/python tests/docs/test_bridge_docs.py
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
import pytest
from docs_helpers import broken_links, literal, parameter_rows, section, table_rows

from pic4rl_base.schema import param_names
from pic4rl_bridge import ENV_IDS
from pic4rl_bridge.config import EnvConfig, load_env_config
from pic4rl_bridge.settings.baselines import BaselinesConfig

ROOT = Path(__file__).resolve().parents[2]
DOC = ROOT / "docs" / "bridge.md"
INTERFACES = ROOT / "docs" / "interfaces.md"
TASK_SECTIONS = {"goToPose": "goToPose", "vineyard": "vineyard",
                 "personMonitoring": "personMonitoring", "explore": "explore"}


@pytest.fixture(scope="module")
def doc() -> str:
    return DOC.read_text(encoding="utf-8")


@pytest.fixture(scope="module")
def emitted() -> dict[str, Any]:
    """What the four registered envs emit in two steps from a seeded reset (the second step
    ends the episode as a timeout), then in a step whose physics diverges: every info key,
    and each task's reward terms."""
    info_keys: set[str] = set()
    terms: dict[str, set[str]] = {}
    configs = {}
    for path in sorted((ROOT / "config").glob("env_*.yaml")):
        loaded = load_env_config(path)
        configs.setdefault((loaded.task, loaded.sensor, loaded.sensors), path)
    for env_id, spec in ENV_IDS.items():
        config = configs[spec["task"], spec["sensor"], tuple(spec.get("sensors", ()))]
        env = gym.make(env_id, config=str(config), overrides={"episode_max_steps": 2})
        try:
            _, info = env.reset(seed=0)
            info_keys |= set(info)
            rng = np.random.default_rng(0)
            for _ in range(2):
                action = rng.uniform(-0.1, 0.1, env.action_space.shape).astype(np.float32)
                *_, info = env.step(action)
                info_keys |= set(info)
                terms.setdefault(spec["task"], set()).update(info["reward_terms"])
            env.reset()  # a diverged step (a NaN state, as the engine detects it) adds its keys
            env.unwrapped.transport.engine.data.qvel[:] = np.nan
            *_, info = env.step(np.zeros(env.action_space.shape, np.float32))
            assert info["outcome"] == "diverged"
            info_keys |= set(info)
        finally:
            env.close()
    return {"info": info_keys, "terms": terms}


# -- parameters --------------------------------------------------------------------------------


def test_the_parameter_table_lists_every_parameter_and_nothing_else(doc):
    rows = table_rows(section(doc, "## Parameters"))
    expected = parameter_rows(EnvConfig)
    assert len(expected) > 50  # param_names() found the nested sections too
    missing = sorted(set(expected) - set(rows))
    stale = sorted(set(rows) - set(expected))
    assert not missing, f"docs/bridge.md's parameter table lacks {missing}"
    assert not stale, f"docs/bridge.md's parameter table lists unknown parameters {stale}"


def test_the_parameter_table_has_the_codes_types_and_defaults(doc):
    rows = table_rows(section(doc, "## Parameters"))
    wrong = []
    for name, (kind, default) in parameter_rows(EnvConfig).items():
        cells = rows.get(name)
        if cells is None:
            continue  # reported by the test above
        assert len(cells) == 3, f"{name}: expected type, default and meaning; got {cells}"
        if (cells[0], cells[1]) != (kind, default):
            wrong.append(f"{name}: doc has {cells[0]} {cells[1]}, code has {kind} {default}")
        if not cells[2]:
            wrong.append(f"{name}: no meaning given")
    assert not wrong, "docs/bridge.md's parameter table differs from the code:\n" + "\n".join(
        wrong)


def test_the_baselines_table_is_the_baselines_section(doc):
    """The baselines' settings are their own section's (``BaselinesConfig``), not the env's."""
    rows = table_rows(section(doc, "## Baselines"))
    expected = parameter_rows(BaselinesConfig)
    assert set(expected) == {name for name in rows
                             if name.startswith(("dwa.", "planner.", "predictive.", "explorer."))}
    assert all(rows[name][:2] == [kind, default] for name, (kind, default) in expected.items())
    assert not any(name.startswith("baselines.") for name in parameter_rows(EnvConfig))


# -- ids and config files ----------------------------------------------------------------------


def test_every_registered_id_is_named_with_its_task_sensor_file_and_sim_defaults(doc):
    rows = table_rows(section(doc, "## Quick start"))
    ids = {name for name in rows if name.startswith("pic4rl/")}
    assert ids == set(ENV_IDS), f"the quick-start table names {sorted(ids)}, not the registry"
    for env_id, spec in ENV_IDS.items():
        task, sensor, config, sim_defaults = rows[env_id]
        sensors = spec.get("sensors", [spec["sensor"]])  # the table names every observed one
        assert (task, sensor) == (f"`{spec['task']}`", ", ".join(f"`{s}`" for s in sensors)), (
            env_id)
        path = re.fullmatch(r"`(config/env_[a-z_]+\.yaml)`", config)
        assert path is not None, f"{env_id}: no config file named in {config!r}"
        loaded = load_env_config(ROOT / path.group(1))
        assert (loaded.task, loaded.sensor, loaded.observed) == (
            spec["task"], spec["sensor"], tuple(sensors)), env_id
        defaults = spec.get("sim_defaults", {})
        named = [f"`{key}: {literal(value)}`" for key, value in defaults.items()]
        assert named == re.findall(r"`[^`]+`", sim_defaults) or (
            not defaults and sim_defaults == "none"), f"{env_id}: sim_defaults {sim_defaults!r}"


def test_every_env_config_file_is_named_and_every_named_one_exists(doc):
    files = sorted(f"config/{p.name}" for p in (ROOT / "config").glob("env_*.yaml"))
    assert len(files) >= len(ENV_IDS)
    missing = [f for f in files if f"`{f}`" not in doc]
    assert not missing, f"docs/bridge.md does not name {missing}"
    stale = sorted(set(re.findall(r"config/env_[a-z_]+\.yaml", doc)) - set(files))
    assert not stale, f"docs/bridge.md names config files that do not exist: {stale}"


# -- what the env emits ------------------------------------------------------------------------


def test_every_info_key_is_documented_and_no_other(doc, emitted):
    keys = emitted["info"]
    assert {"reward_terms", "outcome", "is_success", "seed"} <= keys  # an episode ended
    rows = set(table_rows(section(doc, "### Episode ends and `info`")))
    assert not keys - rows, f"docs/bridge.md does not document info keys {sorted(keys - rows)}"
    assert not rows - keys, f"docs/bridge.md documents info keys the env lacks {rows - keys}"


def test_every_reward_term_is_in_its_tasks_table(doc, emitted):
    assert set(emitted["terms"]) == set(TASK_SECTIONS)
    for task, terms in emitted["terms"].items():
        rows = set(table_rows(section(doc, f"### {TASK_SECTIONS[task]}")))
        assert terms == rows, (f"docs/bridge.md's {task} reward table has {sorted(rows)}; "
                               f"the task reports {sorted(terms)}")
        unscaled = sorted(t for t in terms if f"reward.{t}" not in param_names(EnvConfig))
        assert not unscaled, f"{task}: reward terms without a reward.* scale: {unscaled}"


# -- links -------------------------------------------------------------------------------------


@pytest.mark.parametrize("path", [DOC, INTERFACES, ROOT / "README.md"], ids=lambda p: p.name)
def test_links_to_files_and_headings_resolve(path):
    count, broken = broken_links(path)
    assert count and not broken, f"{path.name} has broken links: {broken}"


def test_interfaces_names_the_recorder_and_the_env_node():
    text = INTERFACES.read_text(encoding="utf-8")
    node = section(text, "## The env node `nav_env`")
    config = EnvConfig()
    names = {"topics.pose": config.topics.pose, "topics.goal": config.topics.goal,
             "topics.cmd_vel": config.topics.cmd_vel,
             "ros.sim_node": f"{config.ros.sim_node}/set_parameters_atomically",
             "ros.reset_service": config.ros.reset_service}
    for parameter, default in names.items():
        for name in (parameter, default):
            assert f"`{name}`" in node or f"`<{name}>" in node, (
                f"interfaces.md's env node section lacks {name}")
    assert "pic4rl_bridge/recorder.py" in section(text, "## The bag contract")


if __name__ == "__main__":
    for name, (kind, default) in parameter_rows(EnvConfig).items():
        print(f"| `{name}` | {kind} | {default} | |")
