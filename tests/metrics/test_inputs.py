"""``inputs``: directories, files and globs name each bag once; naming nothing is an error row.
"""

from __future__ import annotations

from pathlib import Path

from pic4rl_metrics import (
    compute,
)
from pic4rl_metrics.synthetic import (
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
