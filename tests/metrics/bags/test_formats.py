"""Bag formats: every form one episode can take gives the row of the plain rosbag2 bag.

ROS 1 ``.bag`` files (written with rosbags' ROS 1 writer and Noetic's types), rosbag2 bags
compressed per file or per message (and a compressed storage file given on its own), a split
bag whose ``metadata.yaml`` was lost, and ``metadata.yaml`` of every version rosbag2 wrote.
"""

from __future__ import annotations

import dataclasses
import json
import math
import shutil
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml
from metrics_helpers import EXACT, F32, LINE, transform, write_tf_bag
from metrics_helpers import row as _row
from metrics_helpers import same as _same
from rosbags.rosbag1 import Writer as Writer1
from rosbags.rosbag2 import CompressionFormat, CompressionMode, Reader, Writer
from rosbags.typesys import Stores, get_types_from_msg, get_typestore

from pic4rl_metrics import BagError, compute, read_episode
from pic4rl_metrics.cli.commands import main
from pic4rl_metrics.contract import STORAGES, typestore
from pic4rl_metrics.synthetic.synthetic import DEFAULT_T0_NS, Obstacles, write_episode_bag
from pic4rl_metrics.bags.topics import TopicMap

FACTS = {"agent": "td3", "run": "r1", "episode": "3", "footprint": {"radius_m": 0.2}}
SCENE = Obstacles(circles=((2.5, 0.8, 0.3),), segments=((-1.0, -1.0, 8.0, -1.0),))


