"""Judge many bags: one row per bag, a bad bag becomes an error row and the batch goes on.

This is the library behind ``pic4rl-metrics compute`` and the tester of ``pic4rl_agents``.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Iterable
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass
from functools import cached_property
from pathlib import Path

import pandas as pd
from tqdm import tqdm

from .errors import MetricsError
from .facts import EpisodeFacts
from .inputs import discover
from .metrics import compute_metrics
from .reader import read_episode
from .results import ERROR_COLUMN, ID_COLUMNS, METRIC_COLUMNS, EpisodeMetrics
from .series import Episode
from .topics import TopicMap

log = logging.getLogger(__name__)

WARNINGS_COLUMN = "warnings"
COLUMNS: tuple[str, ...] = (*ID_COLUMNS, *METRIC_COLUMNS, ERROR_COLUMN, WARNINGS_COLUMN)


@dataclass(frozen=True)
class BagResult:
    """What became of one bag: its episode and metrics, or the error that stopped it."""

    bag: str
    episode: Episode | None
    metrics: EpisodeMetrics | None
    error: str = ""

    def row(self) -> dict[str, object]:
        """One DataFrame row: ids, metrics (NaN when failed), error and warnings."""
        row: dict[str, object] = dict.fromkeys(COLUMNS, math.nan)
        row.update(bag=self.bag, error=self.error, warnings="")
        for key in ("agent", "task", "world", "run", "episode", "pose_topic", "outcome"):
            row[key] = None
        if self.episode is not None:
            facts = self.episode.facts
            row.update(
                agent=facts.agent, task=facts.task, world=facts.world, run=facts.run,
                episode=facts.episode, pose_topic=self.episode.pose_topic,
                warnings="; ".join(self.episode.warnings),
            )
        if self.metrics is not None:
            row.update(self.metrics.as_dict())
        return row


@dataclass(frozen=True)
class MetricsResult:
    """All bags' results; ``frame`` has one row per bag in ``COLUMNS`` order."""

    results: tuple[BagResult, ...]

    @cached_property
    def frame(self) -> pd.DataFrame:
        return pd.DataFrame([r.row() for r in self.results], columns=list(COLUMNS))

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
) -> BagResult:
    """Read and judge one bag; every failure is caught and described, never raised."""
    try:
        episode = read_episode(bag, topic_map, facts, given)
        return BagResult(str(bag), episode, compute_metrics(episode))
    except MetricsError as err:
        return BagResult(str(bag), None, None, str(err))
    except Exception as err:  # noqa: BLE001 - one broken bag must not stop a batch
        log.debug("unexpected error on %s", bag, exc_info=True)
        return BagResult(str(bag), None, None, f"{str(bag)!r}: {type(err).__name__}: {err}")


def _judge_args(args: tuple[Path, TopicMap | None, EpisodeFacts | None, frozenset[str]]) -> BagResult:
    return judge_bag(*args)


def compute(
    inputs: Iterable[str | Path],
    *,
    topic_map: TopicMap | None = None,
    facts: EpisodeFacts | None = None,
    given: frozenset[str] = frozenset(),
    jobs: int = 1,
    progress: bool = False,
) -> MetricsResult:
    """Judge every bag named by ``inputs`` (see ``inputs.discover``), ``jobs`` at a time.

    Inputs that name no bag become error rows too. ``progress`` shows a bar on stderr.
    """
    found = discover(inputs)
    unmatched = [BagResult(item, None, None, f"{item!r}: {why}") for item, why in found.unmatched]
    work = [(bag, topic_map, facts, given) for bag in found.bags]
    bar = tqdm(total=len(work), desc="bags", unit="bag", disable=not progress, leave=False)
    results: list[BagResult] = []
    with bar:
        if jobs > 1 and len(work) > 1:
            with ProcessPoolExecutor(max_workers=jobs) as pool:
                for result in pool.map(_judge_args, work, chunksize=max(1, len(work) // (4 * jobs))):
                    results.append(result)
                    bar.update()
        else:
            for args in work:
                results.append(_judge_args(args))
                bar.update()
    return MetricsResult(tuple(unmatched + results))

