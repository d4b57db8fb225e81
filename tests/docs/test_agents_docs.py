"""docs/agents.md against the code: the trainer's parameter table lists every ``trainer``
parameter with the code's type and default; every flag of ``pic4rl-train`` and ``pic4rl-test``
is documented in its command's section; every shipped training file is named with its run,
algorithm, sensor and steps; the default test pairs match the packaged JSON; the algorithms and
baselines are the code's; and the run and bag layouts list what the commands really write (a
training of a few dozen steps, resumed once, and a one-episode test, all in ``tmp_path``).

After changing a trainer parameter, print the table's first three columns and update
docs/agents.md:

    PYTHONPATH=tests .venv/bin/python tests/docs/test_agents_docs.py
"""

from __future__ import annotations

import argparse
import json
import math
import re
from pathlib import Path

import pytest
import yaml
from docs_helpers import broken_links, parameter_rows, section, table_rows

from pic4rl_agents.testing import tester

from pic4rl_agents.testing import plan as testplan

from pic4rl_agents.training import train

from pic4rl_agents.tune import search as tune
from pic4rl_agents.models.algorithm_table import ALGORITHM_TABLE
from pic4rl_agents.runs.config import ALGORITHM_NAMES, TrainConfig, load_run_config

ROOT = Path(__file__).resolve().parents[2]
DOC = ROOT / "docs" / "agents.md"
TRAIN_SECTION = "## Training (`pic4rl-train`)"
TEST_SECTION = "## Testing (`pic4rl-test`)"


def code_blocks(text: str) -> str:
    """The contents of the fenced code blocks in ``text``, joined."""
    return "\n".join(re.findall(r"```[a-z]*\n(.*?)```", text, flags=re.S))


def flags(parser: argparse.ArgumentParser) -> list[str]:
    """Every option string of ``parser`` except ``-h``/``--help``."""
    return sorted({option for action in parser._actions for option in action.option_strings
                   if option not in ("-h", "--help")})


def documented(text: str, flag: str) -> bool:
    """Whether ``flag`` opens a code span in ``text`` (`` `--run NAME` ``, `` `-n` ``)."""
    return re.search(rf"`{re.escape(flag)}(?=[`\s=\[])", text) is not None


@pytest.fixture(scope="module")
def doc() -> str:
    return DOC.read_text(encoding="utf-8")


# -- the trainer's parameters ------------------------------------------------------------------


def test_the_parameter_table_lists_every_trainer_parameter_and_nothing_else(doc):
    rows = table_rows(section(section(doc, TRAIN_SECTION), "### Parameters"))
    expected = parameter_rows(TrainConfig)
    assert len(expected) > 30  # param_names() found the nested sections too
    missing = sorted(set(expected) - set(rows))
    stale = sorted(set(rows) - set(expected))
    assert not missing, f"docs/agents.md's parameter table lacks {missing}"
    assert not stale, f"docs/agents.md's parameter table lists unknown parameters {stale}"


def test_the_parameter_table_has_the_codes_types_and_defaults(doc):
    rows = table_rows(section(section(doc, TRAIN_SECTION), "### Parameters"))
    wrong = []
    for name, (kind, default) in parameter_rows(TrainConfig).items():
        cells = rows.get(name)
        if cells is None:
            continue  # reported by the test above
        assert len(cells) == 3, f"{name}: expected type, default and meaning; got {cells}"
        if (cells[0], cells[1]) != (kind, default):
            wrong.append(f"{name}: doc has {cells[0]} {cells[1]}, code has {kind} {default}")
        if not cells[2]:
            wrong.append(f"{name}: no meaning given")
    assert not wrong, "docs/agents.md's parameter table differs from the code:\n" + "\n".join(
        wrong)


# -- command lines -----------------------------------------------------------------------------


@pytest.mark.parametrize(("heading", "module"), [(TRAIN_SECTION, train), (TEST_SECTION, tester)],
                         ids=["pic4rl-train", "pic4rl-test"])
def test_every_flag_is_documented_in_its_commands_section(doc, heading, module):
    text = section(doc, heading)
    options = flags(module.build_parser())
    assert len(options) >= 8
    missing = [flag for flag in options if not documented(text, flag)]
    assert not missing, f"docs/agents.md's {heading!r} does not document {missing}"
    for ros_option in ("--params-file", "-p"):
        assert documented(text, f"--ros-args {ros_option}"), (heading, ros_option)


