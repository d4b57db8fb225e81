"""Open any bag the metrics read, as one stream of messages with a decoder per connection.

A bag is a rosbag2 directory (sqlite3 or MCAP, any metadata version, file- or
message-compressed; rosbags reads it), a lone storage file (``.db3``, ``.mcap``, or one of them
compressed whole, ``.zstd``), the storage files of a split bag that lost its
``metadata.yaml`` (read in index order as one bag), or a ROS 1 ``.bag``. Messages are decoded
with the types the bag embeds; where it embeds none, or an incomplete set, with ROS 2 Jazzy's
(ROS 1 Noetic's for a ROS 1 bag), and a type known to neither is named in the error.

SQLite opens a ``.db3`` through a ``file:`` URI, where ``#``, ``?`` and ``%xx`` in a folder's
name would end or change the path: every path that becomes such a URI goes through
``uri_path`` (the writer's too).
"""

from __future__ import annotations

import contextlib
import os
import shutil
import struct
import sys
import tempfile
from collections.abc import Callable, Iterator
from functools import lru_cache
from pathlib import Path
from typing import Any
from urllib.parse import quote_from_bytes

from apsw import Error as SqliteError
from rosbags.interfaces import Connection, MessageDefinitionFormat
from rosbags.rosbag1 import Reader as Reader1
from rosbags.rosbag1 import ReaderError as ReaderError1
from rosbags.rosbag2 import Reader, ReaderError
from rosbags.rosbag2.reader import DirectoryReader
from rosbags.rosbag2.storage_sqlite3 import Sqlite3Reader
from rosbags.serde import SerdeError
from rosbags.typesys import (
    Stores,
    TypesysError,
    get_types_from_idl,
    get_types_from_msg,
    get_typestore,
)
from rosbags.typesys.base import Nodetype
from rosbags.typesys.store import Typestore

from ..contract import typestore
from ..errors import BagError
from .inputs import COMPRESSED_SUFFIX, ROS1_SUFFIX, is_bag_file, special, split_parts

if sys.version_info >= (3, 14):
    from compression import zstd
else:
    from backports import zstd

#: What a damaged storage file or message raises while rosbags reads it: sqlite's errors
#: (rosbags reads .db3 through apsw), short reads and absurd lengths in MCAP records, CDR
#: that does not match its type, and a compressed file that is not zstd.
DAMAGE = (
    SqliteError, SerdeError, TypesysError, struct.error, EOFError, OverflowError, MemoryError,
    AssertionError, ValueError, IndexError, KeyError, zstd.ZstdError,
)


@contextlib.contextmanager
def bag_errors(path: Path) -> Iterator[None]:
    """rosbags' and the storage libraries' errors while reading ``path`` as one ``BagError``
    naming the bag."""
    try:
        yield
    except (ReaderError, ReaderError1, OSError) as err:
        msg = f"{str(path)!r}: cannot open bag: {_one_line(path, str(err))}"
        raise BagError(msg) from err
    except DAMAGE as err:
        msg = f"{str(path)!r}: damaged bag or message: {type(err).__name__}: {err}"
        raise BagError(msg) from err


#: rosbags' words for a ``metadata.yaml`` that is no YAML, or no rosbag2 metadata.
_METADATA_ERRORS = {"Could not load YAML from ": "not valid YAML",
                    "Invalid bag metadata: ": "not rosbag2 metadata"}


def _one_line(bag: Path, text: str) -> str:
    """rosbags' message on one line: a ``metadata.yaml`` that is no YAML (the parser's error,
    several lines) or no rosbag2 metadata is named, with what is wrong."""
    meta = bag / "metadata.yaml"
    for prefix, what in _METADATA_ERRORS.items():
        if text.startswith(prefix):
            text = text.removeprefix(prefix).removeprefix(f"{meta}: ").rstrip(".")
            text = f"{str(meta)!r}: {what}: {text}"
            break
    lines = (line.strip() for line in text.splitlines())
    return "; ".join(line for line in lines if line).replace('in "<unicode string>", ', "at ")


def uri_path(path: Path) -> str:
    """``path`` as the path of a ``file:`` URI: every byte but letters, digits and ``/_.-~``
    percent-quoted, so that ``#``, ``?``, ``%``, spaces and unicode stay part of the name."""
    return quote_from_bytes(os.fsencode(path), safe="/")


