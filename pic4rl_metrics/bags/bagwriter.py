"""The one rosbag2 writer: what pic4rl's recorder and the synthetic test bags write through.

A bag is written as the bag contract (``contract``) says: the contract's storages and
typestore, one connection per topic and type with its offered QoS, the episode facts on
``/episode/facts`` and in ``custom_data``, the outcome on ``/episode/outcome``. After rosbags'
writer closed it, ``finish_files`` fills in what rosbags leaves out (the ROS distribution, the
MCAP CRCs), so every bag pic4rl writes is finished the same way.

rosbags' sqlite3 writer keeps the whole bag in one open transaction until ``close()``, so a
process killed mid-bag would lose it all; with ``flush_interval_s`` the writer commits that
often instead, and a killed writer leaves a ``.db3`` (without ``metadata.yaml``) that the
metrics read.
"""

from __future__ import annotations

import sqlite3
import struct
import time
import zlib
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

from rosbags.interfaces import (Connection, Qos, QosDurability, QosHistory, QosLiveliness,
                                QosReliability, QosTime)
from rosbags.rosbag2 import Writer, WriterError
from rosbags.rosbag2.enums import CompressionMode, StoragePlugin
from rosbags.rosbag2.storage_sqlite3 import Sqlite3Writer

from pic4rl_base.errors import OutputError

from ..contract import (FACTS_TOPIC, OUTCOME_TOPIC, ROS_DISTRO, STORAGES, WRITTEN_OUTCOMES,
                        EpisodeFacts, Outcome, encode_custom_data, encode_facts_json, outcome_event,
                        plain, typestore)
from .bagfile import uri_path

STRING = "std_msgs/msg/String"

_UNSET = QosTime(0, 0)  # rmw's "unspecified": the default (infinite) deadline, lifespan, lease
#: Offered QoS of latched topics (goal, markers), so ``ros2 bag play`` re-latches them.
LATCHED_QOS = Qos(QosHistory.KEEP_LAST, 1, QosReliability.RELIABLE, QosDurability.TRANSIENT_LOCAL,
                  _UNSET, _UNSET, QosLiveliness.AUTOMATIC, _UNSET, False)
#: Offered QoS of every other topic (when a recorder is not told better).
DEFAULT_QOS = Qos(QosHistory.KEEP_LAST, 10, QosReliability.RELIABLE, QosDurability.VOLATILE,
                  _UNSET, _UNSET, QosLiveliness.AUTOMATIC, _UNSET, False)


def qos_record(depth: int, *, reliable: bool, transient_local: bool) -> Qos:
    """The bag's QoS record of a publisher that offered this (depth 0: history unknown)."""
    return Qos(QosHistory.KEEP_LAST if depth > 0 else QosHistory.UNKNOWN, depth,
               QosReliability.RELIABLE if reliable else QosReliability.BEST_EFFORT,
               QosDurability.TRANSIENT_LOCAL if transient_local else QosDurability.VOLATILE,
               _UNSET, _UNSET, QosLiveliness.AUTOMATIC, _UNSET, False)


class _Sqlite3Storage(Sqlite3Writer):
    """rosbags' sqlite3 storage whose empty tables are created without an fsync (about
    0.13 s of waiting per bag on a virtual disk, for tables that hold nothing to lose); the
    connection keeps sqlite's default syncing for what is written after."""

    def __init__(self, path: Path, compression: CompressionMode) -> None:
        if compression == CompressionMode.STORAGE:
            super().__init__(path, compression)  # rosbags' own error
        self.path = path / f"{path.name}.db3"
        self.conn = sqlite3.connect(f"file:{uri_path(self.path)}", uri=True)
        level = self.conn.execute("PRAGMA synchronous").fetchone()[0]
        self.conn.execute("PRAGMA synchronous=OFF")
        self.conn.executescript(self.SQLITE_SCHEMA)
        self.conn.execute(f"PRAGMA synchronous={int(level)}")
        self.cursor = self.conn.cursor()


class _Writer(Writer):
    """rosbags' writer with ``_Sqlite3Storage`` for sqlite3."""

    STORAGE_PLUGINS = {**Writer.STORAGE_PLUGINS, StoragePlugin.SQLITE3: _Sqlite3Storage}


