"""The HTML report's provenance: what the page was built from and with.

A line under the title states the tool's version, the git commit of its source when that is a
checkout, and the episodes' seeds (``provenance``). The Inputs section is one summary line
with the detail behind a ``<details>``: the inputs as given, the bags' folders, a hash of each
run's config file and of each agent's run set-up, the time written (``inputs_section``).
"""

from __future__ import annotations

import hashlib
import json
import subprocess
from collections.abc import Iterable, Sequence
from datetime import datetime, timezone
from importlib.metadata import PackageNotFoundError, version
from pathlib import Path

import pandas as pd

from ..tables.batch import MetricsResult
from . import html_page as hp

#: Episodes' facts that change from episode to episode: left out of a run's setup hash.
_PER_EPISODE = {"episode", "seed", "start", "goal", "outcome", "shortest_path_m",
                "straight_line_m", "row_centerline"}


def tool_version() -> str:
    """The installed ``pic4rl`` distribution's version, "unknown" when it is not installed."""
    try:
        return version("pic4rl")
    except PackageNotFoundError:
        return "unknown"


def source_commit() -> str | None:
    """The git commit (12 hex digits) of the checkout this package runs from; None when it
    runs from no checkout (an installed wheel) or git is missing."""
    try:
        done = subprocess.run(["git", "-C", str(Path(__file__).resolve().parent), "rev-parse",
                               "--short=12", "HEAD"], capture_output=True, text=True, timeout=5,
                              check=False)
    except (OSError, subprocess.SubprocessError):
        return None
    commit = done.stdout.strip()
    return commit if done.returncode == 0 and commit else None


def seed_ranges(seeds: Iterable[int]) -> str:
    """Whole numbers as sorted runs: ``0–3, 7, 1000–1003``; "none recorded" when empty."""
    values = sorted(set(seeds))
    runs: list[list[int]] = []
    for v in values:
        if runs and v == runs[-1][1] + 1:
            runs[-1][1] = v
        else:
            runs.append([v, v])
    return ", ".join(f"{a}" if a == b else f"{a}–{b}" for a, b in runs) or "none recorded"


def provenance(result: MetricsResult) -> str:
    """The line under the title: version, commit (when known) and the episodes' seeds."""
    seeds = [r.episode.facts.seed for r in result.results
             if r.episode is not None and r.episode.facts.seed is not None]
    read = sum(r.episode is not None for r in result.results)
    commit = source_commit()
    parts = [f"pic4rl {tool_version()}", f"git commit {commit}" if commit else
             "git commit unknown (not run from a checkout)",
             f"seeds {seed_ranges(seeds)} ({len(seeds)} of {read} episodes record one)"]
    return f'<p class="provenance">{hp.text(" · ".join(parts)).markup}</p>'


def _file_hash(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()[:12]


def inputs_section(result: MetricsResult, names: pd.Series, inputs: Sequence[str]) -> str:
    """The Inputs section: a summary, the detail (``names``: each row's agent) folded."""
    folders = sorted({str(Path(r.bag).resolve().parent) for r in result.results})
    configs = sorted({p for f in folders for d in (Path(f), Path(f).parent)
                      for p in d.glob("config*.yaml")})
    setups: dict[tuple[str, str], set[str]] = {}
    for i, r in enumerate(result.results):
        if r.episode is None:
            continue
        values = {k: v for k, v in r.episode.facts.values().items() if k not in _PER_EPISODE}
        digest = hashlib.sha256(json.dumps(values, sort_keys=True, default=str).encode())
        run = str(r.episode.facts.run or "?")
        setups.setdefault((str(names.iloc[i]), run), set()).add(digest.hexdigest()[:12])
    written = datetime.now(timezone.utc).strftime("%Y-%m-%d %H:%M:%S UTC")
    rows = [[hp.text("inputs"), hp.text(" ".join(inputs) or "–")],
            [hp.text("bag folders"), hp.text("; ".join(folders))],
            *([hp.text(f"config {c}"), hp.text(_file_hash(c))] for c in configs),
            *([hp.text(f"setup of {a} / {run}"), hp.text(", ".join(sorted(h)))]
              for (a, run), h in setups.items()),
            [hp.text("pic4rl version"), hp.text(tool_version())],
            [hp.text("git commit"), hp.text(source_commit() or "unknown")],
            [hp.text("written"), hp.text(written)]]
    mixed = [key for key, h in setups.items() if len(h) > 1]
    summary = (f"{len(inputs)} input(s), {len(result.results)} bag(s) in {len(folders)} "
               f"folder(s), {len(configs)} config file(s), {len(setups)} agent run(s) "
               + (f"({len(mixed)} with more than one set-up: see the detail)" if mixed else
                  "each with one set-up") + f"; written {written}")
    note = ("<p class=note>config: sha256 (first 12 hex digits) of each config*.yaml in the "
            "bags' folders and those above them; setup: of the facts an agent's run shares "
            "across its episodes (robot, world, task, tolerances, footprint, budget); more "
            "than one means the run mixed set-ups.</p>")
    return (f"<p>{hp.text(summary).markup}.</p><details><summary>every input, folder, config "
            f"and set-up</summary>{note}{hp.table('inputs', ['what', 'value'], rows)}"
            "</details>")
