"""``Derived``: one episode as its metrics see it, with what several of them share computed once
(velocities, accelerations, the scan's clearance, the outcome, the optimal path, the row
deviation). Metrics are registered on it in ``metrics.py`` (and by plugins, ``registry.py``);
each definition is written in ``docs/metrics.md``.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable
from functools import cached_property
from typing import NamedTuple

import numpy as np

from pic4rl_base.geometry import distance_to_polyline

from ..contract import BARN_WORLDS, UNJUDGED, EpisodeFacts, Outcome, world_set
from .crop_rows import deviations
from .kinematics import (Derivative, PathTurning, VelocitySeries, bearing_in_body, differentiate,
                         path_length, path_turning, seconds, velocity_series)
from .roles import SERIES_ROLES
from .scan_summary import ROW_TASK, ScanClearance, ScanSummary, summarize
from .series import Episode
from .tasks.seen import SeenCurve, seen_curve, wants_seen

NAN = float("nan")
#: Positions closer than this are merged before the path's turning is measured (m).
TURNING_STEP_M = 0.01
#: An unrecorded end this far (fraction) or more before the time budget is ``ABORTED``: a
#: timed-out episode's bag may lack its last step or two, a killed one lacks much more.
ABORT_SLACK = 0.05


class Derived:
    """One episode and what its metrics share, each computed on first use."""

    def __init__(self, episode: Episode) -> None:
        #: ``scan``: the episode's scans, whole (``ScanSeries``) or as the reader summarized
        #: them (``ScanSummary``); the metrics read them through ``scan_summary``.
        self.episode = episode
        self.facts = episode.facts.with_defaults()
        self.pose = episode.pose
        self.scan = episode.scan if episode.scan is not None and len(episode.scan) else None

    def missing(self, needs: Iterable[str]) -> set[str]:
        """The inputs of ``needs`` this episode lacks (``INPUT_TESTS``)."""
        return {name for name in needs if not INPUT_TESTS[name](self)}

    # -- time and outcome ---------------------------------------------------------------------

    @cached_property
    def t_s(self) -> np.ndarray:
        return seconds(self.pose.t_ns)

    @cached_property
    def scan_summary(self) -> ScanSummary | None:
        """What the metrics use of each scan: the reader's summary, else the summary of the
        episode's whole scans (``scan_summary.summarize``)."""
        scan = self.scan
        if scan is None or isinstance(scan, ScanSummary) and scan.made_for(self.facts):
            return scan
        if isinstance(scan, ScanSummary):
            msg = ("the scans were summarized for another footprint, LiDAR mount or task than "
                   "the episode's facts; read the bag with full_scans=True")
            raise ValueError(msg)
        return summarize(scan, self.facts)

    @cached_property
    def clearance(self) -> ScanClearance | None:
        s = self.scan_summary
        return None if s is None else ScanClearance(s.nearest_m, s.range_mean_m, s.margin_m)

    @cached_property
    def collision(self) -> np.ndarray | None:
        """Per scan with a valid beam: the footprint within the collision tolerance (the
        env's test, ``distance < collision_tolerance_m``); None without scan or footprint."""
        if self.clearance is None or self.facts.footprint is None:
            return None
        margin = self.clearance.margin_m
        return margin[np.isfinite(margin)] < self.facts.collision_tolerance_m

    @cached_property
    def outcome(self) -> Outcome:
        """Recorded outcome if any; else goal (final distance within tolerance, reached before
        any collision), collision (some scan in collision), timeout (goal known, neither
        happened) or unknown (no goal known and no collision seen)."""
        facts, pose = self.facts, self.pose
        if facts.outcome is not None:
            return facts.outcome
        first_collision: int | None = None
        if self.collision is not None and self.collision.any():
            seen = np.isfinite(self.clearance.margin_m)  # type: ignore[union-attr]
            first_collision = int(self.scan.t_ns[seen][np.argmax(self.collision)])  # type: ignore[union-attr]
        if facts.goal is not None:
            dist = np.hypot(pose.x - facts.goal[0], pose.y - facts.goal[1])
            if dist[-1] <= facts.goal_tolerance_m:
                reached = int(pose.t_ns[np.flatnonzero(dist <= facts.goal_tolerance_m)[0]])
                if first_collision is None or reached <= first_collision:
                    return Outcome.GOAL
        if first_collision is not None:
            return Outcome.COLLISION
        if self.cut_short:
            return Outcome.ABORTED
        return Outcome.TIMEOUT if facts.goal is not None else Outcome.UNKNOWN

    @cached_property
    def cut_short(self) -> bool:
        """No outcome recorded and the poses end well before the episode's time budget (the
        sim or the tester died): the end says nothing of the agent."""
        budget = self.facts.time_budget_s
        if self.facts.outcome is not None or budget is None:
            return False
        return self.duration_s < budget * (1.0 - ABORT_SLACK)

    @cached_property
    def duration_s(self) -> float:
        """From the first pose to the last (s)."""
        return (int(self.pose.t_ns[-1]) - int(self.pose.t_ns[0])) * 1e-9

    @cached_property
    def success(self) -> float:
        """1 or 0; NaN when the end says nothing of the agent (``UNJUDGED``) or the episode
        has no goal (no goal fact, no recorded ``goal`` outcome: person monitoring, a real log
        without one), where a table heads with the full runs instead. A simulated exploration
        (its world's ``free_area_m2`` known) has its coverage target for a goal: judged."""
        target = wants_seen(self.facts) and self.facts.free_area_m2 is not None
        goal_less = self.facts.goal is None and self.outcome is not Outcome.GOAL and not target
        if self.outcome in UNJUDGED or goal_less:
            return NAN
        return float(self.outcome is Outcome.GOAL)

    @cached_property
    def time_s(self) -> float:
        """To the recorded outcome event when there is one (clamped), else the last pose."""
        t = self.pose.t_ns
        end_ns = int(t[-1])
        if self.facts.outcome_stamp_ns is not None:
            end_ns = min(max(self.facts.outcome_stamp_ns, int(t[0])), end_ns)
        return (end_ns - int(t[0])) * 1e-9

    # -- path and the optimal path ------------------------------------------------------------

    @cached_property
    def path_m(self) -> float:
        return path_length(self.pose.x, self.pose.y)

    @cached_property
    def net_m(self) -> float:
        p = self.pose
        return float(np.hypot(p.x[-1] - p.x[0], p.y[-1] - p.y[0]))

    @cached_property
    def start_goal_m(self) -> float:
        """Straight start-goal distance (m): start = recorded start or first pose."""
        if self.facts.goal is None:
            return NAN
        start = self.facts.start[:2] if self.facts.start else (self.pose.x[0], self.pose.y[0])
        return float(np.hypot(self.facts.goal[0] - start[0], self.facts.goal[1] - start[1]))

    @cached_property
    def straight_m(self) -> float:
        """The recorder's straight-line distance, else the start-goal distance."""
        recorded = self.facts.straight_line_m
        return recorded if recorded is not None else self.start_goal_m

    @cached_property
    def optimal(self) -> tuple[float, str | None]:
        """(length m, source): the shortest collision-free path when the bag records a finite
        one, else the straight line; (NaN, None) when neither is known."""
        shortest = self.facts.shortest_path_m
        if shortest is not None and math.isfinite(shortest) and shortest > 0:
            return shortest, "shortest"
        if math.isfinite(self.straight_m):
            return self.straight_m, "straight"
        return NAN, None

    # -- motion -------------------------------------------------------------------------------

    @cached_property
    def velocity(self) -> VelocitySeries:
        return velocity_series(self.pose)

    @cached_property
    def vel_t_s(self) -> np.ndarray:
        return seconds(self.velocity.t_ns, self.pose.t_ns[0])

    @cached_property
    def acc(self) -> Derivative:
        v = self.velocity
        return differentiate(v.t_ns, np.column_stack([v.vx, v.vy, v.wz]))

    @cached_property
    def jerk(self) -> Derivative:
        return differentiate(self.acc.t_ns, self.acc.value)

    @staticmethod
    def _linear(d: Derivative) -> np.ndarray:
        return np.hypot(d.value[:, 0], d.value[:, 1]) if len(d.dt_s) else np.zeros(0)

    @staticmethod
    def _yaw(d: Derivative) -> np.ndarray:
        return np.abs(d.value[:, 2]) if len(d.dt_s) else np.zeros(0)

    @cached_property
    def lin_acc(self) -> np.ndarray:
        return self._linear(self.acc)

    @cached_property
    def yaw_acc(self) -> np.ndarray:
        return self._yaw(self.acc)

    @cached_property
    def turning(self) -> PathTurning:
        return path_turning(self.pose.x, self.pose.y, TURNING_STEP_M)

    @cached_property
    def goal_dist(self) -> np.ndarray:
        gx, gy = self.facts.goal  # type: ignore[misc]
        return np.hypot(self.pose.x - gx, self.pose.y - gy)

    @cached_property
    def goal_bearing(self) -> np.ndarray:
        gx, gy = self.facts.goal  # type: ignore[misc]
        return bearing_in_body(self.pose.x, self.pose.y, self.pose.yaw, gx, gy)

    @cached_property
    def row_deviation(self) -> tuple[np.ndarray, np.ndarray, str] | None:
        """(times s, signed offsets m, source) of the robot from the row's centre line: the
        ``row_centerline`` fact at every pose (``"centerline"``), else, for a ``vineyard``
        episode, the middle of the rows each scan sees (``"scan"``, ``rows.lane_deviations``,
        scans where no lane is seen left out); ``None`` when neither is known."""
        if self.facts.row_centerline is not None:
            line = np.asarray(self.facts.row_centerline)
            return self.t_s, distance_to_polyline(self.pose.x, self.pose.y, line), "centerline"
        if self.facts.task != ROW_TASK or self.scan_summary is None:
            return None
        offsets = deviations(self.scan_summary.lanes)  # type: ignore[arg-type]
        seen = np.isfinite(offsets)
        if not seen.any():
            return None
        return seconds(self.scan.t_ns[seen], self.pose.t_ns[0]), offsets[seen], "scan"

    @cached_property
    def seen(self) -> SeenCurve | None:
        """An exploration episode's area seen over time (``tasks.seen``): the reader's, else
        integrated from the whole scans; None for another task or without scans."""
        return seen_curve(self.scan, self.pose, self.facts)

    @cached_property
    def spl_weight(self) -> float:
        """``l / max(p, l)`` with ``l`` the optimal path, ``p`` the path travelled."""
        optimal = self.optimal[0]
        longest = max(self.path_m, optimal)
        return optimal / longest if longest > 0 else NAN


#: The inputs a metric may need (``@metric(needs=...)``), each with its test of whether an
#: episode has it; a metric whose input is missing gives NaN. A role that fills a series
#: (``roles.SERIES_ROLES``) is needed by its name; the rest are facts.
INPUT_TESTS: dict[str, Callable[[Derived], bool]] = {
    "pose": lambda d: True,
    **{role.name: role.present for role in SERIES_ROLES.values()},
    "goal": lambda d: d.facts.goal is not None,
    "barn_world": lambda d: (d.facts.reference_path_m is not None
                             or world_set(d.facts.world) == BARN_WORLDS),
    "footprint": lambda d: d.facts.footprint is not None,
    "max_speed": lambda d: d.facts.max_speed_mps is not None,
    "row_centerline": lambda d: d.facts.row_centerline is not None,
    "person_distance": lambda d: d.facts.person_distance_m is not None,
    "camera_fov": lambda d: d.facts.camera_fov_rad is not None,
}
