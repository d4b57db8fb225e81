"""The study's default Optuna storage is a SQLAlchemy URL built from the study folder: a
folder named with ``?``, ``#`` or ``%xx`` must stay that folder (issue 37, item 1: every path
that becomes a URI is quoted). ``sqlite:///…/a?b/study.db`` opened ``…/a``."""

from __future__ import annotations

from pathlib import Path

import optuna
import pytest
from agents_helpers import LIDAR_TD3
from sqlalchemy.engine import make_url

from pic4rl_agents.tune import search as tune


@pytest.mark.parametrize("name", ["a?b", "c#d", "e%20f", "g h ü"])
def test_the_default_storage_names_the_study_folder(tmp_path: Path, name: str) -> None:
    study_dir = tmp_path / name
    args = tune.build_parser().parse_args(["--base", str(LIDAR_TD3), "--study-dir", str(study_dir)])
    storage = tune.settings_from(args).storage
    assert make_url(storage).database == str((study_dir / "study.db").resolve())
    optuna.create_study(study_name="s", storage=storage)
    assert [p.name for p in tmp_path.iterdir()] == [name]
    assert (study_dir / "study.db").is_file()
