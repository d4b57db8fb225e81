"""Judge many bags: one row per bag, a bad bag becomes an error row and the batch goes on.

This is the library behind ``pic4rl-metrics compute`` and the tester of ``pic4rl_agents``.
"""

from __future__ import annotations

import gc
import logging
import math
import os
from collections.abc import Callable, Iterable, Sequence
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass
from functools import cached_property
from pathlib import Path
from typing import Any

import pandas as pd
from tqdm import tqdm

from pic4rl_base.errors import ConfigError, Pic4rlError

from ..bags.inputs import discover
from ..bags.reader import read_episode
from ..bags.topics import TopicMap
from ..contract import EpisodeFacts
from ..core.metrics import compute_metrics
from ..core.registry import METRIC_TABLE
from ..core.series import Episode
from .results import ERROR_COLUMN, ID_COLUMNS, METRIC_COLUMNS, EpisodeMetrics

log = logging.getLogger(__name__)

WARNINGS_COLUMN = "warnings"
#: Columns of a result with pic4rl's own metrics (user metrics go before ``error``).
COLUMNS: tuple[str, ...] = (*ID_COLUMNS, *METRIC_COLUMNS, ERROR_COLUMN, WARNINGS_COLUMN)


def result_columns(metric_names: Sequence[str]) -> tuple[str, ...]:
    """Ids, the given metric columns, error and warnings."""
    return (*ID_COLUMNS, *metric_names, ERROR_COLUMN, WARNINGS_COLUMN)


@dataclass(frozen=True)
class BagResult:
    """What became of one bag: its episode and metrics, or the error that stopped it."""

    bag: str
    episode: Episode | None
    metrics: EpisodeMetrics | None
    error: str = ""

    @property
    def warnings(self) -> tuple[str, ...]:
        """The reader's warnings, then the metrics'."""
        read = self.episode.warnings if self.episode is not None else ()
        return (*read, *(self.metrics.warnings if self.metrics is not None else ()))

    def row(self, columns: Sequence[str] = COLUMNS) -> dict[str, object]:
        """One DataFrame row: ids, metrics (NaN when failed), error and warnings."""
        row: dict[str, object] = dict.fromkeys(columns, math.nan)
        row.update(bag=self.bag, error=self.error, warnings="")
        for key in ("agent", "task", "world", "run", "episode", "pose_topic", "outcome"):
            row[key] = None
        if self.episode is not None:
            facts = self.episode.facts
            row.update(
                agent=facts.agent, task=facts.task, world=facts.world, run=facts.run,
                episode=facts.episode, pose_topic=self.episode.pose_topic,
            )
        row[WARNINGS_COLUMN] = "; ".join(self.warnings)
        if self.metrics is not None:
            row.update(self.metrics.as_dict())
        return row


@dataclass(frozen=True)
class MetricsResult:
    """All bags' results; ``frame`` has one row per bag, in ``columns`` order."""

    results: tuple[BagResult, ...]
    columns: tuple[str, ...] = COLUMNS
    #: Warnings about inputs skipped (``inputs.Discovery.skipped``: a FIFO named ``x.db3``).
    skipped: tuple[str, ...] = ()

    @cached_property
    def frame(self) -> pd.DataFrame:
        columns = list(self.columns)
        return pd.DataFrame([r.row(columns) for r in self.results], columns=columns)

    @property
    def failed(self) -> tuple[BagResult, ...]:
        return tuple(r for r in self.results if r.error)

    @property
    def episodes(self) -> tuple[Episode, ...]:
        return tuple(r.episode for r in self.results if r.episode is not None)


