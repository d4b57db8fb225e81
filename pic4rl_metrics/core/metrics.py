"""pic4rl's navigation metrics, registered as pure functions of an episode (``registry.py``)
seen through ``Derived`` (``derived.py``, what several metrics share, computed once).

Each definition (formula, time base, frame, sign, differencing) is written in
``docs/metrics.md``; keep the two in step.
"""

from __future__ import annotations

import math
from collections.abc import Iterable

import numpy as np

from ..contract import Outcome
from .derived import NAN, ROW_TASK, Derived
from .kinematics import interval_mean, seconds, time_mean, time_std
from .registry import METRIC_TABLE, EpisodeMetrics, Metric, evaluate, metric
from .series import Episode
from .plausibility import (
    PLAUSIBLE_ACC_MPS2,
    PLAUSIBLE_SPEED_MPS,
    PLAUSIBLE_YAW_RATE_RADPS,
    speed_outlier_warning,
    speed_outliers,
)

#: Below these the robot counts as standing still (m/s, rad/s).
STILL_SPEED_MPS = 0.05
STILL_YAW_RATE_RADPS = 0.05
#: A shorter path is no path: its distance/path ratio is undefined, not odometry jitter over a
#: start-goal distance (m).
MIN_PATH_M = 0.01
#: BARN challenge: the optimal time is the reference path over this speed (m/s); the actual
#: time runs from the moment the robot is ``BARN_MOVED_M`` (m) from its start and is clipped to
#: ``BARN_CLIP`` x the optimal time.
BARN_SPEED_MPS = 2.0
BARN_MOVED_M = 0.1
BARN_CLIP = (2.0, 8.0)


def _finite(values: np.ndarray) -> np.ndarray:
    values = np.asarray(values, dtype=float)
    return values[np.isfinite(values)]


def _max(values: np.ndarray) -> float:
    values = _finite(values)
    return float(values.max()) if values.size else NAN


def _min(values: np.ndarray) -> float:
    values = _finite(values)
    return float(values.min()) if values.size else NAN


def _hold_time(t_ns: np.ndarray, flag: np.ndarray) -> float:
    """Total time (s) a per-sample flag holds, each sample holding until the next one."""
    if len(t_ns) < 2:
        return 0.0
    dt = np.diff(t_ns).astype(float) * 1e-9
    return float(np.sum(dt[flag[:-1]]))


def _rising_edges(flag: np.ndarray) -> int:
    """Number of False -> True transitions, counting a True first sample as one."""
    flag = np.asarray(flag, dtype=bool)
    if flag.size == 0:
        return 0
    return int(flag[0]) + int(np.sum(flag[1:] & ~flag[:-1]))


# --- registration: one line per column, in table order ---------------------------------------


def _register(name: str, unit: str, label: str, needs: tuple[str, ...] = ("pose",),
              quality: bool = False, text: bool = False,
              table: tuple[str, int] | None = None):  # noqa: ANN202
    return metric(name, unit=unit, label=label, needs=needs, quality=quality, text=text,
                  table=table, _builtin=True)


_register("outcome", "", "outcome", text=True)(lambda d: d.outcome.value)
_register("success", "n/total", "success", table=("paper", 0))(lambda d: d.success)
_register("clearance_time_s", "s", "time", quality=True, table=("paper", 1))(lambda d: d.time_s)
_register("heading_error_mean_rad", "rad", "cum. heading", ("goal",), quality=True,
          table=("paper", 2))(
    lambda d: time_mean(d.t_s, np.abs(d.goal_bearing)))
_register("heading_error_signed_mean_rad", "rad", "signed heading", ("goal",), quality=True)(
    lambda d: time_mean(d.t_s, d.goal_bearing))
_register("path_length_m", "m", "path", quality=True, table=("paper", 3))(lambda d: d.path_m)
_register("net_displacement_m", "m", "net displacement")(lambda d: d.net_m)
_register("start_goal_distance_m", "m", "start-goal distance", ("goal",))(
    lambda d: d.start_goal_m)


@_register("distance_path_ratio", "m/m", "dist/path", quality=True, table=("paper", 4))
def _distance_path_ratio(d: Derived) -> float:
    reference = d.start_goal_m if math.isfinite(d.start_goal_m) else d.net_m
    return reference / d.path_m if d.path_m >= MIN_PATH_M else NAN


