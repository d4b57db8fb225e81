"""The navigation metrics of one episode, as pure functions of an ``Episode``.

Each definition (formula, time base, frame, sign, differencing) is written in
``docs/metrics.md``; keep the two in step.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from .facts import EpisodeFacts, Outcome
from .kinematics import (
    bearing_in_body,
    differentiate,
    distance_to_polyline,
    interval_mean,
    path_length,
    path_turning,
    seconds,
    time_mean,
    time_std,
    velocity_series,
)
from .results import EpisodeMetrics
from .series import Episode, PoseSeries, ScanSeries

NAN = float("nan")
#: Below these the robot counts as standing still (m/s, rad/s).
STILL_SPEED_MPS = 0.05
STILL_YAW_RATE_RADPS = 0.05
#: Positions closer than this are merged before the path's turning is measured (m).
TURNING_STEP_M = 0.01
#: A shorter path is no path: its distance/path ratio is undefined, not odometry jitter over a
#: start-goal distance (m).
MIN_PATH_M = 0.01
#: BARN challenge: actual time is clipped to [4, 8] x the optimal time.
BARN_CLIP = (4.0, 8.0)


def _finite(values: np.ndarray) -> np.ndarray:
    values = np.asarray(values, dtype=float)
    return values[np.isfinite(values)]


def _max(values: np.ndarray) -> float:
    values = _finite(values)
    return float(values.max()) if values.size else NAN


def _min(values: np.ndarray) -> float:
    values = _finite(values)
    return float(values.min()) if values.size else NAN


class ScanClearance(NamedTuple):
    """Per-scan obstacle figures (m); NaN for a scan with no valid beam."""

    nearest_m: np.ndarray  # nearest valid return
    range_mean_m: np.ndarray  # mean of valid returns
    margin_m: np.ndarray  # nearest return minus the footprint's edge along that beam


def scan_clearance(scan: ScanSeries, facts: EpisodeFacts) -> ScanClearance:
    """Nearest obstacle per scan, and its distance beyond the footprint when one is known."""
    ranges = scan.valid_ranges()
    has_valid = np.isfinite(ranges).any(axis=1)
    with np.errstate(all="ignore"):
        nearest = np.where(has_valid, np.nanmin(np.where(has_valid[:, None], ranges, 0), axis=1), NAN)
        mean = np.where(has_valid, np.nanmean(np.where(has_valid[:, None], ranges, 0), axis=1), NAN)
    if facts.footprint is None:
        return ScanClearance(nearest, mean, np.full(len(scan), NAN))
    edge = facts.footprint.boundary_distance(np.nan_to_num(scan.angles))
    margin_beams = ranges - edge
    with np.errstate(all="ignore"):
        margin = np.where(
            has_valid, np.nanmin(np.where(has_valid[:, None], margin_beams, 0), axis=1), NAN
        )
    return ScanClearance(nearest, mean, margin)


def _hold_time(t_ns: np.ndarray, flag: np.ndarray) -> float:
    """Total time (s) a per-sample flag holds, each sample holding until the next one."""
    if len(t_ns) < 2:
        return 0.0
    dt = np.diff(t_ns).astype(float) * 1e-9
    return float(np.sum(dt[flag[:-1]]))


def infer_outcome(
    pose: PoseSeries, facts: EpisodeFacts, clearance: ScanClearance | None, scan: ScanSeries | None
) -> Outcome:
    """Recorded outcome if any; else goal (final distance within tolerance, reached before any
    collision), collision (scan margin within the collision tolerance), timeout (goal known,
    neither happened) or unknown (no goal known and no collision seen)."""
    if facts.outcome is not None:
        return facts.outcome
    first_collision: int | None = None
    if clearance is not None and scan is not None:
        hits = np.flatnonzero(clearance.margin_m <= facts.collision_tolerance_m)
        first_collision = int(scan.t_ns[hits[0]]) if hits.size else None
    if facts.goal is not None:
        dist = np.hypot(pose.x - facts.goal[0], pose.y - facts.goal[1])
        if dist[-1] <= facts.goal_tolerance_m:
            reached = int(pose.t_ns[np.flatnonzero(dist <= facts.goal_tolerance_m)[0]])
            if first_collision is None or reached <= first_collision:
                return Outcome.GOAL
    if first_collision is not None:
        return Outcome.COLLISION
    return Outcome.TIMEOUT if facts.goal is not None else Outcome.UNKNOWN


def _rising_edges(flag: np.ndarray) -> int:
    """Number of False -> True transitions, counting a True first sample as one."""
    flag = np.asarray(flag, dtype=bool)
    if flag.size == 0:
        return 0
    return int(flag[0]) + int(np.sum(flag[1:] & ~flag[:-1]))


Metrics = dict[str, float]


def _scan_metrics(episode: Episode, clearance: ScanClearance | None) -> Metrics:
    """Obstacle distances, collisions (rising edges) and time within the safety margin."""
    scan, facts = episode.scan, episode.facts
    if clearance is None or scan is None:
        return dict.fromkeys(
            ("obstacle_dist_min_m", "obstacle_dist_mean_m", "scan_range_mean_m",
             "collision_count", "safety_violation_time_s"), NAN,
        )
    valid = _finite(scan.valid_ranges())
    out = {
        "obstacle_dist_min_m": _min(clearance.nearest_m),
        "obstacle_dist_mean_m": time_mean(seconds(scan.t_ns), clearance.nearest_m),
        "scan_range_mean_m": float(valid.mean()) if valid.size else NAN,
        "collision_count": NAN,
        "safety_violation_time_s": NAN,
    }
    if facts.footprint is not None:
        # A scan with no valid beam says nothing: the scan before it holds until the next.
        seen = np.isfinite(clearance.margin_m)
        margin, t_ns = clearance.margin_m[seen], scan.t_ns[seen]
        out["collision_count"] = float(_rising_edges(margin <= facts.collision_tolerance_m))
        out["safety_violation_time_s"] = _hold_time(t_ns, margin <= facts.safety_margin_m)
    return out


def _path_metrics(pose: PoseSeries, start_goal_m: float) -> Metrics:
    """Length, displacement, distance/path ratio, curvature and angle over length."""
    length = path_length(pose.x, pose.y)
    net = float(np.hypot(pose.x[-1] - pose.x[0], pose.y[-1] - pose.y[0]))
    reference = start_goal_m if math.isfinite(start_goal_m) else net
    turning = path_turning(pose.x, pose.y, TURNING_STEP_M)
    has_turns = turning.turn_rad.size > 0
    return {
        "path_length_m": length,
        "net_displacement_m": net,
        "start_goal_distance_m": start_goal_m,
        "distance_path_ratio": reference / length if length >= MIN_PATH_M else NAN,
        "path_curvature_mean_radpm": (
            float(np.mean(turning.turn_rad / turning.step_m)) if has_turns else NAN
        ),
        "angle_over_length_radpm": (
            float(turning.turn_rad.sum() / length) if has_turns and length > 0 else NAN
        ),
    }


def _motion_metrics(pose: PoseSeries) -> Metrics:
    """Velocity statistics, accelerations, jerks and time standing still (body frame)."""
    vel = velocity_series(pose)
    vel_t = seconds(vel.t_ns, pose.t_ns[0])
    speed = vel.speed
    acc = differentiate(vel.t_ns, np.column_stack([vel.vx, vel.vy, vel.wz]))
    jerk = differentiate(acc.t_ns, acc.value)
    lin_acc = np.hypot(acc.value[:, 0], acc.value[:, 1]) if len(acc.dt_s) else np.zeros(0)
    yaw_acc = np.abs(acc.value[:, 2]) if len(acc.dt_s) else np.zeros(0)
    lin_jerk = np.hypot(jerk.value[:, 0], jerk.value[:, 1]) if len(jerk.dt_s) else np.zeros(0)
    yaw_jerk = np.abs(jerk.value[:, 2]) if len(jerk.dt_s) else np.zeros(0)
    still = (speed < STILL_SPEED_MPS) & (np.abs(vel.wz) < STILL_YAW_RATE_RADPS)
    return {
        "lin_vel_mean_mps": time_mean(vel_t, speed),
        "lin_vel_std_mps": time_std(vel_t, speed),
        "ang_vel_mean_radps": time_mean(vel_t, np.abs(vel.wz)),
        "ang_vel_std_radps": time_std(vel_t, vel.wz),
        "lin_acc_max_mps2": _max(lin_acc),
        "lin_acc_mean_mps2": interval_mean(acc.dt_s, lin_acc),
        "yaw_acc_max_radps2": _max(yaw_acc),
        "yaw_acc_mean_radps2": interval_mean(acc.dt_s, yaw_acc),
        "lin_jerk_max_mps3": _max(lin_jerk),
        "lin_jerk_mean_mps3": interval_mean(jerk.dt_s, lin_jerk),
        "yaw_jerk_max_radps3": _max(yaw_jerk),
        "yaw_jerk_mean_radps3": interval_mean(jerk.dt_s, yaw_jerk),
        "time_not_moving_s": (
            float(np.sum(acc.dt_s[still[:-1] & still[1:]])) if len(acc.dt_s) else NAN
        ),
    }


def _goal_metrics(
    pose: PoseSeries, facts: EpisodeFacts, success: float, path_m: float, time_s: float,
    start_goal_m: float,
) -> Metrics:
    """Heading error to the goal, goal distances, SPL, soft-SPL and the BARN score."""
    if facts.goal is None:
        return dict.fromkeys(
            ("heading_error_mean_rad", "heading_error_signed_mean_rad", "goal_dist_min_m",
             "goal_dist_final_m", "spl", "soft_spl", "barn_score"), NAN,
        )
    gx, gy = facts.goal
    t_s = seconds(pose.t_ns)
    bearing = bearing_in_body(pose.x, pose.y, pose.yaw, gx, gy)
    goal_dist = np.hypot(pose.x - gx, pose.y - gy)
    longest = max(path_m, start_goal_m)
    weight = start_goal_m / longest if longest > 0 else NAN
    progress = 1.0 - goal_dist[-1] / start_goal_m if start_goal_m > 0 else NAN
    barn = NAN
    if facts.max_speed_mps is not None and start_goal_m > 0:
        optimal = start_goal_m / facts.max_speed_mps
        lo, hi = BARN_CLIP
        barn = success * optimal / float(np.clip(time_s, lo * optimal, hi * optimal))
    return {
        "heading_error_mean_rad": time_mean(t_s, np.abs(bearing)),
        "heading_error_signed_mean_rad": time_mean(t_s, bearing),
        "goal_dist_min_m": float(goal_dist.min()),
        "goal_dist_final_m": float(goal_dist[-1]),
        "spl": success * weight,
        "soft_spl": float(np.clip(progress, 0.0, 1.0)) * weight,
        "barn_score": barn,
    }


def _row_metrics(pose: PoseSeries, facts: EpisodeFacts) -> Metrics:
    """Deviation from the row's centre line (vineyard task)."""
    if facts.row_centerline is None:
        return {"row_path_mae_m": NAN, "row_path_mse_m2": NAN}
    dev = distance_to_polyline(pose.x, pose.y, np.asarray(facts.row_centerline))
    t_s = seconds(pose.t_ns)
    return {"row_path_mae_m": time_mean(t_s, np.abs(dev)), "row_path_mse_m2": time_mean(t_s, dev**2)}