def test_every_tune_flag_and_its_default_is_documented(doc):
    rows = table_rows(section(doc, "## Tuning (`pic4rl-tune`)"))
    options = flags(tune.build_parser())
    assert len(options) >= 15
    missing = [flag for flag in options if not any(row.split()[0] == flag for row in rows)]
    assert not missing, f"docs/agents.md's tuning section does not document {missing}"
    defaults = tune.build_parser().parse_args([])
    for flag, value in (("--n-trials N", defaults.n_trials), ("--n-jobs N", defaults.n_jobs),
                        ("--n-evaluations N", defaults.n_evaluations),
                        ("--n-startup-trials N", defaults.n_startup_trials)):
        assert f"(default {value})" in rows[flag][0], flag
    assert f"(default {defaults.max_steps:,})" in rows["--max-steps N"][0]
    assert f"(default `{defaults.base}`)" in rows["--base FILE"][0]


def test_the_documented_test_defaults_are_the_parsers():
    defaults = tester.build_parser().parse_args([])
    text = section(DOC.read_text(encoding="utf-8"), TEST_SECTION)
    rows = table_rows(text)
    assert f"(default {defaults.episodes}" in rows["--episodes N"][0]
    assert f"(default {defaults.seed})" in rows["--seed S"][0]
    assert f"(default `{defaults.bags_dir}`)" in rows["--bags DIR"][0]
    assert f"(default `{defaults.format}`)" in rows["--format FMT"][0] or (
        f"`{defaults.format}` (default)" in rows["--format FMT"][0])


# -- shipped files, algorithms, baselines, test pairs ------------------------------------------


def test_every_training_file_is_named_with_its_run_algorithm_sensor_and_budget(doc):
    files = sorted(f"config/{p.name}" for p in (ROOT / "config").glob("train_*.yaml"))
    assert len(files) >= 4
    rows = table_rows(section(doc, "## Quick start"))
    missing = [f for f in files if f not in rows]
    assert not missing, f"docs/agents.md's quick-start table does not name {missing}"
    for file in files:
        run = load_run_config([ROOT / file])
        run_name, algorithm, sensor, budget = (c.strip("`") for c in rows[file][:4])
        assert (run_name, algorithm, sensor) == (run.name, run.train.algorithm,
                                                 run.env.sensor), file
        assert budget == f"{run.train.max_wall_s / 60:g} min", file
    stale = sorted(set(re.findall(r"config/train_[a-z_]+\.yaml", doc)) - set(files))
    assert not stale, f"docs/agents.md names training files that do not exist: {stale}"


def test_every_algorithm_and_baseline_is_documented(doc):
    rows = table_rows(section(section(doc, TRAIN_SECTION), "### Algorithms and networks"))
    assert set(rows) == set(ALGORITHM_NAMES), sorted(rows)
    for name, entry in ALGORITHM_TABLE.items():  # its class, and sb3-contrib where it is
        cell = rows[name][0]
        assert f"`{entry.cls.rpartition('.')[2]}`" in cell, (name, cell)
        assert ("sb3-contrib" in cell) == (entry.distribution == "sb3-contrib"), (name, cell)
    text = section(doc, TEST_SECTION)
    for baseline in tester.BASELINES:
        assert f"`--baseline {baseline}`" in text, baseline


def test_the_default_test_pairs_are_the_packaged_ones(doc):
    text = section(doc, "### The test env and its episodes")
    path = testplan.DEFAULT_PAIRS.relative_to(ROOT).as_posix()
    assert f"`{path}`" in text
    data = json.loads(testplan.DEFAULT_PAIRS.read_text())
    rows = [line for line in text.splitlines() if re.match(r"\| \d+ \|", line)]
    assert len(rows) == len(data["poses"]) == len(data["goals"])
    for i, (line, pose, goal) in enumerate(zip(rows, data["poses"], data["goals"])):
        cells = [c.strip() for c in line.strip("|").split("|")]
        assert int(cells[0]) == i
        assert json.loads(cells[1]) == pose and json.loads(cells[2]) == goal, line
        assert float(cells[3]) == pytest.approx(math.dist(pose[:2], goal), abs=0.005), line


# -- what the commands write -------------------------------------------------------------------

