"""Turn what a user types (dirs, ``metadata.yaml``, ``.db3``, ``.mcap``, globs) into bags.

A bag is either a rosbag2 directory (it holds ``metadata.yaml``) or a lone storage file that no
``metadata.yaml`` lists, as a recorder killed mid-episode leaves it. Every bag is found once,
however many inputs name it; an input that names nothing is reported, not dropped.
"""

from __future__ import annotations

import glob
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path

import yaml

STORAGE_SUFFIXES = (".db3", ".mcap")
METADATA = "metadata.yaml"


@dataclass(frozen=True)
class Discovery:
    """Bags found (sorted, unique) and the inputs that named no bag, with the reason."""

    bags: tuple[Path, ...]
    unmatched: tuple[tuple[str, str], ...]


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
    """A storage file's bag: its directory when that directory's metadata lists it."""
    if _is_bag_dir(path.parent) and path.name in _listed_files(path.parent):
        return path.parent
    return path


def _search_dir(root: Path) -> list[Path]:
    """Bags under ``root``: every dir with ``metadata.yaml``, plus unlisted storage files."""
    if _is_bag_dir(root):
        return [root]
    found: list[Path] = []
    for child in sorted(root.iterdir()):
        if child.is_dir():
            found.extend(_search_dir(child))
        elif child.suffix in STORAGE_SUFFIXES:
            found.append(child)
    return found


def _expand(item: str) -> tuple[list[Path], str | None]:
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
        if candidate.is_dir():
            bags.extend(_search_dir(candidate))
        elif candidate.name == METADATA:
            bags.append(candidate.parent)
        elif candidate.suffix in STORAGE_SUFFIXES:
            bags.append(_bag_of_file(candidate))
        elif len(candidates) == 1:
            return [], (
                f"not a bag: expected a rosbag2 directory, {METADATA}, or a "
                f"{' or '.join(STORAGE_SUFFIXES)} file"
            )
    if not bags:
        return [], "no rosbag2 bag (metadata.yaml, .db3 or .mcap) found here"
    return bags, None


def discover(inputs: Iterable[str | Path]) -> Discovery:
    """Resolve inputs to bags, as the user named them; sorted, each bag once."""
    seen: dict[Path, Path] = {}
    unmatched: list[tuple[str, str]] = []
    for item in inputs:
        bags, reason = _expand(str(item))
        if reason is not None:
            unmatched.append((str(item), reason))
        for bag in bags:
            seen.setdefault(bag.resolve(), bag)
    return Discovery(tuple(sorted(seen.values())), tuple(unmatched))