_register("optimal_path_m", "m", "optimal path")(lambda d: d.optimal[0])
_register("optimal_path_source", "", "optimal path source", text=True)(lambda d: d.optimal[1])


@_register("path_optimality", "m/m", "path optimality", quality=True)
def _path_optimality(d: Derived) -> float:
    return d.optimal[0] / d.path_m if d.path_m >= MIN_PATH_M else NAN


_register("lin_vel_mean_mps", "m/s", "$v_{mean}$", quality=True, table=("paper", 5))(
    lambda d: time_mean(d.vel_t_s, d.velocity.speed))
_register("lin_vel_std_mps", "m/s", "$v_{std.dev.}$", quality=True)(
    lambda d: time_std(d.vel_t_s, d.velocity.speed))
_register("ang_vel_mean_radps", "rad/s", "$\\omega_{mean}$", quality=True)(
    lambda d: time_mean(d.vel_t_s, np.abs(d.velocity.wz)))
_register("ang_vel_std_radps", "rad/s", "$\\omega_{std.dev.}$", quality=True, table=("paper", 6))(
    lambda d: time_std(d.vel_t_s, d.velocity.wz))
_register("lin_acc_max_mps2", "m/s$^2$", "max linear acceleration", quality=True,
          table=("paper", 7))(
    lambda d: _max(d.lin_acc))
_register("lin_acc_mean_mps2", "m/s$^2$", "mean linear acceleration", quality=True)(
    lambda d: interval_mean(d.acc.dt_s, d.lin_acc))
_register("yaw_acc_max_radps2", "rad/s$^2$", "max yaw acceleration", quality=True,
          table=("paper", 8))(
    lambda d: _max(d.yaw_acc))
_register("yaw_acc_mean_radps2", "rad/s$^2$", "mean yaw acceleration", quality=True)(
    lambda d: interval_mean(d.acc.dt_s, d.yaw_acc))
_register("lin_jerk_max_mps3", "m/s$^3$", "max linear jerk", quality=True)(
    lambda d: _max(d._linear(d.jerk)))
_register("lin_jerk_mean_mps3", "m/s$^3$", "mean linear jerk", quality=True)(
    lambda d: interval_mean(d.jerk.dt_s, d._linear(d.jerk)))
_register("yaw_jerk_max_radps3", "rad/s$^3$", "max yaw jerk", quality=True)(
    lambda d: _max(d._yaw(d.jerk)))
_register("yaw_jerk_mean_radps3", "rad/s$^3$", "mean yaw jerk", quality=True)(
    lambda d: interval_mean(d.jerk.dt_s, d._yaw(d.jerk)))
_register("obstacle_dist_min_m", "m", "min obstacle distance", ("scan",), quality=True,
          table=("paper", 9))(
    lambda d: _min(d.clearance.nearest_m))
_register("obstacle_dist_mean_m", "m", "mean obstacle distance", ("scan",), quality=True,
          table=("paper", 10))(
    lambda d: time_mean(seconds(d.scan.t_ns), d.clearance.nearest_m))


@_register("scan_range_mean_m", "m", "mean scan range", ("scan",), quality=True)
def _scan_range_mean(d: Derived) -> float:
    s = d.scan_summary  # type: ignore[union-attr]
    count = int(s.n_valid.sum())  # type: ignore[union-attr]
    return float(s.range_sum_m.sum() / count) if count else NAN  # type: ignore[union-attr]


# With a footprint: clearance from its boundary (the scan's margin, the collision test's).
_register("footprint_clearance_min_m", "m", "min footprint clearance", ("scan", "footprint"),
          quality=True)(lambda d: _min(d.clearance.margin_m))
_register("footprint_clearance_mean_m", "m", "mean footprint clearance",
          ("scan", "footprint"), quality=True)(
    lambda d: time_mean(seconds(d.scan.t_ns), d.clearance.margin_m))


@_register("collision_count", "count", "collisions", ("scan", "footprint"))
def _collision_count(d: Derived) -> float:
    """Rising edges over the scans with a valid beam (one with none says nothing)."""
    flags = d.collision
    return float(_rising_edges(flags)) if flags is not None and flags.size else NAN


