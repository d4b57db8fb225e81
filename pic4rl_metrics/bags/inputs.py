"""Turn what a user types (dirs, ``metadata.yaml``, storage files, ``.bag``, globs) into bags.

A bag is a rosbag2 directory (it holds ``metadata.yaml``), a lone storage file that no
``metadata.yaml`` lists, as a recorder killed mid-episode leaves it (``.db3``, ``.mcap``, either
compressed whole as ``.zstd``), a directory holding the files ``<name>_<n>.<ext>`` of one split
bag without its ``metadata.yaml``, or a ROS 1 ``.bag`` file. Every bag is found once, however
many inputs name it; an input that names nothing is reported, not dropped.
"""

from __future__ import annotations

import glob
import re
import stat
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path

import yaml

STORAGE_SUFFIXES = (".db3", ".mcap")
#: A storage file compressed whole (rosbag2's ``file`` compression mode).
COMPRESSED_SUFFIX = ".zstd"
ROS1_SUFFIX = ".bag"
METADATA = "metadata.yaml"
_KINDS = (f"{'/'.join(STORAGE_SUFFIXES)} file (or its {COMPRESSED_SUFFIX}), "
          f"or ROS 1 {ROS1_SUFFIX} file")
_SPLIT = re.compile(r"(?P<name>.+)_(?P<index>\d+)")


def is_bag_file(path: Path) -> bool:
    """A storage file by its name: ``.db3``, ``.mcap``, either ``.zstd``-compressed, ``.bag``."""
    name = path.name.removesuffix(COMPRESSED_SUFFIX)
    return name.endswith(STORAGE_SUFFIXES) or path.name.endswith(ROS1_SUFFIX)


def _split_key(path: Path) -> tuple[str, str, int] | None:
    """(name, suffixes, index) of a split bag's file ``<name>_<index><suffixes>``."""
    stem, _, rest = path.name.partition(".")
    match = _SPLIT.fullmatch(stem)
    return (match["name"], rest, int(match["index"])) if match else None


def split_parts(directory: Path) -> list[Path]:
    """The files of one split bag in a directory without ``metadata.yaml``, in index order:
    two or more storage files, all ``<name>_<n>`` of one name and kind; else []."""
    if _is_bag_dir(directory):
        return []
    files = [p for p in directory.iterdir() if p.is_file() and is_bag_file(p)]
    keys = [_split_key(p) for p in files]
    if len(files) < 2 or None in keys or len({k[:2] for k in keys if k}) != 1:
        return []
    return [p for _, p in sorted(zip([k[2] for k in keys if k], files, strict=True))]


@dataclass(frozen=True)
class Discovery:
    """Bags found (sorted, unique), the inputs that named no bag with the reason, and the
    warnings about what was skipped (neither a regular file nor a directory)."""

    bags: tuple[Path, ...]
    unmatched: tuple[tuple[str, str], ...]
    skipped: tuple[str, ...] = ()


def special(path: Path) -> str | None:
    """What ``path`` is when it exists and is neither a regular file nor a directory (a FIFO,
    a socket, a device), else None."""
    try:
        mode = path.stat().st_mode
    except OSError:
        return None
    if stat.S_ISREG(mode) or stat.S_ISDIR(mode):
        return None
    kinds = ((stat.S_ISFIFO, "a FIFO"), (stat.S_ISSOCK, "a socket"), (stat.S_ISCHR, "a device"),
             (stat.S_ISBLK, "a device"))
    return next((name for test, name in kinds if test(mode)), "not a regular file")


def _skip_note(path: Path, kind: str) -> str:
    return f"{str(path)!r} is {kind}, not a regular file or directory; skipped"


def _listed_files(bag_dir: Path) -> set[str]:
    """Storage files a ``metadata.yaml`` lists (empty when it cannot be read)."""
    try:
        info = yaml.safe_load((bag_dir / METADATA).read_text())["rosbag2_bagfile_information"]
        return {Path(p).name for p in info.get("relative_file_paths") or []}
    except (OSError, yaml.YAMLError, KeyError, TypeError):
        return set()


def _is_bag_dir(path: Path) -> bool:
    return (path / METADATA).is_file()


def _bag_of_file(path: Path) -> Path:
    """A storage file's bag: its directory when that directory's metadata lists it or the
    file is a part of the directory's split bag."""
    if _is_bag_dir(path.parent) and path.name in _listed_files(path.parent):
        return path.parent
    if path in split_parts(path.parent):
        return path.parent
    return path


def _search_dir(root: Path, skipped: list[str]) -> list[Path]:
    """Bags under ``root``: every dir with ``metadata.yaml`` or a split bag's files, plus
    unlisted storage files (what is neither a file nor a directory goes to ``skipped``)."""
    if _is_bag_dir(root) or split_parts(root):
        return [root]
    found: list[Path] = []
    for child in sorted(root.iterdir()):
        kind = special(child)
        if kind is not None:
            if is_bag_file(child):
                skipped.append(_skip_note(child, kind))
        elif child.is_dir():
            found.extend(_search_dir(child, skipped))
        elif is_bag_file(child):
            found.append(child)
    return found


def _expand(item: str, skipped: list[str]) -> tuple[list[Path], str | None]:
    path = Path(item)
    if path.exists():
        candidates = [path]
    elif glob.has_magic(item):
        candidates = [Path(p) for p in sorted(glob.glob(item, recursive=True))]
        if not candidates:
            return [], "no file matches this pattern"
    else:
        return [], "no such file or directory"

    bags: list[Path] = []
    for candidate in candidates:
        kind = special(candidate)
        if kind is not None:
            skipped.append(_skip_note(candidate, kind))
            if len(candidates) == 1:
                return [], None
        elif candidate.is_dir():
            bags.extend(_search_dir(candidate, skipped))
        elif candidate.name == METADATA:
            bags.append(candidate.parent)
        elif is_bag_file(candidate):
            bags.append(_bag_of_file(candidate))
        elif len(candidates) == 1:
            return [], f"not a bag: expected a rosbag2 directory, {METADATA}, a {_KINDS}"
    if not bags:
        return [], f"no bag found here (no {METADATA}, {_KINDS})"
    return bags, None


def discover(inputs: Iterable[str | Path]) -> Discovery:
    """Resolve inputs to bags, as the user named them; sorted, each bag once."""
    seen: dict[Path, Path] = {}
    unmatched: list[tuple[str, str]] = []
    skipped: list[str] = []
    for item in inputs:
        bags, reason = _expand(str(item), skipped)
        if reason is not None:
            unmatched.append((str(item), reason))
        for bag in bags:
            seen.setdefault(bag.resolve(), bag)
    return Discovery(tuple(sorted(seen.values())), tuple(unmatched), tuple(dict.fromkeys(skipped)))
