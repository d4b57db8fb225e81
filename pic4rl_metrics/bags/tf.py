"""Poses from a chain of transforms (``tf2_msgs/msg/TFMessage``), as evo and tf2 read them.

A bag's ``/tf`` holds the moving transforms (``odom -> base_link`` from the wheels,
``map -> odom`` from a localiser) and ``/tf_static`` the fixed ones (sensor mounts, a fixed
``map -> odom``). The pose of frame *child* in frame *parent* is the product of the transforms
along the tree's path between them, in 3D, projected onto the plane at the end. Its stamps are
those of the moving transform nearest the child; every other moving transform is interpolated
there (linearly, rotations by slerp), and a stamp outside its time span is dropped, since tf2
does not extrapolate. A static transform holds at all times (the last one of a child wins).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from pic4rl_base.geometry import wrap_angle

#: (parent, child, stamp ns, tx, ty, tz, qx, qy, qz, qw) of one ``TransformStamped``.
Row = tuple[str, str, int, float, float, float, float, float, float, float]


class ChainError(LookupError):
    """No chain of transforms joins two frames, or the chain does not move."""


def tf_rows(msg: Any) -> list[Row]:
    """The transforms of a ``TFMessage`` (frame names without a leading ``/``, as ROS 1 has)."""
    rows = []
    for tf in msg.transforms:
        t, q, stamp = tf.transform.translation, tf.transform.rotation, tf.header.stamp
        rows.append((
            tf.header.frame_id.lstrip("/"), tf.child_frame_id.lstrip("/"),
            int(stamp.sec) * 1_000_000_000 + int(stamp.nanosec), t.x, t.y, t.z, q.x, q.y, q.z, q.w,
        ))  # fmt: skip
    return rows


@dataclass(frozen=True)
class Edge:
    """One parent -> child transform over time: stamps (ns, increasing, unique), receive
    times (ns) of their messages, translations (N, 3) and unit quaternions (N, 4, xyzw)."""

    parent: str
    child: str
    t_ns: np.ndarray
    recv_ns: np.ndarray
    trans: np.ndarray
    quat: np.ndarray

    @property
    def moves(self) -> bool:
        return len(self.t_ns) > 1

    @property
    def name(self) -> str:
        return f"{self.parent}->{self.child}"


def edges(dynamic: list[tuple[int, list[Row]]], static: list[list[Row]]) -> dict[str, Edge]:
    """Every child frame's transform from its parent: ``dynamic`` are (receive time, rows) of
    ``/tf`` messages, ``static`` the rows of ``/tf_static`` messages. A child's last parent wins;
    a static transform, or one with a single stamp, holds at all times."""
    samples: dict[str, list[tuple[int, int, Row]]] = {}
    for recv, rows in dynamic:
        for row in rows:
            samples.setdefault(row[1], []).append((row[2], recv, row))
    for rows in static:
        for row in rows:
            samples[row[1]] = [(0, 0, row)]
    out = {}
    for child, got in samples.items():
        parent = got[-1][2][0]
        got = sorted((s for s in got if s[2][0] == parent), key=lambda s: s[0])
        t_ns = np.array([s[0] for s in got], dtype=np.int64)
        last = np.append(t_ns[1:] != t_ns[:-1], True)  # of repeated stamps, the last received
        values = np.array([s[2][3:] for s in got], dtype=float)[last]
        quat = values[:, 3:] / np.linalg.norm(values[:, 3:], axis=1, keepdims=True)
        recv = np.array([s[1] for s in got], dtype=np.int64)[last]
        out[child] = Edge(parent, child, t_ns[last], recv, values[:, :3], quat)
    return out


def _up(tree: dict[str, Edge], frame: str) -> list[Edge]:
    """Edges from ``frame`` up to its tree's root (stopping at a loop)."""
    path: list[Edge] = []
    while frame in tree and tree[frame] not in path:
        path.append(tree[frame])
        frame = tree[frame].parent
    return path


def links(tree: dict[str, Edge]) -> str:
    """The tree's transforms, for an error message."""
    return ", ".join(sorted(e.name for e in tree.values())) or "none"


def chain(tree: dict[str, Edge], parent: str, child: str) -> tuple[list[Edge], list[Edge]]:
    """Edges from the common ancestor down to ``parent`` and down to ``child``, root first;
    ``ChainError`` when the two frames are not in one tree."""
    to_parent, to_child = _up(tree, parent), _up(tree, child)
    root_of_parent = to_parent[-1].parent if to_parent else parent
    if root_of_parent != (to_child[-1].parent if to_child else child):
        msg = f"no chain of transforms joins {parent!r} and {child!r}; transforms: {links(tree)}"
        raise ChainError(msg)
    while to_parent and to_child and to_parent[-1] is to_child[-1]:
        to_parent.pop()
        to_child.pop()
    return to_parent[::-1], to_child[::-1]


