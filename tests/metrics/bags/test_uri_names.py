"""Folder and run names that mean something in a URI (``#``, ``?``, ``%xx``), spaces and
unicode: a bag is written inside its own folder and reads back whole (issue 37, item 1).

SQLite opens a ``file:`` URI: an unquoted ``#`` ended the path (the writer wrote ``bags/run ``
outside the run), ``?`` started a query (``run?1`` and ``run?2`` would share one file) and
``%20`` was decoded (a bag under ``a%20b/`` could not be opened).
"""

from __future__ import annotations

import contextlib
import sqlite3
from pathlib import Path

import pytest

from pic4rl_metrics import compute
from pic4rl_metrics.bags.bagwriter import STRING, BagWriter, string_cdr
from pic4rl_metrics.bags.bagfile import uri_path
from pic4rl_metrics.synthetic.synthetic import straight_line, write_episode_bag

NAMES = ["run #2", "run?1", "a%20b", "with space", "ünïcødé λ", "100%", "a#b?c%3Fd"]


def _files(root: Path) -> list[str]:
    return sorted(str(p.relative_to(root)) for p in root.rglob("*") if p.is_file())


@pytest.mark.parametrize("name", NAMES)
@pytest.mark.parametrize("storage", ["sqlite3", "mcap"])
def test_a_bag_in_a_folder_named_so_is_written_inside_it_and_read_back(
        tmp_path: Path, name: str, storage: str) -> None:
    bag = write_episode_bag(tmp_path / name / "episode_0000", straight_line(0.5, 10.0),
                            outcome="goal", storage=storage)
    ext = "db3" if storage == "sqlite3" else "mcap"
    assert _files(tmp_path) == [f"{name}/episode_0000/episode_0000.{ext}",
                                f"{name}/episode_0000/metadata.yaml"]
    frame = compute([bag]).frame
    assert frame["error"].tolist() == [""]
    assert frame["outcome"].tolist() == ["goal"]
    assert frame["path_length_m"].iloc[0] == pytest.approx(5.0, abs=1e-9)  # 0.5 m/s for 10 s
    # the storage file alone (as a killed recorder leaves it) reads too
    killed = write_episode_bag(tmp_path / name / "episode_0001", straight_line(0.5, 4.0),
                               storage=storage, write_metadata=False)
    lone = compute([killed / f"episode_0001.{ext}"]).frame
    assert lone["error"].tolist() == [""]
    assert lone["path_length_m"].iloc[0] == pytest.approx(2.0, abs=1e-9)


def test_runs_named_with_a_question_mark_stay_apart(tmp_path: Path) -> None:
    """``run?1`` and ``run?2`` were one file ``run``: the second writer failed on it."""
    for k, speed in ((1, 0.5), (2, 0.25)):
        writer = BagWriter(tmp_path / f"run?{k}")
        for i in range(k + 1):
            writer.write("/note", STRING, string_cdr(f"{k}.{i}"), 1_000 + i)
        writer.close({})
        write_episode_bag(tmp_path / f"ep?{k}", straight_line(speed, 4.0), outcome="goal")
    assert _files(tmp_path) == sorted(
        [f"{d}?{k}/{f}" for d in ("ep", "run") for k in (1, 2)
         for f in (f"{d}?{k}.db3", "metadata.yaml")])
    for k in (1, 2):
        with contextlib.closing(sqlite3.connect(tmp_path / f"run?{k}" / f"run?{k}.db3")) as db:
            assert db.execute("SELECT count(*) FROM messages").fetchone() == (k + 1,)
    frame = compute([tmp_path / "ep?1", tmp_path / "ep?2"]).frame
    assert frame["path_length_m"].tolist() == pytest.approx([2.0, 1.0], abs=1e-9)


def test_a_path_becomes_a_uri_path_with_every_special_character_quoted() -> None:
    assert uri_path(Path("/b/run #2/x?1/a%20b/ü")) == "/b/run%20%232/x%3F1/a%2520b/%C3%BC"
    assert uri_path(Path("rel/ok_-.~name")) == "rel/ok_-.~name"