@pytest.fixture(scope="module")
def plain(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The reference: a rosbag2 sqlite3 bag of a 5 m straight run past a cylinder to its goal."""
    root = tmp_path_factory.mktemp("formats")
    return write_episode_bag(root / "plain", LINE, obstacles=SCENE, goal=(5.0, 0.0),
                             facts=FACTS, outcome="goal")


@pytest.fixture(scope="module")
def reference(plain: Path) -> dict[str, object]:
    row = _row(plain)
    assert row["outcome"] == "goal" and row["path_length_m"] == pytest.approx(5.0, abs=EXACT)
    assert row["obstacle_dist_min_m"] == pytest.approx(0.5, abs=F32)  # 0.8 - 0.3 at x = 2.5
    return row


def _assert_same_row(a: dict[str, object], b: dict[str, object]) -> None:
    differ = {k: (a[k], b[k]) for k in a if k != "bag" and not _same(a[k], b[k])}
    assert differ == {}


def _messages(src: Path) -> tuple[list[tuple[str, str, int, bytes]], dict[str, str]]:
    """(topic, type, receive ns, CDR) of every message of a rosbag2 bag, and its custom_data."""
    with Reader(src) as reader:
        custom = dict(reader.storage.metadata.custom or {})
        msgs = [(c.topic, c.msgtype, t, bytes(raw)) for c, t, raw in reader.messages()]
    return msgs, custom


def _write2(dst: Path, msgs: list[tuple[str, str, int, bytes]], custom: dict[str, str], *,
            storage: str = "sqlite3", compression: CompressionMode | None = None) -> Path:
    writer = Writer(dst, version=9, storage_plugin=STORAGES[storage])
    if compression is not None:
        writer.set_compression(compression, CompressionFormat.ZSTD)
    with writer:
        conns: dict[str, Any] = {}
        for topic, msgtype, t_ns, raw in msgs:
            if topic not in conns:
                conns[topic] = writer.add_connection(topic, msgtype, typestore=typestore())
            writer.write(conns[topic], t_ns, raw)
        for k, v in custom.items():
            writer.set_custom_data(k, v)
    return dst


# --------------------------------------------------------------------------- ROS 1


def _noetic() -> Any:
    """Noetic's types, plus ``tf2_msgs/msg/TFMessage`` (which rosbags' Noetic store lacks)."""
    ts = get_typestore(Stores.ROS1_NOETIC)
    ts.register(get_types_from_msg("geometry_msgs/TransformStamped[] transforms",
                                   "tf2_msgs/msg/TFMessage"))
    return ts


def _to_ros1(value: Any, ts: Any) -> Any:
    """A ROS 2 message as its ROS 1 counterpart (field by field; ``Header.seq`` is 0)."""
    if isinstance(value, list):
        return [_to_ros1(v, ts) for v in value]
    if not hasattr(value, "__msgtype__"):
        return value
    cls = ts.types[value.__msgtype__]
    return cls(**{f.name: _to_ros1(getattr(value, f.name), ts) if hasattr(value, f.name) else 0
                  for f in dataclasses.fields(cls) if not f.name.startswith("__")})


def _to_bag(src: Path, dst: Path, *, empty_definition: str | None = None,
            chunks: Writer1.CompressionFormat | None = None) -> Path:
    """Copy rosbag2 ``src`` into the ROS 1 bag ``dst``; ``empty_definition``: a topic whose
    connection carries no message definition (as some ROS 1 tools write it); ``chunks``:
    their compression."""
    jazzy, noetic = typestore(), _noetic()
    msgs, _ = _messages(src)
    writer = Writer1(dst)
    if chunks is not None:
        writer.set_compression(chunks)
    with writer:
        conns: dict[str, Any] = {}
        for topic, msgtype, t_ns, raw in msgs:
            if topic not in conns:
                bare = {"msgdef": "", "md5sum": "0" * 32} if topic == empty_definition else {}
                conns[topic] = writer.add_connection(topic, msgtype, typestore=noetic, **bare)
            msg = _to_ros1(jazzy.deserialize_cdr(raw, msgtype), noetic)
            writer.write(conns[topic], t_ns, noetic.serialize_ros1(msg, msgtype))
    return dst


@pytest.mark.parametrize("chunks", [None, *Writer1.CompressionFormat])
def test_a_ros1_bag_gives_the_rosbag2_row(
    plain: Path, reference: dict[str, object], tmp_path: Path, capsys: pytest.CaptureFixture[str],
    chunks: Writer1.CompressionFormat | None,
) -> None:
    bag = _to_bag(plain, tmp_path / "episode.bag", chunks=chunks)
    _assert_same_row(reference, _row(bag))
    assert main(["compute", "--format", "json", str(tmp_path)]) == 0  # found in a directory
    (row,) = json.loads(capsys.readouterr().out)
    assert row["bag"] == str(bag) and row["success"] == 1.0


def test_a_ros1_tf_only_bag_gives_poses_from_pose_frames(tmp_path: Path) -> None:
    """The robot's odom -> base_link along +x at 1 m/s, and a static map -> odom shift by
    (2, 3): ROS 1 frame names carry a leading '/', which is dropped."""
    records = [(DEFAULT_T0_NS, "/tf_static", [transform(0, "/map", "/odom", 2.0, 3.0, 0.0)])]
    records += [(DEFAULT_T0_NS + i * 10**8, "/tf",
                 [transform(DEFAULT_T0_NS + i * 10**8, "/odom", "/base_link", 0.1 * i, 0.0, 0.0)])
                for i in range(11)]  # fmt: skip
    bag = _to_bag(write_tf_bag(tmp_path / "tf2", records), tmp_path / "tf.bag")
    episode = read_episode(bag, TopicMap(pose_frames=("map", "base_link")))
    np.testing.assert_allclose(episode.pose.x, 2.0 + 0.1 * np.arange(11), atol=EXACT)
    np.testing.assert_allclose(episode.pose.y, 3.0, atol=EXACT)


@pytest.mark.bad_input
def test_a_type_no_definition_covers_is_named(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A ROS 1 /tf connection without a definition: Noetic has no tf2_msgs/msg/TFMessage."""
    records = [(DEFAULT_T0_NS + i * 10**8, "/tf",
                [transform(DEFAULT_T0_NS + i * 10**8, "odom", "base_link", 0.1 * i, 0.0, 0.0)])
               for i in range(3)]  # fmt: skip
    bag = _to_bag(write_tf_bag(tmp_path / "tf2", records), tmp_path / "bare.bag",
                  empty_definition="/tf")
    assert main(["compute", "--pose-frames", "odom:base_link", str(bag)]) == 1
    err = capsys.readouterr().err
    assert (f"error: '{bag}': topic '/tf': message type(s) ['tf2_msgs/msg/TFMessage'] are "
            "neither defined in the bag nor known to ROS 1 Noetic's types") in err


def test_a_ros1_odometry_without_definition_uses_noetic(plain: Path, tmp_path: Path) -> None:
    bag = _to_bag(plain, tmp_path / "bare_odom.bag", empty_definition="/ground_truth")
    assert _row(bag)["path_length_m"] == pytest.approx(5.0, abs=EXACT)


