"""What no robot does, in one place: speeds beyond its reach, and a pose stream that leaps
back and forth between two tracks.

* A speed is *implausible* above ``speed_limit``: twice the robot's max speed (the
  ``max_speed_mps`` fact, ``--max-speed``), capped at ``PLAUSIBLE_SPEED_MPS``, which holds when
  no max speed is known. Twice, because the fact is the forward limit: an omnidirectional
  robot's diagonal reaches √2 times it, and a simulated one overshoots it by about 12 %.
* A pose stream is *two sources in one* (two robots relayed on one topic, or a clock step that
  moved the receive times too, so that the bag interleaves two stretches) when, in a sustained
  share of its steps (``CORRUPT_SHARE``, at least ``CORRUPT_MIN``), consecutive poses imply an
  implausible speed, or a pose leaps away from both its neighbours while they lie close
  together (it alternates between two tracks). ``check_one_track`` refuses it as corrupt.
* Isolated implausible samples (odometry spikes) are judged; ``speed_outliers`` finds them so
  that the metrics warn, with their times.

docs/metrics.md ("Clock jumps and mixed sources", "Odd input") holds the definitions.
"""

from __future__ import annotations

import numpy as np

from ..errors import CorruptBagError
from .series_kinds import PoseSeries

#: Beyond these no ground robot moves (m/s, rad/s, m/s²): a series that exceeds one is damaged.
PLAUSIBLE_SPEED_MPS = 20.0
PLAUSIBLE_YAW_RATE_RADPS = 50.0
PLAUSIBLE_ACC_MPS2 = 100.0
#: A speed above this times the robot's max speed is implausible.
MAX_SPEED_FACTOR = 2.0
#: A pose stream whose implausible steps (or leaps between two tracks) make up this share of
#: its steps, and at least ``CORRUPT_MIN`` of them, holds two sources: refused.
CORRUPT_SHARE = 0.1
CORRUPT_MIN = 5
#: A pose leaps between two tracks when it lies at least ``ALTERNATION_RATIO`` times farther
#: from each neighbour than the neighbours lie from each other, and at least
#: ``ALTERNATION_MIN_M`` (m) from each (closer is odometry jitter).
ALTERNATION_RATIO = 3.0
ALTERNATION_MIN_M = 0.1


def speed_limit(max_speed_mps: float | None) -> float:
    """The speed (m/s) above which a sample is implausible, for a robot of this max speed."""
    if max_speed_mps is None:
        return PLAUSIBLE_SPEED_MPS
    return min(PLAUSIBLE_SPEED_MPS, MAX_SPEED_FACTOR * max_speed_mps)


def _limit_text(max_speed_mps: float | None) -> str:
    limit = speed_limit(max_speed_mps)
    if limit == PLAUSIBLE_SPEED_MPS:
        return f"{limit:g} m/s"
    return f"{limit:g} m/s ({MAX_SPEED_FACTOR:g} x the max speed {max_speed_mps:g} m/s)"


def step_speeds(pose: PoseSeries) -> np.ndarray:
    """The speed (m/s) each step between consecutive poses implies, over the larger of its
    time and the median step time (two messages stamped a millisecond apart after a delay
    carry the pose of a whole period, not a leap)."""
    if len(pose) < 2:
        return np.zeros(0)
    dt_s = np.diff(pose.t_ns).astype(float) * 1e-9
    dt_s = np.maximum(dt_s, float(np.median(dt_s)))
    return np.hypot(np.diff(pose.x), np.diff(pose.y)) / dt_s


def alternations(pose: PoseSeries) -> np.ndarray:
    """Per pose but the first and last, whether it leaps away from both its neighbours while
    they lie close together (``ALTERNATION_RATIO``, ``ALTERNATION_MIN_M``)."""
    if len(pose) < 3:
        return np.zeros(0, dtype=bool)
    step = np.hypot(np.diff(pose.x), np.diff(pose.y))
    skip = np.hypot(pose.x[2:] - pose.x[:-2], pose.y[2:] - pose.y[:-2])
    leap = np.minimum(step[:-1], step[1:])
    return (leap >= ALTERNATION_MIN_M) & (leap >= ALTERNATION_RATIO * skip)