def _follow_metrics(episode: Episode) -> Metrics:
    """Bearing of the person seen from the robot, at pose stamps within the person's recorded
    time range (person position linearly interpolated)."""
    keys = ("follow_heading_mean_rad", "follow_heading_mae_rad", "follow_heading_rmse_rad",
            "follow_heading_max_rad")
    pose, person = episode.pose, episode.person
    if person is None or len(person) == 0:
        return dict.fromkeys(keys, NAN)
    inside = (pose.t_ns >= person.t_ns[0]) & (pose.t_ns <= person.t_ns[-1])
    if not inside.any():
        return dict.fromkeys(keys, NAN)
    t0 = pose.t_ns[0]  # float64 of epoch nanoseconds would round to 256 ns
    at = (pose.t_ns[inside] - t0).astype(float)
    person_t = (person.t_ns - t0).astype(float)
    px = np.interp(at, person_t, person.x)
    py = np.interp(at, person_t, person.y)
    bearing = bearing_in_body(pose.x[inside], pose.y[inside], pose.yaw[inside], px, py)
    t_s = seconds(pose.t_ns[inside])
    return dict(zip(keys, (
        time_mean(t_s, bearing),
        time_mean(t_s, np.abs(bearing)),
        math.sqrt(time_mean(t_s, bearing**2)),
        float(np.abs(bearing).max()),
    )))


