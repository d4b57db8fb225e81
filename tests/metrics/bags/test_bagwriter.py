"""The one bag writer: a ``.db3``'s empty tables are created without waiting for the disk,
and what is written after keeps sqlite's syncing (rosbags' one transaction) or the periodic
commits' setting; either bag reads back whole."""

from __future__ import annotations

import sqlite3
from pathlib import Path

import pytest
from rosbags.rosbag2 import Reader

from pic4rl_metrics.bags.bagwriter import STRING, BagWriter, string_cdr


@pytest.mark.parametrize(("flush", "level"), [(None, "default"), (0.0, 0)])
def test_the_writes_keep_their_syncing_and_the_bag_reads_back(
        tmp_path: Path, flush: float | None, level: object) -> None:
    default = sqlite3.connect(":memory:").execute("PRAGMA synchronous").fetchone()[0]
    writer = BagWriter(tmp_path / "bag", flush_interval_s=flush)
    conn = writer._writer.storage.conn  # type: ignore[union-attr]
    assert conn.execute("PRAGMA synchronous").fetchone()[0] == (
        default if level == "default" else level)
    for k in range(3):
        writer.write("/note", STRING, string_cdr(f"n{k}"), 1_000 + k)
    bag = writer.close({})
    with Reader(bag) as reader:
        assert [c.topic for c in reader.connections] == ["/note"]
        assert [t for _, t, _ in reader.messages()] == [1_000, 1_001, 1_002]