def _qmul(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    ax, ay, az, aw = np.moveaxis(a, -1, 0)
    bx, by, bz, bw = np.moveaxis(b, -1, 0)
    return np.stack([
        aw * bx + ax * bw + ay * bz - az * by, aw * by - ax * bz + ay * bw + az * bx,
        aw * bz + ax * by - ay * bx + az * bw, aw * bw - ax * bx - ay * by - az * bz,
    ], axis=-1)  # fmt: skip


def _rotate(q: np.ndarray, v: np.ndarray) -> np.ndarray:
    u, w = q[..., :3], q[..., 3:]
    t = 2.0 * np.cross(u, v)
    return v + w * t + np.cross(u, t)


def _slerp(q0: np.ndarray, q1: np.ndarray, s: np.ndarray) -> np.ndarray:
    dot = np.sum(q0 * q1, axis=-1, keepdims=True)
    q1 = np.where(dot < 0, -q1, q1)
    theta = np.arccos(np.clip(np.abs(dot), 0.0, 1.0))
    small = theta < 1e-9
    sin = np.where(small, 1.0, np.sin(theta))
    w0 = np.where(small, 1.0 - s, np.sin((1.0 - s) * theta) / sin)
    w1 = np.where(small, s, np.sin(s * theta) / sin)
    q = w0 * q0 + w1 * q1
    return q / np.linalg.norm(q, axis=-1, keepdims=True)


def _at(edge: Edge, t_ns: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The edge's transform at ``t_ns`` (inside its span), interpolated."""
    if not edge.moves:
        n = len(t_ns)
        return np.repeat(edge.trans[-1:], n, axis=0), np.repeat(edge.quat[-1:], n, axis=0)
    i = np.clip(np.searchsorted(edge.t_ns, t_ns, side="right") - 1, 0, len(edge.t_ns) - 2)
    t0, t1 = edge.t_ns[i], edge.t_ns[i + 1]
    s = ((t_ns - t0) / (t1 - t0))[:, None]
    trans = edge.trans[i] + s * (edge.trans[i + 1] - edge.trans[i])
    return trans, _slerp(edge.quat[i], edge.quat[i + 1], s)


def _compose(path: list[Edge], t_ns: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The product of ``path``'s transforms (root first) at ``t_ns``."""
    trans = np.zeros((len(t_ns), 3))
    quat = np.tile([0.0, 0.0, 0.0, 1.0], (len(t_ns), 1))
    for edge in path:
        t, q = _at(edge, t_ns)
        trans, quat = trans + _rotate(quat, t), _qmul(quat, q)
    return trans, quat


def _relative(tree: dict[str, Edge], parent: str, child: str, t_ns: np.ndarray) -> np.ndarray:
    """(N, 3) of x, y, yaw of ``child`` in ``parent`` at ``t_ns``: inverse(root->parent) *
    (root->child), projected onto the plane."""
    to_parent, to_child = chain(tree, parent, child)
    tp, qp = _compose(to_parent, t_ns)
    tc, qc = _compose(to_child, t_ns)
    qp_inv = qp * np.array([-1.0, -1.0, -1.0, 1.0])
    trans, q = _rotate(qp_inv, tc - tp), _qmul(qp_inv, qc)
    yaw = np.arctan2(2.0 * (q[:, 3] * q[:, 2] + q[:, 0] * q[:, 1]),
                     1.0 - 2.0 * (q[:, 1] ** 2 + q[:, 2] ** 2))
    return np.column_stack([trans[:, 0], trans[:, 1], yaw])


def chain_poses(
    tree: dict[str, Edge], parent: str, child: str, warnings: list[str]
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Stamps (ns), receive times (ns) and (N, 3) x, y, yaw of ``child`` in ``parent``; the
    stamps are the moving transform's nearest ``child``. ``ChainError`` when no chain joins the
    frames or nothing on it moves."""
    to_parent, to_child = chain(tree, parent, child)
    moving = [e for e in (*to_parent[::-1], *to_child[::-1]) if e.moves]
    if not moving:
        on = ", ".join(e.name for e in (*to_parent, *to_child)) or "the same frame"
        msg = f"the transforms from {parent!r} to {child!r} ({on}) do not move"
        raise ChainError(msg)
    clock = next((e for e in to_child[::-1] if e.moves), moving[0])
    t_ns, recv = clock.t_ns, clock.recv_ns
    keep = np.ones(len(t_ns), dtype=bool)
    for edge in moving:
        inside = (t_ns >= edge.t_ns[0]) & (t_ns <= edge.t_ns[-1])
        if not inside.all() and edge is not clock:
            warnings.append(
                f"{int(np.sum(keep & ~inside))} pose(s) of {parent}->{child} outside the time "
                f"span of the transform {edge.name} dropped (tf2 does not extrapolate)"
            )
        keep &= inside
    t_ns, recv = t_ns[keep], recv[keep]
    return t_ns, recv, _relative(tree, parent, child, t_ns)


def static_pose(tree: dict[str, Edge], parent: str, child: str) -> tuple[float, float, float]:
    """x, y, yaw of ``child`` in ``parent`` through transforms that hold (``ChainError`` when
    none joins them)."""
    x, y, yaw = _relative(tree, parent, child, np.zeros(1, dtype=np.int64))[0]
    return float(x), float(y), float(wrap_angle(yaw))
