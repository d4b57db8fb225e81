"""Files written whole or not at all: each goes to a temporary file beside it, then is renamed
over it (``os.replace``), so a process killed mid-write leaves the previous file (or none),
never half of one. The metrics' tables, figures and videos go this way, and the agents'
checkpoints, replay buffers, configs, summaries and curves.

``claim_dir`` gives a new run folder the same way: created exclusively, never shared.

A temporary file is hidden (``.<name>.<random>.tmp<suffix>``): no run-directory glob sees it,
and the suffix is the target's, since SB3 appends ``.zip`` or ``.pkl`` to a path without one.
"""

from __future__ import annotations

import contextlib
import os
import secrets
from collections.abc import Iterator
from pathlib import Path

#: The glob of the temporary files a killed process may leave behind.
PARTIAL_GLOB = ".*.tmp*"


@contextlib.contextmanager
def temporary(path: str | Path) -> Iterator[Path]:
    """A new, empty, hidden file beside ``path`` (the umask's permissions, not mkstemp's 0600),
    removed when the block ends unless the block moved it."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    while True:
        tmp = path.with_name(f".{path.name}.{secrets.token_hex(4)}.tmp{path.suffix}")
        try:
            tmp.open("xb").close()
            break
        except FileExistsError:
            continue
    try:
        yield tmp
    finally:
        tmp.unlink(missing_ok=True)


@contextlib.contextmanager
def replacing(path: str | Path) -> Iterator[Path]:
    """A temporary path beside ``path`` to write; when the block ends it replaces ``path``
    (after an ``fsync``), and when the block raises it is removed and ``path`` is untouched."""
    with temporary(path) as tmp:
        yield tmp
        with tmp.open("rb+") as written:
            os.fsync(written.fileno())
        os.replace(tmp, path)


def write_text(path: str | Path, text: str) -> Path:
    """Write ``text`` to ``path`` whole or not at all."""
    with replacing(path) as tmp:
        tmp.write_text(text)
    return Path(path)


def remove_partials(folder: Path) -> list[Path]:
    """Delete the temporary files under ``folder`` that a killed writer left; those deleted."""
    partials = [p for p in folder.rglob(PARTIAL_GLOB) if p.is_file()]
    for partial in partials:
        partial.unlink(missing_ok=True)
    return partials


def numbered(path: Path, n: int, *, keep_suffix: bool = False) -> Path:
    """The ``n``-th of a series of files that never overwrite each other: ``path`` itself for
    1, else ``<name>-<n>`` (before the suffix with ``keep_suffix``: ``config-2.yaml``)."""
    if n == 1:
        return path
    stem, suffix = (path.stem, path.suffix) if keep_suffix else (path.name, "")
    return path.with_name(f"{stem}-{n}{suffix}")


def claim_dir(path: str | Path) -> Path:
    """The first of ``numbered(path, 1)``, ``numbered(path, 2)``, ... that this call creates
    (its parents made): ``os.mkdir`` is exclusive, so processes claiming the same name at once
    each get a folder of their own."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    n = 1
    while True:
        try:
            numbered(path, n).mkdir()
            return numbered(path, n)
        except FileExistsError:
            n += 1


def series_index(path: Path, first: Path) -> int | None:
    """Which of ``numbered(first, n, keep_suffix=True)`` ``path`` is, or None for another."""
    if path.name == first.name:
        return 1
    number = path.name.removeprefix(f"{first.stem}-").removesuffix(first.suffix)
    ok = path.name.startswith(f"{first.stem}-") and path.name.endswith(first.suffix)
    return int(number) if ok and number.isdigit() else None
