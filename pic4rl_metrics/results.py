"""Typed results: one ``EpisodeMetrics`` per bag; ``METRICS`` describes every column.

Units are in the field names. ``NaN`` means "cannot be computed from this bag" (no goal,
no scan, no footprint, ...), never zero.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, fields
from typing import NamedTuple


@dataclass(frozen=True)
class EpisodeMetrics:
    """Navigation metrics of one episode; definitions in ``docs/metrics.md``."""

    outcome: str
    success: float
    clearance_time_s: float
    heading_error_mean_rad: float
    heading_error_signed_mean_rad: float
    path_length_m: float
    net_displacement_m: float
    start_goal_distance_m: float
    distance_path_ratio: float
    lin_vel_mean_mps: float
    lin_vel_std_mps: float
    ang_vel_mean_radps: float
    ang_vel_std_radps: float
    lin_acc_max_mps2: float
    lin_acc_mean_mps2: float
    yaw_acc_max_radps2: float
    yaw_acc_mean_radps2: float
    lin_jerk_max_mps3: float
    lin_jerk_mean_mps3: float
    yaw_jerk_max_radps3: float
    yaw_jerk_mean_radps3: float
    obstacle_dist_min_m: float
    obstacle_dist_mean_m: float
    scan_range_mean_m: float
    collision_count: float
    safety_violation_time_s: float
    spl: float
    soft_spl: float
    barn_score: float
    path_curvature_mean_radpm: float
    angle_over_length_radpm: float
    time_not_moving_s: float
    goal_dist_min_m: float
    goal_dist_final_m: float
    row_path_mae_m: float
    row_path_mse_m2: float
    follow_heading_mean_rad: float
    follow_heading_mae_rad: float
    follow_heading_rmse_rad: float
    follow_heading_max_rad: float
    n_poses: int
    n_scans: int

    def as_dict(self) -> dict[str, float | int | str]:
        """Plain dict, one key per column."""
        return asdict(self)


class MetricInfo(NamedTuple):
    """How a column is labelled in tables and plots."""

    label: str
    unit: str


#: Label and unit of each metric column, in table order.
METRICS: dict[str, MetricInfo] = {
    "success": MetricInfo("success", "n/total"),
    "clearance_time_s": MetricInfo("time", "s"),
    "heading_error_mean_rad": MetricInfo("cum. heading", "rad"),
    "heading_error_signed_mean_rad": MetricInfo("signed heading", "rad"),
    "path_length_m": MetricInfo("path", "m"),
    "net_displacement_m": MetricInfo("net displacement", "m"),
    "start_goal_distance_m": MetricInfo("start-goal distance", "m"),
    "distance_path_ratio": MetricInfo("dist/path", "m/m"),
    "lin_vel_mean_mps": MetricInfo("$v_{mean}$", "m/s"),
    "lin_vel_std_mps": MetricInfo("$v_{std.dev.}$", "m/s"),
    "ang_vel_mean_radps": MetricInfo("$\\omega_{mean}$", "rad/s"),
    "ang_vel_std_radps": MetricInfo("$\\omega_{std.dev.}$", "rad/s"),
    "lin_acc_max_mps2": MetricInfo("max linear acceleration", "m/s$^2$"),
    "lin_acc_mean_mps2": MetricInfo("mean linear acceleration", "m/s$^2$"),
    "yaw_acc_max_radps2": MetricInfo("max yaw acceleration", "rad/s$^2$"),
    "yaw_acc_mean_radps2": MetricInfo("mean yaw acceleration", "rad/s$^2$"),
    "lin_jerk_max_mps3": MetricInfo("max linear jerk", "m/s$^3$"),
    "lin_jerk_mean_mps3": MetricInfo("mean linear jerk", "m/s$^3$"),
    "yaw_jerk_max_radps3": MetricInfo("max yaw jerk", "rad/s$^3$"),
    "yaw_jerk_mean_radps3": MetricInfo("mean yaw jerk", "rad/s$^3$"),
    "obstacle_dist_min_m": MetricInfo("min obstacle distance", "m"),
    "obstacle_dist_mean_m": MetricInfo("mean obstacle distance", "m"),
    "scan_range_mean_m": MetricInfo("mean scan range", "m"),
    "collision_count": MetricInfo("collisions", "count"),
    "safety_violation_time_s": MetricInfo("time in safety margin", "s"),
    "spl": MetricInfo("SPL", "-"),
    "soft_spl": MetricInfo("soft-SPL", "-"),
    "barn_score": MetricInfo("BARN score", "-"),
    "path_curvature_mean_radpm": MetricInfo("mean curvature", "rad/m"),
    "angle_over_length_radpm": MetricInfo("angle over length", "rad/m"),
    "time_not_moving_s": MetricInfo("time not moving", "s"),
    "goal_dist_min_m": MetricInfo("min goal distance", "m"),
    "goal_dist_final_m": MetricInfo("final goal distance", "m"),
    "row_path_mae_m": MetricInfo("row path MAE", "m"),
    "row_path_mse_m2": MetricInfo("row path MSE", "m$^2$"),
    "follow_heading_mean_rad": MetricInfo("following heading mean", "rad"),
    "follow_heading_mae_rad": MetricInfo("following heading MAE", "rad"),
    "follow_heading_rmse_rad": MetricInfo("following heading RMSE", "rad"),
    "follow_heading_max_rad": MetricInfo("following heading max", "rad"),
}

#: Columns of the paper's Table 1, in its order.
TABLE1_COLUMNS: tuple[str, ...] = (
    "success",
    "clearance_time_s",
    "heading_error_mean_rad",
    "path_length_m",
    "distance_path_ratio",
    "lin_vel_mean_mps",
    "ang_vel_std_radps",
    "lin_acc_max_mps2",
    "yaw_acc_max_radps2",
    "obstacle_dist_min_m",
    "obstacle_dist_mean_m",
)

#: Columns a result DataFrame holds besides the metrics: where the row came from.
ID_COLUMNS: tuple[str, ...] = ("bag", "agent", "task", "world", "run", "episode", "pose_topic")
#: Column holding the error message of a bag that could not be judged ("" when none).
ERROR_COLUMN = "error"

METRIC_COLUMNS: tuple[str, ...] = tuple(f.name for f in fields(EpisodeMetrics))