def compute_metrics(episode: Episode) -> EpisodeMetrics:
    """Every metric of ``docs/metrics.md`` for one episode."""
    pose, facts, scan = episode.pose, episode.facts, episode.scan
    clearance = scan_clearance(scan, facts) if scan is not None and len(scan) else None
    outcome = infer_outcome(pose, facts, clearance, scan)
    success = {Outcome.GOAL: 1.0, Outcome.COLLISION: 0.0, Outcome.TIMEOUT: 0.0}.get(outcome, NAN)

    # Clearance time: to the recorded outcome event when there is one, else the last pose.
    end_ns = int(pose.t_ns[-1])
    if facts.outcome_stamp_ns is not None:
        end_ns = min(max(facts.outcome_stamp_ns, int(pose.t_ns[0])), end_ns)
    time_s = (end_ns - int(pose.t_ns[0])) * 1e-9

    start = np.array(facts.start[:2]) if facts.start else np.array([pose.x[0], pose.y[0]])
    start_goal = float(np.linalg.norm(np.array(facts.goal) - start)) if facts.goal else NAN
    path = _path_metrics(pose, start_goal)
    return EpisodeMetrics(
        outcome=outcome.value,
        success=success,
        clearance_time_s=time_s,
        **path,
        **_motion_metrics(pose),
        **_scan_metrics(episode, clearance),
        **_goal_metrics(pose, facts, success, path["path_length_m"], time_s, start_goal),
        **_row_metrics(pose, facts),
        **_follow_metrics(episode),
        n_poses=len(pose),
        n_scans=len(scan) if scan is not None else 0,
    )