def judge_bag(
    bag: Path | str,
    topic_map: TopicMap | None = None,
    facts: EpisodeFacts | None = None,
    given: frozenset[str] = frozenset(),
    metrics: Sequence[str] | None = None,
    full_scans: bool = False,
    progress: bool = False,
    scan_sample: int = 0,
) -> BagResult:
    """Read and judge one bag (all metrics, or the named ones); every failure is caught and
    described, never raised. ``full_scans``: the episode keeps every beam (plots, videos);
    ``scan_sample``: at most that many whole scans beside the summary (maps);
    ``progress``: a bar on stderr while a long bag is read."""
    try:
        selected = METRIC_TABLE.select(metrics)
        episode = read_episode(bag, topic_map, facts, given, full_scans=full_scans,
                               progress=progress, scan_sample=scan_sample)
        judged = compute_metrics(episode, selected, explicit=metrics is not None)
        return BagResult(str(bag), episode, judged)
    except Pic4rlError as err:
        return BagResult(str(bag), None, None, str(err))
    except Exception as err:  # noqa: BLE001 - one broken bag must not stop a batch
        log.debug("unexpected error on %s", bag, exc_info=True)
        return BagResult(str(bag), None, None, f"{str(bag)!r}: {type(err).__name__}: {err}")


def _judge_args(
    args: tuple[Path, TopicMap | None, EpisodeFacts | None, frozenset[str], Sequence[str] | None,
                bool, bool, int],
) -> BagResult:
    return judge_bag(*args)


def resolve_jobs(jobs: int) -> int:
    """Worker processes for ``jobs``: itself when positive, every core for 0."""
    if jobs < 0:
        msg = f"jobs={jobs!r}: expected a positive number of processes, or 0 for every core"
        raise ConfigError(msg)
    return jobs or os.cpu_count() or 1


def compute(
    inputs: Iterable[str | Path],
    *,
    topic_map: TopicMap | None = None,
    facts: EpisodeFacts | None = None,
    given: frozenset[str] = frozenset(),
    jobs: int = 1,
    progress: bool = False,
    metrics: Sequence[str] | None = None,
    full_scans: bool = False,
    scan_sample: int = 0,
) -> MetricsResult:
    """Judge every bag named by ``inputs`` (see ``inputs.discover``), ``jobs`` at a time (0:
    one per core). ``metrics``: the columns to compute (default: every registered metric;
    ``outcome`` and ``success`` always), else ``topic_map.metrics``.

    Inputs that name no bag become error rows too. ``progress`` shows a bar on stderr (and,
    one bag at a time, one per long bag). ``full_scans``: the episodes keep every beam;
    ``scan_sample``: they keep at most that many whole scans each, evenly spread (maps).
    Unknown metric names or a negative ``jobs`` raise ``ConfigError``.
    """
    jobs = resolve_jobs(jobs)
    if metrics is None and topic_map is not None:
        metrics = topic_map.metrics
    names = tuple(m.name for m in METRIC_TABLE.select(metrics))
    found = discover(inputs)
    unmatched = [BagResult(item, None, None, f"{item!r}: {why}") for item, why in found.unmatched]
    chosen = names if metrics is not None else None
    work = [(bag, topic_map, facts, given, chosen, full_scans, progress and jobs == 1,
             scan_sample)
            for bag in found.bags]
    results = run_parallel(_judge_args, work, jobs=jobs, progress=progress, what="bags")
    return MetricsResult(tuple(unmatched + results), result_columns(names), found.skipped)


def run_parallel(fn: Callable[[Any], Any], work: Sequence[Any], *, jobs: int, progress: bool,
                 what: str) -> list[Any]:
    """``fn`` over ``work`` in order, in ``jobs`` processes (one: in this one), with a progress
    bar counting ``what`` (a plural noun) on stderr when ``progress``."""
    bar = tqdm(total=len(work), desc=what, unit=what.rstrip("s"), disable=not progress,
               leave=False)
    out: list[Any] = []
    with bar:
        if jobs > 1 and len(work) > 1:
            # The workers are forked: garbage whose destructor takes a lock that a thread of
            # this process held (Ray's GCS client after ray.shutdown) would hang a worker's
            # first collection, so it is collected here, before the fork.
            gc.collect()
            with ProcessPoolExecutor(max_workers=min(jobs, len(work))) as pool:
                chunks = max(1, len(work) // (4 * jobs))
                for item in pool.map(fn, work, chunksize=chunks):
                    out.append(item)
                    bar.update()
        else:
            for item in work:
                out.append(fn(item))
                bar.update()
    return out