def _sustained(flags: np.ndarray) -> bool:
    n = int(np.count_nonzero(flags))
    return n >= CORRUPT_MIN and n >= CORRUPT_SHARE * flags.size


def _span(t_s: np.ndarray) -> str:
    return f"{t_s.min():.2f}-{t_s.max():.2f} s" if t_s.size else "-"


def check_one_track(pose: PoseSeries, max_speed_mps: float | None, topic: str) -> None:
    """Refuse (``CorruptBagError``) a pose stream that holds two sources: implausible steps
    or leaps between two tracks in a sustained share of its steps."""
    t_s = (pose.t_ns - pose.t_ns[0]) * 1e-9 if len(pose) else np.zeros(0)
    fast = step_speeds(pose) > speed_limit(max_speed_mps)
    if _sustained(fast):
        at = t_s[:-1][fast]
        msg = (f"{topic}: consecutive poses imply a speed beyond {_limit_text(max_speed_mps)} "
               f"in {int(fast.sum())} of {fast.size} steps (up to "
               f"{float(step_speeds(pose)[fast].max()):.3g} m/s, at {_span(at)} after the first "
               "pose): two sources in one stream, as two robots relayed on one topic or a clock "
               "step that moved the receive times too give"
               f"{'' if max_speed_mps is None else ' (or the max speed is wrong)'}; refused as "
               "corrupt, not scored")
        raise CorruptBagError(msg)
    zig = alternations(pose)
    if _sustained(zig):
        msg = (f"{topic}: {int(zig.sum())} of {zig.size} poses leap away from both neighbours "
               f"while the neighbours lie close together (at {_span(t_s[1:-1][zig])} after the "
               "first pose): the stream alternates between two tracks, as two robots relayed "
               "on one topic give; refused as corrupt, not scored")
        raise CorruptBagError(msg)


def speed_outliers(speed: np.ndarray, max_speed_mps: float | None) -> np.ndarray:
    """Indices of the speed samples (m/s) that are implausible (``speed_limit``) or not
    finite."""
    speed = np.asarray(speed, dtype=float)
    return np.flatnonzero(~np.isfinite(speed) | (speed > speed_limit(max_speed_mps)))


def _max_at(values: np.ndarray, touched: np.ndarray, what: str, unit: str) -> str | None:
    """``what`` (its max) and whether an implausible sample is among those it is taken from."""
    values = np.asarray(values, dtype=float)
    if not values.size or not np.isfinite(values).any():
        return None
    k = int(np.nanargmax(np.where(np.isfinite(values), values, -np.inf)))
    return f"{what} {values[k]:.3g} {unit} {'at' if touched[k] else 'not at'} them"


def speed_outlier_warning(topic: str, t_s: np.ndarray, speed: np.ndarray,
                          max_speed_mps: float | None, lin_acc: np.ndarray,
                          lin_jerk: np.ndarray) -> str | None:
    """The warning on an episode whose speed samples (m/s, at ``t_s`` s after the first pose)
    include implausible ones: how many, when, and whether the max linear acceleration and
    jerk (differences of consecutive speeds, of consecutive accelerations) are taken at them.
    None when there are none."""
    bad = speed_outliers(speed, max_speed_mps)
    if not bad.size:
        return None
    touched = np.zeros(len(speed), dtype=bool)
    touched[bad] = True
    acc_touched = touched[:-1] | touched[1:]  # an acceleration spans two speeds
    jerk_touched = acc_touched[:-1] | acc_touched[1:]  # a jerk spans three
    times = ", ".join(f"{t:.2f}" for t in t_s[bad][:10]) + (", ..." if bad.size > 10 else "")
    speeds = np.asarray(speed, dtype=float)[bad]
    worst = float(np.max(np.where(np.isfinite(speeds), speeds, np.inf)))
    maxima = [m for m in (_max_at(lin_acc, acc_touched, "max linear acceleration", "m/s^2"),
                          _max_at(lin_jerk, jerk_touched, "max linear jerk", "m/s^3")) if m]
    return (f"{topic}: {bad.size} implausible speed sample(s) (odometry spikes?), above "
            f"{_limit_text(max_speed_mps)}, up to {worst:.3g} m/s, at t = {times} s; kept as "
            "read: the acceleration and jerk columns include them"
            + (f" ({'; '.join(maxima)})" if maxima else ""))
