"""Write each episode to its own rosbag2, as the bag contract says.

Bags are the contract between running a robot and judging it, so the recorder writes through
``pic4rl_metrics.bags.bagwriter``, the metrics' one bag writer: the messages as on the wire, the
typed ``EpisodeFacts`` on ``/episode/facts`` and in ``custom_data``, the outcome on
``/episode/outcome``, with the contract's storages and typestore. What the recorder adds is
the run: the offered QoS of the sim's topics, the episode's run and name, the layout
``<bags_dir>/<run>/<episode>/`` with the run's config beside the episodes. Nothing already on
disk is ever overwritten: a run recorded twice into one directory appends episodes and keeps
every config it was run with.
"""

from __future__ import annotations

import logging
import re
from collections.abc import Callable, Iterator, Mapping
from contextlib import contextmanager
from dataclasses import replace
from pathlib import Path
from types import TracebackType
from typing import Any

import yaml
from rosbags.interfaces import Qos

from pic4rl_base import atomic
from pic4rl_base.errors import OutputError
from pic4rl_metrics.bags.bagwriter import DEFAULT_QOS, LATCHED_QOS, BagWriter, qos_record
from pic4rl_metrics.contract import STORAGES, CollisionRule, EpisodeFacts, Outcome, plain
from pic4rl_sim.interfaces import QosKind, find

from .errors import RecorderError
from .transports.transport import OfferedQos, RawMessage

log = logging.getLogger(__name__)

CONFIG_NAME = "config"
EPISODE_PREFIX = "episode_"

#: How a transport tells how a topic was offered (``Transport.offered_qos``).
QosSource = Callable[[str], OfferedQos | None]


def offered_qos(topic: str, offered: OfferedQos | None = None) -> Qos:
    """The bag's QoS record of ``topic``: as ``offered`` (what its publisher really offered),
    else transient-local for the sim's latched topics (``pic4rl_sim.interfaces``: re-latched on
    replay), else reliable."""
    if offered is None:
        sim_topic = find(topic)
        latched = sim_topic is not None and sim_topic.qos is QosKind.LATCHED
        return LATCHED_QOS if latched else DEFAULT_QOS
    return qos_record(offered.depth, reliable=offered.reliable,
                      transient_local=offered.transient_local)


@contextmanager
def _as_recorder_error() -> Iterator[None]:
    """The bag writer's ``OutputError`` as the bridge's ``RecorderError`` (same message)."""
    try:
        yield
    except OutputError as err:
        raise RecorderError(str(err)) from err


class EpisodeBag:
    """One episode's bag being written; ``write`` is usable as the transport's tap.

    Durability: with ``sqlite3`` the writes are committed every ``flush_interval_s`` (s of wall
    time; 0: every write) and right after ``facts`` (``BagWriter``), so a process killed at any
    time (SIGKILL included) leaves a ``.db3`` holding everything up to the last commit. A kill
    in the middle of a commit (milliseconds) leaves a hot ``-journal`` that rosbags' read-only
    reader ignores: opening the ``.db3`` once with ``sqlite3`` rolls it back. With ``mcap``
    there is no such guarantee: rosbags writes the chunk index and footer only on close, so a
    killed recorder leaves an MCAP file that may not be readable.
    """

    def __init__(self, path: Path, *, storage: str = "sqlite3", flush_interval_s: float = 1.0,
                 qos: QosSource | None = None) -> None:
        self.path = Path(path)
        self.storage = storage
        self.flush_interval_s = float(flush_interval_s)
        self._facts = EpisodeFacts(run=self.path.parent.name, episode=self.path.name)

        def bag_qos(topic: str) -> Qos:
            return offered_qos(topic, qos(topic) if qos is not None else None)

        with _as_recorder_error():
            self._bag = BagWriter(self.path, storage=storage, qos=bag_qos,
                                  flush_interval_s=self.flush_interval_s)

    @property
    def is_open(self) -> bool:
        return self._bag.is_open

    @property
    def counts(self) -> dict[str, int]:
        """Messages written per topic (facts and outcome included)."""
        return self._bag.counts

    def write(self, msg: RawMessage) -> None:
        """Write one message (CDR) at its ``stamp_ns`` (bag time, ns)."""
        with _as_recorder_error():
            self._bag.write(msg.topic, msg.msgtype, msg.data, msg.stamp_ns)

    def facts(self, facts: EpisodeFacts, stamp_ns: int) -> None:
        """Publish ``facts`` (``run`` and ``episode`` default to the bag's directories) on
        ``/episode/facts`` at ``stamp_ns`` and keep them for ``custom_data``. Committed at
        once, so a killed recorder's bag still has them."""
        self._facts = replace(
            facts, run=self._facts.run if facts.run is None else facts.run,
            episode=self._facts.episode if facts.episode is None else facts.episode)
        with _as_recorder_error():
            self._bag.write_facts(self._facts, stamp_ns)

    def close(self, outcome: Outcome | str, stamp_ns: int, reason: str | None = None,
              rule: CollisionRule | str | None = None) -> Path:
        """End the episode: publish the ``outcome`` (one of the contract's
        ``WRITTEN_OUTCOMES``) at ``stamp_ns`` (ns), store every fact, the outcome, the
        ``reason`` it was cut short (if any) and the ``rule`` that made it a collision (if
        any) in ``custom_data``, write ``metadata.yaml``; return the bag directory."""
        with _as_recorder_error():
            word = self._bag.write_outcome(outcome, stamp_ns)
            self._bag.close(replace(self._facts, outcome=word, end_reason=reason,
                                    collision_rule=None if rule is None else CollisionRule(rule)))
        log.info("episode bag %s: %s, %d messages", self.path, word.value,
                 sum(self.counts.values()))
        return self.path

    def abort(self) -> Path:
        """Close without an outcome (the episode was cut short): everything written is kept
        and the bag stays readable. Does nothing when already closed."""
        if self._bag.is_open:
            with _as_recorder_error():
                self._bag.close(self._facts)
            log.warning("episode bag %s closed without an outcome", self.path)
        return self.path

    def __enter__(self) -> EpisodeBag:
        return self

    def __exit__(self, exc_type: type[BaseException] | None, exc: BaseException | None,
                 tb: TracebackType | None) -> None:
        self.abort()


