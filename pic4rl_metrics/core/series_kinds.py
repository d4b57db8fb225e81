"""The kinds of decoded time series an episode holds, as plain numpy arrays (``series``
gathers them into an ``Episode``).

Timestamps stay int nanoseconds (``t_ns``) on one time base per bag: message header stamps,
with headerless messages moved onto that base (see ``reader``). Arrays are sorted by time
with exact duplicates removed; frames are those of the recorded messages (poses in the pose
topic's frame, twists in the robot's body frame as ``nav_msgs/Odometry`` defines them).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from pic4rl_base.geometry import Pose2D, scan_points


@dataclass(frozen=True)
class PoseSeries:
    """Robot pose (m, rad) and, when the source carries one, its body-frame twist."""

    t_ns: np.ndarray
    x: np.ndarray
    y: np.ndarray
    yaw: np.ndarray
    #: Body-frame twist (m/s, rad/s); ``None`` for pose-only sources (PoseStamped).
    vx: np.ndarray | None = None
    vy: np.ndarray | None = None
    wz: np.ndarray | None = None

    def __len__(self) -> int:
        return len(self.t_ns)


@dataclass(frozen=True)
class ScanSeries:
    """2D laser scans, padded to a common beam count with NaN (ranges in m, angles in rad)."""

    t_ns: np.ndarray
    ranges: np.ndarray  # (n_scans, n_beams) float32/float64, NaN where padded
    angles: np.ndarray  # (n_scans, n_beams) bearing of each beam in the scan frame
    range_min: np.ndarray  # (n_scans,)
    range_max: np.ndarray  # (n_scans,)

    def __len__(self) -> int:
        return len(self.t_ns)

    def valid_ranges(self) -> np.ndarray:
        """Ranges with every non-return as NaN, following REP 117.

        ``+inf`` (no return), NaN (error) and finite values outside ``[range_min, range_max]``
        are no obstacle; ``-inf`` (object closer than ``range_min``) counts as ``range_min``.
        """
        ranges = np.asarray(self.ranges, dtype=float)
        rmin = self.range_min[:, None]
        rmax = self.range_max[:, None]
        too_close = np.isneginf(ranges)
        in_range = np.isfinite(ranges) & (ranges >= rmin) & (ranges <= rmax)
        out = np.where(in_range, ranges, np.nan)
        return np.where(too_close, np.broadcast_to(rmin, ranges.shape), out)

    def points(self, mount: Pose2D, ranges: np.ndarray | None = None,
               ) -> tuple[np.ndarray, np.ndarray]:
        """Valid returns (``ranges``: ``valid_ranges()``) of a scanner at ``mount`` as points in
        the base frame (``geometry.scan_points``): x and y (n_scans, n_beams), NaN elsewhere."""
        ranges = self.valid_ranges() if ranges is None else ranges
        angles = self.angles
        if len(angles) and (angles == angles[0]).all():
            angles = angles[0]  # one scanner: the trigonometry once, not once per scan
        return scan_points(ranges, angles, mount)


@dataclass(frozen=True)
class CmdSeries:
    """Velocity commands (m/s, rad/s) from ``Twist`` or ``TwistStamped``."""

    t_ns: np.ndarray
    vx: np.ndarray
    vy: np.ndarray
    wz: np.ndarray

    def __len__(self) -> int:
        return len(self.t_ns)


@dataclass(frozen=True)
class PointSeries:
    """Positions (m) of something tracked over time, e.g. the walking person."""

    t_ns: np.ndarray
    x: np.ndarray
    y: np.ndarray

    def __len__(self) -> int:
        return len(self.t_ns)


@dataclass(frozen=True)
class PeopleSeries:
    """Positions (m) of the people a tracker or the simulator reports: one row per message,
    one column per person (``geometry_msgs/PoseArray``: the array's index is the person), NaN
    where a message holds fewer people than the longest one."""

    t_ns: np.ndarray
    x: np.ndarray  # (n_messages, n_people)
    y: np.ndarray

    def __len__(self) -> int:
        return len(self.t_ns)