@_register("safety_violation_time_s", "s", "time in safety margin", ("scan", "footprint"))
def _safety_violation_time(d: Derived) -> float:
    margin = d.clearance.margin_m  # type: ignore[union-attr]
    seen = np.isfinite(margin)
    if not seen.any():
        return NAN
    return _hold_time(d.scan.t_ns[seen], margin[seen] <= d.facts.safety_margin_m)  # type: ignore[union-attr]


_register("spl", "-", "SPL", ("goal",))(lambda d: d.success * d.spl_weight)


@_register("soft_spl", "-", "soft-SPL", ("goal",))
def _soft_spl(d: Derived) -> float:
    straight = d.straight_m
    progress = 1.0 - d.goal_dist[-1] / straight if straight >= MIN_PATH_M else NAN
    return float(np.clip(progress, 0.0, 1.0)) * d.spl_weight


def _barn_time(d: Derived) -> float:
    """BARN's actual time (s): from the first pose ``BARN_MOVED_M`` from the start (the
    ``start`` fact, else the first pose) to the end; NaN when the robot never got that far."""
    start = d.facts.start or (d.pose.x[0], d.pose.y[0])
    moved = np.flatnonzero(np.hypot(d.pose.x - start[0], d.pose.y - start[1]) >= BARN_MOVED_M)
    if not moved.size:
        return NAN
    return d.time_s - float(d.t_s[moved[0]] - d.t_s[0])


#: The BARN columns' episodes: a goal in a BARN world (its ``reference_path_m`` fact, or a
#: ``barn:<n>`` world); NaN elsewhere (an indoor episode, a real log without a goal).
BARN_NEEDS = ("goal", "barn_world")
_register("barn_time_s", "s", "BARN time", BARN_NEEDS, quality=True)(_barn_time)


@_register("barn_score", "-", "BARN score", BARN_NEEDS)
def _barn_score(d: Derived) -> float:
    reference = d.facts.reference_path_m or d.optimal[0]
    if not reference > 0 or math.isnan(d.success):
        return NAN
    if not d.success:
        return 0.0
    ot = reference / BARN_SPEED_MPS
    lo, hi = BARN_CLIP
    return ot / float(np.clip(_barn_time(d), lo * ot, hi * ot))


@_register("path_curvature_mean_radpm", "rad/m", "mean curvature", quality=True)
def _curvature(d: Derived) -> float:
    turning = d.turning
    return float(np.mean(turning.turn_rad / turning.step_m)) if turning.turn_rad.size else NAN


@_register("angle_over_length_radpm", "rad/m", "angle over length", quality=True)
def _angle_over_length(d: Derived) -> float:
    turning = d.turning
    if not turning.turn_rad.size or d.path_m <= 0:
        return NAN
    return float(turning.turn_rad.sum() / d.path_m)


@_register("time_not_moving_s", "s", "time not moving", quality=True)
def _time_not_moving(d: Derived) -> float:
    v = d.velocity
    still = (v.speed < STILL_SPEED_MPS) & (np.abs(v.wz) < STILL_YAW_RATE_RADPS)
    return float(np.sum(d.acc.dt_s[still[:-1] & still[1:]])) if len(d.acc.dt_s) else NAN


_register("goal_dist_min_m", "m", "min goal distance", ("goal",))(
    lambda d: float(d.goal_dist.min()))
_register("goal_dist_final_m", "m", "final goal distance", ("goal",))(
    lambda d: float(d.goal_dist[-1]))


def _crop_row_stat(stat):  # noqa: ANN001, ANN202
    def value(d: Derived) -> float:
        row = d.row_deviation
        return NAN if row is None else float(stat(row[0], row[1]))
    return value


_register("row_path_mae_m", "m", "row path MAE",
          table=("row", 0))(
    _crop_row_stat(lambda t, e: time_mean(t, np.abs(e))))
_register("row_path_mse_m2", "m$^2$", "row path MSE",
          table=("row", 1))(
    _crop_row_stat(lambda t, e: time_mean(t, e**2)))
_register("row_reference", "", "row reference", text=True)(
    lambda d: None if d.row_deviation is None else d.row_deviation[2])