class _UriPath(type(Path())):  # type: ignore[misc]
    """A path that formats as ``uri_path`` of itself: rosbags' sqlite3 reader opens
    ``f"file:{path}?immutable=1"`` from the path unquoted."""

    def __format__(self, spec: str) -> str:
        return uri_path(self)


class _Sqlite3Reader(Sqlite3Reader):
    """rosbags' sqlite3 reader, given a path that it puts into its URI quoted."""

    def __init__(self, path: Path) -> None:
        super().__init__(_UriPath(path))


class _DirectoryReader(DirectoryReader):
    STORAGE_PLUGINS = {**DirectoryReader.STORAGE_PLUGINS, "sqlite3": _Sqlite3Reader}


class _Reader(Reader):
    """rosbags' reader whose ``.db3`` files (alone or in a directory) open whatever their
    folders are named."""

    STORAGE_PLUGINS = {**Reader.STORAGE_PLUGINS, "dir": _DirectoryReader, ".db3": _Sqlite3Reader}


def _default_store(ros1: bool) -> Typestore:
    return _noetic() if ros1 else typestore()


@lru_cache(maxsize=1)
def _noetic() -> Typestore:
    return get_typestore(Stores.ROS1_NOETIC)


def _names(desc: tuple[Any, Any]) -> Iterator[str]:
    """Message types a field description refers to."""
    kind, rest = desc
    if kind == Nodetype.NAME:
        yield rest
    elif kind in (Nodetype.ARRAY, Nodetype.SEQUENCE):
        yield from _names(rest[0])


def _missing(store: Typestore, msgtype: str) -> list[str]:
    """Types ``msgtype`` needs (itself included) that ``store`` lacks, sorted."""
    seen, todo, missing = set(), [msgtype], set()
    while todo:
        name = todo.pop()
        if name in seen:
            continue
        seen.add(name)
        if name not in store.fielddefs:
            missing.add(name)
            continue
        for _, desc in store.fielddefs[name][1]:
            todo.extend(_names(desc))
    return sorted(missing)


def _embedded(msgdef_format: MessageDefinitionFormat, msgdef: str, msgtype: str) -> dict[str, Any]:
    """Types a connection's embedded definition declares (none when it is empty)."""
    if msgdef_format == MessageDefinitionFormat.NONE or not msgdef.strip():
        return {}
    if msgdef_format == MessageDefinitionFormat.MSG:
        return dict(get_types_from_msg(msgdef, msgtype))
    sep = "=" * 80 + "\n"
    parts = msgdef.split(sep)[1:] if msgdef.startswith(f"{sep}IDL: ") else []
    types: dict[str, Any] = {}
    for idl in [part.split("\n", 1)[1] for part in parts] or [msgdef]:
        types.update(get_types_from_idl(idl))
    return types


@lru_cache(maxsize=64)
def typestore_for(
    msgtype: str, msgdef_format: MessageDefinitionFormat, msgdef: str, ros1: bool = False
) -> tuple[Typestore, tuple[str, ...]]:
    """The typestore that decodes ``msgtype`` as the bag defines it, and the types it needs
    that neither the bag nor the default store (Jazzy; Noetic for ROS 1) define.

    The default store (whose decoders are generated once per process) unless the bag embeds
    a definition that differs from it; the embedded definition's gaps are filled from the
    default store. Cached on the definition text, so opening many bags does not rebuild types
    and decoders for each (rosbags' ``AnyReader`` does).
    """
    default = _default_store(ros1)
    types = _embedded(msgdef_format, msgdef, msgtype)
    if not types:
        return default, tuple(_missing(default, msgtype))
    own = get_typestore(Stores.EMPTY)
    own.register(types)
    known = default.fielddefs
    while fill := {t: known[t] for t in _missing(own, msgtype) if t in known}:
        own.register(fill)
    missing = tuple(_missing(own, msgtype))
    if missing:
        return own, missing
    same = msgtype in default.fielddefs and own.hash_rihs01(msgtype) == default.hash_rihs01(msgtype)
    return (default if same else own), ()


