"""Helpers shared by the metrics' tests: tolerances, a straight line, one bag's metrics row,
and a bag rewritten with another outcome event.

Tolerances (absolute unless stated):

* ``EXACT = 1e-12``: quantities that are exact in real arithmetic and only pick up float64
  rounding of O(1..10) values summed over ~100 samples (a few ulps each, ~1e-14 in all).
* ``DIFF = 1e-9``: finite differences of float64 samples: ``Δv/Δt`` divides a rounding error
  of ~1e-16 by ``Δt = 0.1`` s (twice for jerk), far below 1e-9.
* ``F32 = 1e-6``: scan ranges travel as float32 (relative error 6e-8, ranges <= 10 m), so
  anything read from a scan is compared to 1e-6 m.
* Chord-vs-arc: a circle sampled every ``Δφ`` has a path ``N·2r·sin(Δφ/2)``, shorter than
  the arc ``N·r·Δφ`` by a relative ``Δφ²/24``; the code is compared with the exact chord sum
  at ``DIFF`` and with the arc within that discretisation error.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

from rosbags.rosbag2 import Reader, Writer

from pic4rl_metrics import compute
from pic4rl_metrics.contract import typestore
from pic4rl_metrics.tables.results import ERROR_COLUMN, ID_COLUMNS, METRIC_COLUMNS
from pic4rl_metrics.synthetic.synthetic import straight_line

EXACT = 1e-12
DIFF = 1e-9
F32 = 1e-6
NS = 1_000_000_000

JACKAL = {"length_m": 0.508, "width_m": 0.430}  # half-length 0.254, half-width 0.215


def row(bag: Path | str, **kwargs: object) -> dict[str, object]:
    """The one metrics row of ``bag`` (asserting that it was judged without error)."""
    frame = compute([bag], **kwargs).frame  # type: ignore[arg-type]
    assert len(frame) == 1, frame
    row = frame.iloc[0].to_dict()
    assert row["error"] == "", row["error"]
    return row


def same(a: object, b: object) -> bool:
    """Equal, with NaN equal to NaN (and None to None)."""
    if isinstance(a, float) and isinstance(b, float) and math.isnan(a) and math.isnan(b):
        return True
    return a == b


def rewrite(src: Path, dst: Path, *, outcome_stamp_ns: int | None = None,
             outcome_word_recv_ns: int | None = None) -> Path:
    """Copy bag ``src`` to ``dst`` message by message (a real rosbag2 bag again), changing
    the outcome event: its ``stamp_ns``, or a bare word (no stamp) received at a given bag
    time. custom_data is not copied (the facts and outcome topics carry what it held)."""
    ts = typestore()
    with Reader(src) as reader, Writer(dst, version=9) as writer:
        conns = {c.id: writer.add_connection(c.topic, c.msgtype, typestore=ts)
                 for c in reader.connections}
        for conn, t_ns, raw in reader.messages():
            data = bytes(raw)
            if conn.topic == "/episode/outcome":
                msg = ts.deserialize_cdr(data, conn.msgtype)
                event = json.loads(msg.data)
                if outcome_stamp_ns is not None:
                    text = json.dumps(event | {"stamp_ns": outcome_stamp_ns})
                else:
                    text, t_ns = event["outcome"], outcome_word_recv_ns or t_ns
                data = ts.serialize_cdr(ts.types[conn.msgtype](text), conn.msgtype)
            writer.write(conns[conn.id], t_ns, data)
    return dst


LINE = straight_line(0.5, 10.0)  # 0.5 m/s along +x for 10 s at 10 Hz: 101 poses, x 0..5 m


def result_row(bag: str, agent: object, run: object = "run1", error: str = "", **metrics: object):
    """One row of a result frame, as ``compute`` makes it; NaN metrics unless given."""
    row: dict[str, object] = dict.fromkeys(ID_COLUMNS)
    row.update(bag=bag, agent=agent, task="goal", world="indoor", run=run, episode=1)
    row.update({m: math.nan for m in METRIC_COLUMNS})
    row.update(outcome=None if error else "goal", n_poses=0 if error else 100, n_scans=50)
    row.update(metrics)
    row[ERROR_COLUMN] = error
    return row


def transform(ns: int, parent: str, child: str, x: float, y: float, yaw: float,
              z: float = 0.0) -> object:
    """A ``TransformStamped`` of ``child`` in ``parent``: (x, y, z) and a turn ``yaw`` about z."""
    t = typestore().types
    sec, nanosec = divmod(int(ns), NS)
    return t["geometry_msgs/msg/TransformStamped"](
        t["std_msgs/msg/Header"](t["builtin_interfaces/msg/Time"](sec, nanosec), parent),
        child,
        t["geometry_msgs/msg/Transform"](
            t["geometry_msgs/msg/Vector3"](x, y, z),
            t["geometry_msgs/msg/Quaternion"](0.0, 0.0, math.sin(yaw / 2), math.cos(yaw / 2)),
        ),
    )


def write_tf_bag(path: Path, records: list[tuple[int, str, list[object]]]) -> Path:
    """A bag of ``TFMessage``s only: (receive ns, topic, transforms), written in that order."""
    ts = typestore()
    tf_message = ts.types["tf2_msgs/msg/TFMessage"]
    with Writer(path, version=9) as writer:
        conns: dict[str, object] = {}
        for recv_ns, topic, transforms in records:
            if topic not in conns:
                conns[topic] = writer.add_connection(topic, "tf2_msgs/msg/TFMessage", typestore=ts)
            data = ts.serialize_cdr(tf_message(transforms), "tf2_msgs/msg/TFMessage")
            writer.write(conns[topic], recv_ns, data)
    return path