# The person-monitoring columns (follow_heading_*, person_*) come here, in table order.
from .tasks import person  # noqa: E402, F401
# The exploration columns (area_seen_m2, coverage_pct, ...): NaN unless the task explores.
from .tasks import coverage  # noqa: E402, F401
# The social columns (zone intrusions, people_*, ...) of an episode with people.
from .tasks import crowd  # noqa: E402, F401

_register("n_poses", "count", "poses")(lambda d: len(d.pose))
_register("n_scans", "count", "scans")(lambda d: len(d.scan) if d.scan is not None else 0)
_register("n_speed_outliers", "count", "speed outliers")(
    lambda d: len(speed_outliers(d.velocity.speed, d.facts.max_speed_mps)))

#: pic4rl's own columns, in table order (user metrics come after them).
BUILTIN_COLUMNS: tuple[str, ...] = tuple(METRIC_TABLE.metrics)


# --- checks on the data ----------------------------------------------------------------------


def data_warnings(d: Derived) -> list[str]:
    """What makes the numbers suspect: implausible speeds (``plausibility``), physically
    impossible motion (a damaged bag judges silently otherwise) and scans that say nothing."""
    out: list[str] = []
    name = d.episode.pose_topic
    v = d.velocity
    dt = np.diff(d.pose.t_ns).astype(float) * 1e-9
    moved = np.hypot(np.diff(d.pose.x), np.diff(d.pose.y)) / dt if dt.size else np.zeros(0)
    note = speed_outlier_warning(name, d.vel_t_s, v.speed, d.facts.max_speed_mps, d.lin_acc,
                                 d._linear(d.jerk))
    out += [note] if note else []
    for what, values, limit, unit in (
        ("speed from pose differences", moved, PLAUSIBLE_SPEED_MPS, "m/s"),
        ("yaw rate", np.abs(v.wz), PLAUSIBLE_YAW_RATE_RADPS, "rad/s"),
        ("linear acceleration", d.lin_acc, PLAUSIBLE_ACC_MPS2, "m/s^2"),
    ):
        values = np.asarray(values, dtype=float)
        bad = ~np.isfinite(values) | (values > limit)
        if bad.any():
            worst = float(np.nanmax(np.where(np.isfinite(values), values, np.inf)))
            out.append(
                f"{name}: {what} up to {worst:.3g} {unit} in {int(bad.sum())} sample(s), beyond "
                f"{limit:g} {unit}: physically impossible (damaged bag?); metrics kept as read"
            )
    if d.facts.outcome is Outcome.ABORTED:
        out.append(f"aborted by the recorder ({d.facts.end_reason or 'no reason given'}): "
                   "out of the success rate")
    if d.cut_short and d.outcome is Outcome.ABORTED:
        out.append(f"no outcome recorded and {d.duration_s:.1f} s of its "
                   f"{d.facts.time_budget_s:g} s budget: judged aborted (cut short), out of the "
                   "success rate")
    if d.facts.task == ROW_TASK and d.row_deviation is None:
        why = "no scan" if d.scan is None else "no scan in which a row is seen on both sides"
        out.append(f"row: no row_centerline fact and {why}: row_path_mae_m and "
                   "row_path_mse_m2 NaN (give row_centerline in a topic map's facts)")
    if d.scan is not None:
        bad_limits = int(np.sum(~(d.scan.range_min <= d.scan.range_max)))
        if bad_limits:
            out.append(f"scan: {bad_limits} scan(s) with range_min > range_max (or NaN): "
                       "no beam of theirs is valid")
        if not np.isfinite(d.clearance.nearest_m).any():  # type: ignore[union-attr]
            out.append(f"scan: none of its {len(d.scan)} scans has a valid beam; obstacle "
                       "distances, collisions and safety time are NaN")
    return out


def compute_metrics(
    episode: Episode, metrics: Iterable[Metric] | None = None, *, explicit: bool = False
) -> EpisodeMetrics:
    """The registered metrics (all, or ``metrics``) of one episode; the warnings ride along.

    ``explicit``: the metrics were asked for by name, so a missing input is warned about.
    """
    derived = Derived(episode)
    selected = METRIC_TABLE.select() if metrics is None else tuple(metrics)
    values, warnings = evaluate(derived, selected, explicit=explicit)
    return EpisodeMetrics(values, warnings=(*data_warnings(derived), *warnings))