@pytest.mark.bad_input
def test_a_ros1_bag_of_garbage_is_one_error_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    bag = tmp_path / "garbage.bag"
    bag.write_bytes(b"#ROSBAG V2.0\n" + bytes(range(256)) * 8)
    assert main(["compute", str(bag)]) == 1
    (line,) = [x for x in capsys.readouterr().err.splitlines() if x.startswith("error:")]
    assert line.startswith(f"error: '{bag}': cannot open bag: ")


# --------------------------------------------------------------------------- compression


@pytest.mark.parametrize("storage", ["sqlite3", "mcap"])
@pytest.mark.parametrize("mode", [CompressionMode.FILE, CompressionMode.MESSAGE])
def test_a_compressed_bag_gives_the_plain_row(
    plain: Path, reference: dict[str, object], tmp_path: Path, storage: str,
    mode: CompressionMode,
) -> None:
    msgs, custom = _messages(plain)
    bag = _write2(tmp_path / "zipped", msgs, custom, storage=storage, compression=mode)
    _assert_same_row(reference, _row(bag))
    if mode == CompressionMode.FILE:
        (zipped,) = bag.glob("*.zstd")
        assert compute([zipped]).frame["bag"].tolist() == [str(bag)]  # its directory's bag
        (bag / "metadata.yaml").unlink()  # a lone compressed file, as a killed run leaves it
        _assert_same_row(reference, _row(zipped))


@pytest.mark.bad_input
def test_a_zstd_file_that_is_not_zstd_is_one_error_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    bad = tmp_path / "run_0.db3.zstd"
    bad.write_bytes(b"SQLite format 3\x00" + bytes(1000))
    assert main(["compute", str(bad)]) == 1
    (line,) = [x for x in capsys.readouterr().err.splitlines() if x.startswith("error:")]
    assert line.startswith(f"error: '{bad}': damaged bag or message: ZstdError")


# --------------------------------------------------------------------------- split bags


def test_a_split_bag_without_metadata_is_one_episode(
    plain: Path, reference: dict[str, object], tmp_path: Path
) -> None:
    msgs, _ = _messages(plain)
    half = len(msgs) // 2
    split = tmp_path / "runs" / "split"
    split.mkdir(parents=True)
    for i, part in enumerate((msgs[:half], msgs[half:])):
        written = _write2(tmp_path / f"part{i}", part, {})
        shutil.move(next(written.glob("*.db3")), split / f"split_{9 + i}.db3")
    # split_10 comes after split_9 (by index, not by name): no "went backwards" warning.
    _assert_same_row(reference, _row(split))
    for inputs in ([tmp_path / "runs"], [str(split / "*.db3")], [split / "split_9.db3"]):
        assert compute(inputs).frame["bag"].tolist() == [str(split)], inputs


def test_a_directory_of_unrelated_storage_files_is_no_one_bag(plain: Path, tmp_path: Path) -> None:
    mixed = tmp_path / "mixed"
    mixed.mkdir()
    for name in ("a.db3", "b.db3"):
        shutil.copy(next(plain.glob("*.db3")), mixed / name)
    with pytest.raises(BagError, match=r"'.*mixed': cannot open bag: no metadata.yaml and 2 "
                       r"storage files that are not one split bag"):
        read_episode(mixed)
    assert sorted(Path(b).name for b in compute([mixed]).frame["bag"]) == ["a.db3", "b.db3"]


# --------------------------------------------------------------------------- metadata versions

#: The metadata keys each rosbag2 version added (rosbags' DirectoryReader history).
_ADDED = {3: ("compression_format", "compression_mode"), 5: ("files",), 6: ("custom_data",),
          8: ("ros_distro",)}


@pytest.mark.parametrize("version", range(1, 10))
def test_every_metadata_version_gives_the_same_row(
    plain: Path, reference: dict[str, object], tmp_path: Path, version: int
) -> None:
    bag = shutil.copytree(plain, tmp_path / f"v{version}")
    meta = yaml.safe_load((bag / "metadata.yaml").read_text())
    info = meta["rosbag2_bagfile_information"]
    info["version"] = version
    for since, keys in _ADDED.items():
        for k in keys if version < since else ():
            info.pop(k)
    for topic in info["topics_with_message_count"]:
        md = topic["topic_metadata"]
        if version < 7:
            md.pop("type_description_hash")
        if version < 4:
            md.pop("offered_qos_profiles")
        elif version < 9:
            md["offered_qos_profiles"] = ""  # a YAML string before version 9
    (bag / "metadata.yaml").write_text(yaml.safe_dump(meta))
    row = _row(bag)
    _assert_same_row(reference, row)
    assert not math.isnan(row["collision_count"])  # the footprint fact was read