class OpenBag:
    """A bag's storage files, open: their connections, messages in file order, decoders.

    Use as a context manager inside ``bag_errors``; a ``.zstd`` file is decompressed into a
    temporary directory that is removed on exit (the bag itself is never written to).
    """

    def __init__(self, path: Path) -> None:
        self.path = path
        self.ros1 = path.is_file() and path.name.endswith(ROS1_SUFFIX)
        self._stack = contextlib.ExitStack()
        self._readers: list[Reader | Reader1] = []

    def __enter__(self) -> OpenBag:
        try:
            for part in self._parts():
                reader = Reader1(part) if self.ros1 else _Reader(self._plain(part))
                self._readers.append(self._stack.enter_context(reader))
        except BaseException:
            self._stack.close()
            raise
        return self

    def __exit__(self, *exc: object) -> None:
        self._stack.close()

    def _parts(self) -> list[Path]:
        """Storage files (or the rosbag2 directory) that make up the bag; ``BagError`` for a
        storage file that is no regular file (opening a FIFO waits for a writer forever)."""
        for path in (self.path, *(self.path.iterdir() if self.path.is_dir() else ())):
            kind = special(path)
            if kind is not None and (path == self.path or is_bag_file(path)):
                msg = f"{str(path)!r} is {kind}, not a regular file or directory; not read"
                raise BagError(msg)
        if not self.path.is_dir():
            if not is_bag_file(self.path):
                msg = f"{str(self.path)!r}: not a bag file (a rosbag2 storage file or a ROS 1 .bag)"
                raise BagError(msg)
            return [self.path]
        if (self.path / "metadata.yaml").is_file():
            return [self.path]
        parts = split_parts(self.path)
        if not parts:
            parts = sorted(p for p in self.path.iterdir() if p.is_file() and is_bag_file(p))
            if len(parts) != 1:
                found = (f"{len(parts)} storage files that are not one split bag" if parts
                         else "no storage file")
                msg = f"{str(self.path)!r}: cannot open bag: no metadata.yaml and {found}"
                raise BagError(msg)
        self.ros1 = parts[0].name.endswith(ROS1_SUFFIX)
        return parts

    def _plain(self, part: Path) -> Path:
        """``part`` itself, or its decompressed copy in a temporary directory for ``.zstd``."""
        if not part.name.endswith(COMPRESSED_SUFFIX):
            return part
        tmp = Path(self._stack.enter_context(tempfile.TemporaryDirectory(prefix="pic4rl-")))
        plain = tmp / part.name.removesuffix(COMPRESSED_SUFFIX)
        with part.open("rb") as raw, zstd.open(raw, "rb") as src, plain.open("wb") as dst:
            shutil.copyfileobj(src, dst)
        return plain

    @property
    def connections(self) -> list[Connection]:
        return [c for reader in self._readers for c in reader.connections]

    @property
    def custom(self) -> dict[str, str]:
        """The metadata's ``custom_data`` (empty for a lone file or a ROS 1 bag)."""
        out: dict[str, str] = {}
        for reader in self._readers:
            if isinstance(reader, Reader):
                out.update(reader.storage.metadata.custom or {})
        return out

    def streams(
        self, connections: list[Connection]
    ) -> Iterator[tuple[list[Connection], Iterator[tuple[Connection, int, bytes]]]]:
        """Per file, its connections among ``connections`` and their messages (connection,
        receive time in ns, raw data); connection ids are unique within one file only."""
        for reader in self._readers:
            own = [c for c in reader.connections if any(c is w for w in connections)]
            if own:
                yield own, reader.messages(connections=own)

    def publishers(self, conn: Connection) -> int:
        """How many publishers the bag recorded on ``conn``'s topic: its offered QoS profiles
        (rosbag2: one per publisher the recorder saw), and the connections of its storage
        file on that topic (ROS 1: one per publishing node)."""
        reader = next(r for r in self._readers if any(c is conn for c in r.connections))
        same = [c for c in reader.connections if c.topic == conn.topic]
        nodes = {getattr(c.ext, "callerid", None) or c.id for c in same}
        profiles = getattr(conn.ext, "offered_qos_profiles", None)
        return max(len(nodes), len(profiles) if isinstance(profiles, list) else 0)

    def decoder(self, conn: Connection) -> Callable[[bytes, str], Any]:
        """The function decoding ``conn``'s raw messages (called with the data and the
        message type); ``BagError`` naming the type that no definition covers."""
        msgdef = conn.msgdef
        store, missing = typestore_for(conn.msgtype, msgdef.format, msgdef.data, self.ros1)
        if missing:
            default = "ROS 1 Noetic" if self.ros1 else "ROS 2 Jazzy"
            msg = (
                f"{str(self.path)!r}: topic {conn.topic!r}: message type(s) {list(missing)} are "
                f"neither defined in the bag nor known to {default}'s types"
            )
            raise BagError(msg)
        return store.deserialize_ros1 if self.ros1 else store.deserialize_cdr
