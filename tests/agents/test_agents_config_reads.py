"""Resolve once, pass down: ``pic4rl-test`` and ``pic4rl-train`` read each params file once
(``pic4rl_base.params_file.read``, the one reader), then hand typed configs down; nothing
below them reads a file again."""

from __future__ import annotations

from collections import Counter
from pathlib import Path
from typing import Any

import pandas as pd
import pytest
from agents_helpers import ROOT

from pic4rl_agents.launch.rosargs import split_ros_args
from pic4rl_agents.testing import tester
from pic4rl_agents.training import args as trainargs
from pic4rl_base import params_file

AGENT = ROOT / "checkpoints" / "td3_lidar"


@pytest.fixture
def reads(monkeypatch: pytest.MonkeyPatch) -> Counter[str]:
    """Every params file read, by path."""
    counted: Counter[str] = Counter()
    read = params_file.read

    def counting(path: str | Path) -> Any:
        counted[str(Path(path).resolve())] += 1
        return read(path)

    monkeypatch.setattr(params_file, "read", counting)
    return counted


def _test_file(tmp_path: Path) -> Path:
    (tmp_path / "pairs.json").write_text("{}")  # found beside the file; never opened here
    path = tmp_path / "test.yaml"
    path.write_text("nav_env:\n  ros__parameters:\n    episode_max_steps: 50\n"
                    "    episodes: {file: pairs.json}\n"
                    "sim:\n  ros__parameters: {world_variant: 0}\n")
    return path


def test_pic4rl_test_reads_each_params_file_once(tmp_path: Path, reads: Counter[str],
                                                 monkeypatch: pytest.MonkeyPatch) -> None:
    """An agent (its run's config), a baseline beside it and a test params file: main resolves
    the plan once and ``drive_and_judge`` drives what it was handed."""
    extra = _test_file(tmp_path)
    driven: list[Any] = []
    monkeypatch.setattr(tester, "drive_agent", lambda spec, **_: driven.append(spec) or ["goal"])
    monkeypatch.setattr(tester, "judge", lambda run_dir, *_, **__: (pd.DataFrame(), ()))
    monkeypatch.setattr("pic4rl_metrics.tables.text.render_comparison", lambda *a, **k: "")
    monkeypatch.setattr("pic4rl_metrics.tables.results.table_columns", lambda table: [])
    code = tester.main(["--agent", str(AGENT), "--baseline", "dwa", "--bags", str(tmp_path),
                        "--no-progress", "--format", "csv",
                        "--ros-args", "--params-file", str(extra)])
    assert [s.name for s in driven] == ["td3_lidar", "dwa"]
    assert reads == {str((AGENT / "config.yaml").resolve()): 1, str(extra.resolve()): 1}
    assert code == 0
    # What was read reached the envs: the test file's steps, its pairs beside it, recorded.
    for spec in driven:
        assert spec.run.env.episode_max_steps == 50
        assert spec.run.env.episodes.file == str(tmp_path / "pairs.json")
        assert spec.run.env.record.enabled and spec.run.env.record.run == spec.name


def test_pic4rl_train_resume_reads_the_run_config_once(tmp_path: Path,
                                                       reads: Counter[str]) -> None:
    """A resume without a params file: the run's config gives the session's config and the
    checkpoint's "trained with" words from one read."""
    plain, ros = split_ros_args(["--resume", str(AGENT), "-n", "10"])
    run, resume = trainargs.resolve(trainargs.build_parser().parse_args(plain), ros)
    assert reads == {str((AGENT / "config.yaml").resolve()): 1}
    assert resume is not None and resume.trained.startswith("trained with sensor lidar, from ")
    assert run.train.max_steps == 10


def test_the_latest_of_a_runs_configs_is_found_by_the_recorders_naming(tmp_path: Path) -> None:
    """``config.yaml``, ``config-2.yaml``, ...: one naming rule (``atomic.numbered``) for the
    recorder that writes them and the runs that read the newest back."""
    from pic4rl_agents.runs.rundir import run_config_file
    from pic4rl_bridge.recorder import RunRecorder

    written = [RunRecorder(tmp_path, "run", config={"n": n}).config_path for n in range(11)]
    run = tmp_path / "run"
    (run / "config-x.yaml").write_text("{}")  # not of the series
    assert [p.name for p in written[:3]] == ["config.yaml", "config-2.yaml", "config-3.yaml"]
    assert run_config_file(run) == run / "config-11.yaml"  # by number, not by name