_GENERIC = [(r"^model_\d+_steps\.zip$", "model_<steps>_steps.zip"),
            (r"^model_replay_buffer_\d+_steps\.pkl$", "model_replay_buffer_<steps>_steps.pkl"),
            (r"^\d+_\d+\.monitor\.csv$", "<session>_<rank>.monitor.csv"),
            (r"^events\.out\.tfevents\..*$", "events.out.tfevents.*"),
            (r"^\d+$", "<session>"), (r"^episode_\d{4}$", "episode_0000")]


def _generic(name: str) -> str:
    for pattern, placeholder in _GENERIC:
        if re.match(pattern, name):
            return placeholder
    return name


def _layout_names(root: Path) -> set[str]:
    """Every file and folder name under ``root``, with numbers as the doc's placeholders."""
    return {_generic(p.name) for p in root.rglob("*")
            if not (p.parent.name.startswith("episode_") and p.is_file())}


@pytest.fixture(scope="module")
def trained(tmp_path_factory) -> Path:
    """A TD3-LiDAR run of 64 steps with a checkpoint and an evaluation, resumed to 96."""
    runs = tmp_path_factory.mktemp("runs")
    common = ["--no-progress", "--hyperparams", f"runs_dir:{runs}", "learning_starts:16",
              "batch_size:8", "policy.net_arch:[8]", "policy.critic_arch:[8]",
              "checkpoint.interval_steps:32", "eval.interval_steps:32", "eval.episodes:1",
              "--env-kwargs", "episode_max_steps:20"]
    params = ["--ros-args", "--params-file", str(ROOT / "config/train_goto_lidar_td3.yaml")]
    assert train.main(["-n", "64", "--run", "doc", *common, *params]) == 0
    assert train.main(["-n", "96", "--resume", str(runs / "doc"), *common]) == 0
    return runs / "doc"


@pytest.mark.slow
def test_the_run_directory_is_as_documented(doc, trained):
    layout = code_blocks(section(section(doc, TRAIN_SECTION), "### The run directory"))
    names = _layout_names(trained)
    assert {"config-2.yaml", "summary-2.yaml", "model_<steps>_steps.zip", "best_model.zip",
            "progress.csv"} <= names  # the resume wrote a second session
    assert sorted(p.name for p in (trained / "logs").iterdir()) == ["0", "1"]
    missing = sorted(n for n in names if n not in layout)
    assert not missing, f"docs/agents.md's run directory lacks {missing}"
    summary = yaml.safe_load((trained / "summary-2.yaml").read_text())
    assert summary["session"] == 1 and summary["total_steps"] == 96
    keys = section(section(doc, TRAIN_SECTION), "### The run directory")
    undocumented = [k for k in summary if f"`{k}`" not in keys]
    assert not undocumented, f"docs/agents.md does not describe summary keys {undocumented}"


def test_the_test_run_is_as_documented(doc, tmp_path):
    bags = tmp_path / "bags"
    argv = ["--baseline", "proportional", "--random", "1", "--bags", str(bags), "--run", "t",
            "--no-progress", "--env-kwargs", "episode_max_steps:5",
            "--ros-args", "--params-file", str(ROOT / "config/env_goto_lidar.yaml")]
    assert tester.main(argv) == 0
    layout = code_blocks(section(doc, "### Bags and the table"))
    names = {n.replace("proportional", "<agent>") for n in _layout_names(bags / "t")}
    assert {"<agent>", "episode_0000", "episodes.csv", "table.md", "config.yaml"} <= names
    missing = sorted(n for n in names if n not in layout)
    assert not missing, f"docs/agents.md's bag layout lacks {missing}"
    assert tester.main(["--bags", str(bags)]) == 2  # nothing to test: bad arguments


# -- links -------------------------------------------------------------------------------------


def test_links_to_files_and_headings_resolve():
    count, broken = broken_links(DOC)
    assert count and not broken, f"agents.md has broken links: {broken}"


def test_the_readme_and_interfaces_point_here():
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    interfaces = (ROOT / "docs" / "interfaces.md").read_text(encoding="utf-8")
    assert "(docs/agents.md)" in readme
    assert "(agents.md" in interfaces
    for command in ("pic4rl-train", "pic4rl-test", "pic4rl-run"):
        assert f"## `{command}`" in interfaces, command
        assert command in readme, command
    assert "pic4rl_bridge.demo" not in readme and "demo.py" not in readme


if __name__ == "__main__":
    for name, (kind, default) in parameter_rows(TrainConfig).items():
        print(f"| `{name}` | {kind} | {default} | |")
