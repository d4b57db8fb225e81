"""The places table of ``docs/architecture.md``, executed: for a metric, a baseline, a task
and a sensor, a piece written outside the packages (its files under ``tests/places/<piece>/``,
registered as a user registers one: imported, or named in its ``pyproject.toml``'s entry
points) is run end to end, and the table's count for that piece is the number of files its
folder holds."""

from __future__ import annotations

import importlib
import math
import re
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
HERE = Path(__file__).resolve().parent
DOC = ROOT / "docs" / "architecture.md"
#: Each piece's folder under ``tests/places/`` → its row in the places table.
ROWS = {"metric": "a metric"}


def _written(piece: str) -> list[Path]:
    """The files a user wrote for ``piece``."""
    return sorted(p for p in (HERE / piece).rglob("*")
                  if p.is_file() and "__pycache__" not in p.parts)


def _doc_count(row: str) -> int:
    text = DOC.read_text(encoding="utf-8").split("## Places for a new piece", 1)[1]
    found = re.search(rf"^\| {re.escape(row)} \| (\d+) \|", text, re.M)
    assert found, f"docs/architecture.md's places table has no row {row!r}"
    return int(found[1])


@pytest.mark.parametrize("piece", sorted(ROWS))
def test_the_table_counts_the_files_each_piece_took(piece: str) -> None:
    files = _written(piece)
    assert files, f"tests/places/{piece}/ holds no file"
    assert _doc_count(ROWS[piece]) == len(files), \
        f"{ROWS[piece]}: the table says {_doc_count(ROWS[piece])}, the test wrote {len(files)}"


# -- a metric: one file, registered by its import -----------------------------------------------

def test_a_metric_from_outside_gets_its_column_and_its_table_place(
        monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    from pic4rl_metrics import METRIC_TABLE, compute
    from pic4rl_metrics.synthetic import circle, write_episode_bag
    from pic4rl_metrics.tables.groups import render_groups
    from pic4rl_metrics.tables.results import table_columns

    monkeypatch.syspath_prepend(str(HERE / "metric"))
    try:
        importlib.import_module("places_chord")  # as the user's program imports it
        # A quarter of a circle of radius 1 m: the chord is sqrt(2) m, the path pi/2 m.
        quarter = circle(1.0, 0.5, math.pi, dt_s=math.pi / 100)
        bag = write_episode_bag(tmp_path / "quarter", quarter, goal=(1.0, 0.0), outcome="goal")
        frame = compute([bag]).frame
        assert frame.iloc[0]["chord_m"] == pytest.approx(math.sqrt(2.0), abs=1e-9)
        assert frame.iloc[0]["path_length_m"] == pytest.approx(math.pi / 2, rel=1e-3)
        assert table_columns(frame)[-1] == "chord_m"
        table = render_groups(frame.assign(agent="mine"), "markdown", columns=table_columns)
        header, _, row = table.splitlines()[:3]
        assert header.endswith("| chord [m] |") and row.endswith("| 1.41 |"), table
    finally:
        METRIC_TABLE.remove("chord_m")
        sys.modules.pop("places_chord", None)
