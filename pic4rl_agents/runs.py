"""The layout of a run directory, ``<runs_dir>/<run>/``, in one place."""

from __future__ import annotations

from pathlib import Path


def free_path(path: Path, *, keep_suffix: bool = False) -> Path:
    """``path``, or ``<name>-2``, ``<name>-3``, ... (before the suffix with ``keep_suffix``):
    the first that does not exist, so nothing is overwritten."""
    stem, suffix = (path.stem, path.suffix) if keep_suffix else (path.name, "")
    candidate, n = path, 1
    while candidate.exists():
        n += 1
        candidate = path.with_name(f"{stem}-{n}{suffix}")
    return candidate


def run_config_file(folder: Path) -> Path | None:
    """A run folder's latest params file: ``config.yaml`` or its newest ``config-N.yaml``."""
    found = [p for p in folder.glob("config*.yaml")
             if p.stem == "config" or p.stem.removeprefix("config-").isdigit()]
    return max(found, key=lambda p: int(p.stem.removeprefix("config-") or 1)
               if p.stem != "config" else 1, default=None)