class BagWriter:
    """One bag being written at ``path`` (a new directory) with ``storage`` (a key of
    ``STORAGES``); every failure is an ``OutputError`` naming the bag.

    ``qos(topic)`` gives the offered QoS recorded for a topic's connection (none recorded when
    not given or ``None``, as rosbags writes by default). ``flush_interval_s`` (sqlite3 only; s of wall time, 0: every write):
    commit that often, with ``PRAGMA synchronous=OFF``, so a process killed at any time
    (SIGKILL included) leaves a ``.db3`` holding everything up to the last commit; only an OS
    crash or power loss can lose more. ``None``: rosbags' one transaction, committed on close.
    """

    def __init__(self, path: Path, *, storage: str = "sqlite3",
                 flush_interval_s: float | None = None,
                 qos: Callable[[str], Qos | None] | None = None) -> None:
        self.path = Path(path)
        if storage not in STORAGES:
            raise OutputError(f"{self.path}: storage {storage!r} is unknown; expected "
                              f"{' or '.join(STORAGES)}")
        self.flush_interval_s = flush_interval_s
        self._qos = qos
        #: Messages written per topic (facts and outcome included).
        self.counts: dict[str, int] = {}
        self._connections: dict[tuple[str, str], Connection] = {}
        self._writer: Writer | None = _Writer(self.path, version=9,
                                              storage_plugin=STORAGES[storage])
        try:
            self._writer.open()
        except (WriterError, OSError) as err:
            self._writer = None
            raise OutputError(f"{self.path}: cannot create the bag: {err}") from err
        self._db = self._durable_db() if storage == "sqlite3" and flush_interval_s is not None \
            else None
        self._last_commit = time.monotonic()

    def _durable_db(self) -> sqlite3.Connection:
        """rosbags' sqlite3 connection, set to commit without syncing or spilling."""
        assert self._writer is not None
        db = getattr(self._writer.storage, "conn", None)
        if not isinstance(db, sqlite3.Connection):
            self._writer.abort()
            self._writer = None
            raise OutputError(f"{self.path}: rosbags' sqlite3 writer exposes no connection; "
                              "cannot commit periodically")
        db.execute("PRAGMA synchronous=OFF")
        # Never write uncommitted pages into the .db3: it stays consistent between commits.
        db.execute("PRAGMA cache_spill=OFF")
        return db

    @property
    def is_open(self) -> bool:
        return self._writer is not None

    def write(self, topic: str, msgtype: str, data: bytes, stamp_ns: int) -> None:
        """Write one message (CDR) at ``stamp_ns`` (bag time, ns); commit when one is due."""
        writer = self._open_writer()
        stamp = int(stamp_ns)
        if stamp < 0:
            raise OutputError(f"{self.path}: {topic}: bag time {stamp} ns is negative")
        try:
            conn = self._connections.get((topic, msgtype))
            if conn is None:
                conn = self._connect(writer, topic, msgtype)
            writer.write(conn, stamp, data)
        except (WriterError, sqlite3.Error, OSError) as err:
            raise OutputError(f"{self.path}: cannot write {topic!r}: {err}") from err
        self.counts[topic] = self.counts.get(topic, 0) + 1
        if self._db is not None and \
                time.monotonic() - self._last_commit >= self.flush_interval_s:  # type: ignore[operator]
            self.commit()

    def _connect(self, writer: Writer, topic: str, msgtype: str) -> Connection:
        if msgtype not in typestore().fielddefs:
            raise OutputError(f"{self.path}: topic {topic!r} has type {msgtype!r}, which the "
                              "bag contract's typestore (ROS 2 Jazzy) lacks")
        qos = self._qos(topic) if self._qos is not None else None
        conn = writer.add_connection(topic, msgtype, typestore=typestore(),
                                     offered_qos_profiles=[] if qos is None else [qos])
        self._connections[topic, msgtype] = conn
        return conn

    def write_message(self, topic: str, message: Any, stamp_ns: int) -> None:
        """Write a typestore message object (``typestore().types[...]``) at ``stamp_ns``."""
        msgtype = message.__msgtype__
        self.write(topic, msgtype, bytes(typestore().serialize_cdr(message, msgtype)), stamp_ns)

    def write_facts(self, facts: EpisodeFacts | Mapping[str, Any], stamp_ns: int) -> None:
        """Publish ``facts`` (typed, or plain values by key) on ``/episode/facts``; committed
        at once when the writer commits periodically, so a killed writer's bag has them."""
        values = facts.values() if isinstance(facts, EpisodeFacts) else facts
        self.write(FACTS_TOPIC, STRING, string_cdr(encode_facts_json(values)), stamp_ns)
        if self._db is not None:
            self.commit()

    def write_outcome(self, outcome: Outcome | str, stamp_ns: int) -> Outcome:
        """Publish ``outcome`` (one of the contract's ``WRITTEN_OUTCOMES``) and its time (ns)
        on ``/episode/outcome``; return it."""
        word = plain(outcome)
        if word not in WRITTEN_OUTCOMES:
            raise OutputError(f"{self.path}: outcome {outcome!r} is not one of "
                              f"{', '.join(WRITTEN_OUTCOMES)}")
        self.write(OUTCOME_TOPIC, STRING, string_cdr(outcome_event(word, stamp_ns)), stamp_ns)
        return Outcome(word)

    def commit(self) -> None:
        """Commit what was written (sqlite3 with ``flush_interval_s`` only)."""
        if self._db is None:
            return
        try:
            self._db.commit()
        except sqlite3.Error as err:
            raise OutputError(f"{self.path}: cannot commit: {err}") from err
        self._last_commit = time.monotonic()

    def close(self, facts: EpisodeFacts | Mapping[str, Any]) -> Path:
        """Store ``facts`` (typed, or plain values by key) as ``custom_data``, write
        ``metadata.yaml`` and finish the files; return the bag directory."""
        writer = self._open_writer()
        values = facts.values() if isinstance(facts, EpisodeFacts) else facts
        for key, value in encode_custom_data(values).items():
            writer.set_custom_data(key, value)
        self._writer = self._db = None
        try:
            writer.close()
            finish_files(self.path)
        except (WriterError, sqlite3.Error, OSError) as err:
            raise OutputError(f"{self.path}: cannot close the bag: {err}") from err
        return self.path

    def _open_writer(self) -> Writer:
        if self._writer is None:
            raise OutputError(f"{self.path}: the bag is closed")
        return self._writer


