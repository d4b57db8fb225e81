"""``inputs``: directories, files and globs name each bag once; naming nothing is an error row.
"""

from __future__ import annotations

import os
import stat
from pathlib import Path

import pytest

from pic4rl_metrics import (
    compute,
)
from pic4rl_metrics.cli.commands import main
from pic4rl_metrics.synthetic.synthetic import (
    straight_line,
    write_episode_bag,
)

# --- inputs ------------------------------------------------------------------------------------


def _bags(inputs: list[object]) -> list[Path]:
    frame = compute(inputs).frame  # type: ignore[arg-type]
    assert (frame["error"] == "").all(), frame["error"].tolist()
    return [Path(b).resolve() for b in frame["bag"]]


def test_inputs_all_name_the_same_bags_once(tmp_path: Path) -> None:
    root = tmp_path / "runs"
    short = straight_line(0.5, 1.0)
    a = write_episode_bag(root / "a", short)
    b = write_episode_bag(root / "deep" / "er" / "b", short)
    k = write_episode_bag(root / "deep" / "k", short, write_metadata=False)
    every = sorted(p.resolve() for p in (a, b, k / "k.db3"))

    assert _bags([root]) == every  # a directory, searched recursively
    assert _bags([a / "metadata.yaml"]) == [a.resolve()]
    assert _bags([a / "a.db3"]) == [a.resolve()]  # the .db3 beside its metadata is that bag
    assert _bags([a, a / "metadata.yaml", a / "a.db3"]) == [a.resolve()]  # once, not thrice
    assert _bags([str(root / "**" / "metadata.yaml")]) == sorted([a.resolve(), b.resolve()])
    assert _bags([str(root / "**" / "*.db3")]) == every
    assert _bags([root, str(root / "*"), a, k / "k.db3", b / "metadata.yaml"]) == every


def test_input_naming_nothing_is_an_error_row(tmp_path: Path) -> None:
    frame = compute([tmp_path / "missing", str(tmp_path / "*.db3")]).frame
    assert len(frame) == 2
    assert all(frame["error"] != "")
    assert frame["outcome"].isna().all()


@pytest.mark.bad_input
def test_a_fifo_named_like_a_bag_is_skipped_with_a_warning_not_waited_on(
    tmp_path: Path, capsys: pytest.CaptureFixture[str],
) -> None:
    """Opening a FIFO waits for a writer forever: ``compute`` hung on one named ``x.db3``,
    with no output even for the good bags (issue 27, item 10)."""
    good = write_episode_bag(tmp_path / "runs" / "good", straight_line(0.5, 1.0))
    fifo = tmp_path / "runs" / "stuck.db3"
    os.mkfifo(fifo)
    inside = write_episode_bag(tmp_path / "inside", straight_line(0.5, 1.0))
    os.mkfifo(inside / "inside_1.db3")  # a storage file of a bag that is a FIFO
    result = compute([tmp_path / "runs", fifo])
    assert [Path(b).name for b in result.frame["bag"]] == ["good"]
    note = f"{str(fifo)!r} is a FIFO, not a regular file or directory; skipped"
    assert result.skipped == (note,)  # once, however many inputs reach it
    assert result.frame["error"].tolist() == [""]
    assert main(["compute", str(tmp_path / "runs"), str(inside)]) == 1
    err = capsys.readouterr().err
    assert f"warning: {note}" in err
    assert (f"error: {str(inside / 'inside_1.db3')!r} is a FIFO, not a regular file or "
            "directory; not read") in err
    assert good.exists() and stat.S_ISFIFO(fifo.stat().st_mode)  # nothing touched


@pytest.mark.bad_input
def test_a_lone_fifo_exits_non_zero_naming_the_skip(
    tmp_path: Path, capsys: pytest.CaptureFixture[str],
) -> None:
    """``compute x.db3`` on a FIFO printed an empty table and exited 0, where an empty folder
    exits 1 (issue 37, minor): nothing was judged, so it fails, naming what was skipped."""
    fifo = tmp_path / "x.db3"
    os.mkfifo(fifo)
    assert main(["compute", str(fifo)]) == 1
    err = capsys.readouterr().err
    assert f"warning: {str(fifo)!r} is a FIFO, not a regular file or directory; skipped" in err
    assert ("error: no bag judged: every input was skipped (neither a regular file nor a "
            "directory)") in err
    empty = tmp_path / "empty"
    empty.mkdir()
    assert main(["compute", str(empty)]) == 1  # as before
    good = write_episode_bag(tmp_path / "good", straight_line(0.5, 1.0))
    assert main(["compute", str(good), str(fifo)]) == 0  # a bag judged: the skip is a warning
    assert "warning:" in capsys.readouterr().err