class RunRecorder:
    """The episode bags of one run: ``<bags_dir>/<run>/episode_NNNN/`` and the run's config.

    ``config`` (any YAML-able mapping) is written beside the episodes as ``config.yaml``;
    when that file exists with other content (another run into the same directory), as
    ``config-2.yaml``, ``config-3.yaml``, ... instead, never over a file already there.
    """

    def __init__(self, bags_dir: Path, run: str, *, storage: str = "sqlite3",
                 flush_interval_s: float = 1.0, config: Mapping[str, Any] | None = None) -> None:
        if storage not in STORAGES:
            raise RecorderError(f"{run}: storage {storage!r} is unknown; expected "
                                f"{' or '.join(STORAGES)}")
        self.run_dir = Path(bags_dir) / _component(run, "run")
        self.storage = storage
        self.flush_interval_s = flush_interval_s
        self._episodes: list[Path] = []
        try:
            self.run_dir.mkdir(parents=True, exist_ok=True)
            self.config_path = None if config is None else self._write_config(config)
        except OSError as err:
            raise RecorderError(f"{self.run_dir}: cannot write the run directory: {err}") from err
        except yaml.YAMLError as err:
            raise RecorderError(f"{self.run_dir}: config is not YAML-able: {err}") from err

    @property
    def episodes(self) -> list[Path]:
        """The bag directories this recorder began, in order."""
        return list(self._episodes)

    def begin(self, episode: str | None = None, *, qos: QosSource | None = None) -> EpisodeBag:
        """Open the next episode's bag: ``episode`` if given (``RecorderError`` if it exists),
        else ``episode_NNNN`` numbered after the highest one on disk; ``qos`` tells how each
        topic was offered (the transport's)."""
        if episode is None:
            episode = f"{EPISODE_PREFIX}{self._next_index():04d}"
        path = self.run_dir / _component(episode, "episode")
        if path.exists():
            raise RecorderError(f"{path}: the episode bag exists already; not overwriting it")
        bag = EpisodeBag(path, storage=self.storage, flush_interval_s=self.flush_interval_s,
                         qos=qos)
        self._episodes.append(path)
        return bag

    def _next_index(self) -> int:
        pattern = re.compile(rf"{EPISODE_PREFIX}(\d+)")
        taken = [int(m.group(1)) for p in self.run_dir.iterdir()
                 if (m := pattern.fullmatch(p.name))]
        return max(taken, default=-1) + 1

    def _write_config(self, config: Mapping[str, Any]) -> Path:
        """Write ``config`` to the first of config.yaml, config-2.yaml, ... that is free or
        already holds the same text; return that file."""
        text = yaml.safe_dump(plain(config), sort_keys=False)
        n = 1
        while True:
            path = atomic.numbered(self.run_dir / f"{CONFIG_NAME}.yaml", n, keep_suffix=True)
            try:
                with path.open("x") as f:
                    f.write(text)
                log.info("run config written to %s", path)
                return path
            except FileExistsError:
                if path.read_text() == text:
                    return path
            n += 1


def _component(name: str, what: str) -> str:
    """``name`` if it is one plain path component, else ``RecorderError``."""
    if not name or name in (".", "..") or "/" in name or "\\" in name:
        raise RecorderError(f"{what} name {name!r} must be one directory name (no '/')")
    return name
