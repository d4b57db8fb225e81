"""docs/sensors.md, held to the code: one row and one section for every sensor kind of the
sim's table, every topic it names in the sim's interface table, every path and link there."""

from __future__ import annotations

import re
from pathlib import Path

from docs_helpers import broken_links

from pic4rl_sim.engine.sensors import OWN_KINDS
from pic4rl_sim.interfaces import INTERFACE_TABLE

ROOT = Path(__file__).resolve().parents[2]
DOC = ROOT / "docs" / "sensors.md"


def _kinds() -> dict[str, list[str]]:
    """The summary table's rows by kind (its second cell): kind → the row's cells."""
    rows = {}
    for line in DOC.read_text(encoding="utf-8").splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if len(cells) == 5 and re.fullmatch(r"`\w+`", cells[1]):
            rows[cells[1].strip("`")] = cells
    return rows


def test_every_sensor_kind_has_a_row_and_a_section() -> None:
    rows, text = _kinds(), DOC.read_text(encoding="utf-8")
    assert set(rows) == set(OWN_KINDS), sorted(rows)
    for kind, cells in rows.items():
        anchor = re.match(r"\[(.+)\]\(#([\w-]+)\)", cells[0])
        assert anchor and f"\n## {anchor.group(1)}\n" in text, kind
        assert (ROOT / cells[2].strip("`")).exists(), cells[2]


def test_every_topic_named_is_one_the_sim_has() -> None:
    names = {i.name for i in INTERFACE_TABLE}
    for kind, cells in _kinds().items():
        for topic in re.findall(r"`([\w/]+)`", cells[3]):
            assert topic in names, (kind, topic)


def test_every_link_and_path_exists() -> None:
    count, broken = broken_links(DOC)
    assert count > 5 and broken == []
    paths = re.findall(r"`((?:pic4rl_\w+|tests|docs|config)/[\w./-]+)`", DOC.read_text("utf-8"))
    assert paths and [p for p in paths if not (ROOT / p).exists()] == []