def string_cdr(text: str) -> bytes:
    """A ``std_msgs/msg/String`` holding ``text``, as CDR."""
    ts = typestore()
    return bytes(ts.serialize_cdr(ts.types[STRING](data=text), STRING))


def finish_files(bag: Path) -> None:
    """What rosbags' writer leaves out, filled in after it closed ``bag``: ``ros_distro``
    (it writes ``rosbags``) in ``metadata.yaml`` and the storage's copy, and in MCAP files
    each chunk's CRC-32 and the data section's, so that a reader detects a damaged chunk."""
    meta = bag / "metadata.yaml"
    text = meta.read_text()
    meta.write_text(text.replace("ros_distro: rosbags", f"ros_distro: {ROS_DISTRO}", 1))
    for db in bag.glob("*.db3"):
        with sqlite3.connect(db) as conn:
            conn.execute("UPDATE metadata SET metadata = replace(metadata, ?, ?)",
                         ("ros_distro: rosbags", f"ros_distro: {ROS_DISTRO}"))
        conn.close()
    for mcap in bag.glob("*.mcap"):
        data = bytearray(mcap.read_bytes())
        # Same length, so no offset in the file moves (YAML ignores the trailing spaces).
        old = b"ros_distro: rosbags"
        data[:] = data.replace(old, f"ros_distro: {ROS_DISTRO}".encode().ljust(len(old)), 1)
        _mcap_crcs(data)
        mcap.write_bytes(bytes(data))


def _mcap_crcs(data: bytearray) -> None:
    """Set the CRC-32 of every uncompressed chunk's records and of the data section, in place
    (MCAP: a CRC of 0 means "not computed", which rosbags writes)."""
    pos = 8  # past the magic
    while pos + 9 <= len(data):
        op = data[pos]
        (length,) = struct.unpack_from("<Q", data, pos + 1)
        body = pos + 9
        if op == 0x06:  # chunk: start, end, uncompressed size, CRC, compression, records
            (compression_len,) = struct.unpack_from("<I", data, body + 28)
            compression = bytes(data[body + 32:body + 32 + compression_len])
            start = body + 40 + compression_len
            (records_len,) = struct.unpack_from("<Q", data, start - 8)
            if compression == b"":
                struct.pack_into("<I", data, body + 24, zlib.crc32(data[start:start + records_len]))
        elif op == 0x0F:  # data end: the CRC of everything before it
            struct.pack_into("<I", data, body, zlib.crc32(data[:pos]))
            return
        pos = body + length
