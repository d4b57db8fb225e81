"""Property tests of ``compute_metrics`` on random episodes built from numpy arrays, and of
``read_episode``/``judge_bag`` on random bags.

The pure tests draw trajectories with irregular steps of 10 ms to 0.5 s, positions within
about ±130 m and yaw steps below 3 rad (so that the unwrapped yaw is unambiguous); the
tolerances of the rigid-motion test follow from that conditioning (see ``_tolerance``).
"""

from __future__ import annotations

import dataclasses
import math
import tempfile
import warnings
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, assume, example, given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from pic4rl_metrics import (
    Episode,
    EpisodeFacts,
    EpisodeMetrics,
    Footprint,
    MetricsError,
    Outcome,
    compute_metrics,
    judge_bag,
    read_episode,
)
from pic4rl_metrics.synthetic import synthetic
from pic4rl_metrics.core.metrics import MIN_PATH_M
from pic4rl_metrics.core.plausibility import check_one_track
from pic4rl_metrics.errors import CorruptBagError
from pic4rl_metrics.tables.results import METRIC_COLUMNS
from pic4rl_metrics.core.series import PointSeries, PoseSeries, ScanSeries

PURE = settings(max_examples=80, deadline=None, suppress_health_check=[HealthCheck.too_slow])
BAGS = settings(
    max_examples=15,
    deadline=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
)

EPS = np.finfo(float).eps
DT_MIN_NS = 10_000_000  # 10 ms
DT_MAX_NS = 500_000_000  # 0.5 s
STEP_M = 2.0
YAW_STEP = 3.0  # < pi: consecutive yaws never differ by an ambiguous half turn
STILL = 0.05  # metrics.STILL_SPEED_MPS and STILL_YAW_RATE_RADPS
TURNING_STEP_M = 0.01  # metrics.TURNING_STEP_M


def _wrap(angle: np.ndarray | float) -> np.ndarray:
    return (np.asarray(angle, dtype=float) + np.pi) % (2 * np.pi) - np.pi


# --------------------------------------------------------------------------- strategies


@st.composite
def stamps(draw: st.DrawFn, n: int, t0: int | None = None) -> np.ndarray:
    """``n`` strictly increasing int64 stamps (ns) with irregular steps."""
    if t0 is None:
        t0 = draw(st.integers(0, 2_000_000_000_000_000_000))
    steps = draw(arrays(np.int64, n - 1, elements=st.integers(DT_MIN_NS, DT_MAX_NS)))
    return t0 + np.concatenate([[0], np.cumsum(steps)]).astype(np.int64)


@st.composite
def poses(
    draw: st.DrawFn, *, min_n: int = 2, max_n: int = 40, twist: bool | None = None
) -> PoseSeries:
    n = draw(st.integers(min_n, max_n))
    t_ns = draw(stamps(n))
    origin = draw(arrays(float, 2, elements=st.floats(-50, 50)))
    # Subnormal steps (< 2.2e-308 m) round on a grid coarser than themselves: left out.
    step = st.floats(-STEP_M, STEP_M, allow_subnormal=False)
    steps = draw(arrays(float, (n - 1, 2), elements=step))
    xy = origin + np.vstack([np.zeros((1, 2)), np.cumsum(steps, axis=0)])
    yaw0 = draw(st.floats(-math.pi, math.pi))
    turns = draw(arrays(float, n - 1, elements=st.floats(-YAW_STEP, YAW_STEP)))
    yaw = _wrap(yaw0 + np.concatenate([[0.0], np.cumsum(turns)]))
    if twist is None:
        twist = draw(st.booleans())
    body: tuple[np.ndarray | None, ...] = (None, None, None)
    if twist:
        vel = arrays(float, n, elements=st.floats(-3, 3))
        vy = draw(st.one_of(st.none(), vel))
        body = (draw(vel), vy, draw(vel))
    return PoseSeries(t_ns, xy[:, 0].copy(), xy[:, 1].copy(), yaw, *body)


footprints = st.one_of(
    st.builds(Footprint, radius_m=st.floats(0.05, 1.0)),
    st.builds(Footprint, length_m=st.floats(0.1, 2.0), width_m=st.floats(0.1, 2.0)),
)
scan_values = st.one_of(
    st.sampled_from([math.inf, -math.inf, math.nan]),
    st.floats(0.0, 12.0),
)


@st.composite
def scans(draw: st.DrawFn, t_ns: np.ndarray, *, min_n: int = 0, max_n: int = 8) -> ScanSeries:
    """Scans over roughly the pose span, with ragged beam counts padded by NaN."""
    n = draw(st.integers(min_n, max_n))
    start = int(t_ns[0]) + draw(st.integers(-DT_MAX_NS, DT_MAX_NS))
    t_scan = draw(stamps(n, t0=start)) if n else np.zeros(0, np.int64)
    beams = draw(st.lists(st.integers(1, 24), min_size=n, max_size=n))
    width = max(beams, default=1)
    ranges = np.full((n, width), np.nan)
    angles = np.full((n, width), np.nan)
    for i, k in enumerate(beams):
        ranges[i, :k] = draw(arrays(float, k, elements=scan_values))
        # Subnormal start angles are left to test_rectangle_edge_at_a_tiny_bearing_...
        angle_min = draw(st.floats(-math.pi, 0.0).filter(lambda a: a == 0 or abs(a) > 1e-300))
        angles[i, :k] = angle_min + 2 * math.pi / k * np.arange(k)
    range_min = np.asarray(draw(st.lists(st.floats(0.0, 0.5), min_size=n, max_size=n)), float)
    range_max = np.asarray(draw(st.lists(st.floats(1.0, 10.0), min_size=n, max_size=n)), float)
    return ScanSeries(t_scan, ranges, angles, range_min, range_max)


points = st.tuples(st.floats(-60, 60), st.floats(-60, 60))


@st.composite
def episodes(
    draw: st.DrawFn,
    *,
    goal: bool | None = None,
    scan: bool | None = None,
    twist: bool | None = None,
    anything: bool = False,
) -> Episode:
    """A random episode. ``anything``: also random outcome, outcome stamp, max speed,
    row centre line and person."""
    pose = draw(poses(twist=twist))
    has_goal = draw(st.booleans()) if goal is None else goal
    has_scan = draw(st.booleans()) if scan is None else scan
    facts = EpisodeFacts(
        goal=draw(points) if has_goal else None,
        start=(*draw(points), draw(st.floats(-math.pi, math.pi))) if draw(st.booleans()) else None,
        footprint=draw(st.one_of(st.none(), footprints)),
        goal_tolerance_m=draw(st.floats(0.0, 5.0)),
        collision_tolerance_m=draw(st.floats(0.0, 0.5)),
        safety_margin_m=draw(st.floats(0.0, 1.0)),
    )
    person = None
    if anything:
        span = int(pose.t_ns[-1] - pose.t_ns[0])
        facts = dataclasses.replace(
            facts,
            outcome=draw(st.one_of(st.none(), st.sampled_from(list(Outcome)))),
            outcome_stamp_ns=draw(
                st.one_of(
                    st.none(), st.integers(int(pose.t_ns[0]) - span, int(pose.t_ns[-1]) + span)
                )
            ),
            max_speed_mps=draw(st.one_of(st.none(), st.floats(0.01, 5.0))),
            row_centerline=(
                tuple(draw(st.lists(points, min_size=2, max_size=5)))
                if draw(st.booleans())
                else None
            ),
        )
        if draw(st.booleans()):
            m = draw(st.integers(1, 10))
            t_person = draw(
                stamps(m, t0=int(pose.t_ns[0]) + draw(st.integers(-DT_MAX_NS, DT_MAX_NS)))
            )
            xy = draw(arrays(float, (m, 2), elements=st.floats(-60, 60)))
            person = PointSeries(t_person, xy[:, 0].copy(), xy[:, 1].copy())
    return Episode(
        bag=Path("random"),
        facts=facts,
        pose=pose,
        pose_topic="/odom",
        scan=draw(scans(pose.t_ns)) if has_scan else None,
        person=person,
    )


# --------------------------------------------------------------------------- helpers


def _same(a: float, b: float, *, rel: float = 0.0, abs_: float = 0.0) -> bool:
    if isinstance(a, str) or isinstance(b, str) or a is None or b is None:
        return a == b
    if math.isnan(a) or math.isnan(b):
        return math.isnan(a) and math.isnan(b)
    return math.isclose(a, b, rel_tol=rel, abs_tol=abs_)


def _differences(
    m1: EpisodeMetrics, m2: EpisodeMetrics, tolerances: dict[str, float], rel: float
) -> dict[str, tuple[float, float]]:
    return {
        name: (getattr(m1, name), getattr(m2, name))
        for name, abs_ in tolerances.items()
        if not _same(getattr(m1, name), getattr(m2, name), rel=rel, abs_=abs_)
    }


def _rigid(episode: Episode, theta: float, shift: tuple[float, float]) -> Episode:
    """The episode seen in a frame rotated by ``theta`` and moved by ``shift``: poses, yaw,
    goal and start move; body-frame twists and scans do not."""
    c, s = math.cos(theta), math.sin(theta)

    def move(x: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        return c * x - s * y + shift[0], s * x + c * y + shift[1]

    pose = episode.pose
    x, y = move(pose.x, pose.y)
    pose = dataclasses.replace(pose, x=x, y=y, yaw=_wrap(pose.yaw + theta))
    facts = episode.facts
    goal = start = None
    if facts.goal is not None:
        goal = tuple(float(v) for v in move(np.float64(facts.goal[0]), np.float64(facts.goal[1])))
    if facts.start is not None:
        sx, sy = move(np.float64(facts.start[0]), np.float64(facts.start[1]))
        start = (float(sx), float(sy), float(_wrap(facts.start[2] + theta)))
    facts = dataclasses.replace(facts, goal=goal, start=start)
    return dataclasses.replace(episode, pose=pose, facts=facts)


def _turning_well_posed(x: np.ndarray, y: np.ndarray) -> bool:
    """No pair of positions lies within rounding of the 1 cm merge distance of the turning
    metrics (whether a point is merged could otherwise flip under a rotation)."""
    d = np.hypot(x[:, None] - x[None, :], y[:, None] - y[None, :])
    return bool(np.all(np.abs(d - TURNING_STEP_M) > 1e-9))


def _stillness_well_posed(pose: PoseSeries) -> bool:
    """No velocity sample lies within rounding of the standing-still thresholds."""
    if pose.vx is not None and pose.wz is not None:
        return True  # body twist: untouched by the rigid motion
    dt = np.diff(pose.t_ns) * 1e-9
    speed = np.hypot(np.diff(pose.x), np.diff(pose.y)) / dt
    yaw_rate = np.abs(_wrap(np.diff(pose.yaw))) / dt
    return bool(np.all(np.abs(speed - STILL) > 1e-6) and np.all(np.abs(yaw_rate - STILL) > 1e-6))


def _goal_well_posed(episode: Episode) -> tuple[bool, bool]:
    """(goal bearing and outcome are well defined, signed bearing is away from ±pi)."""
    facts, pose = episode.facts, episode.pose
    if facts.goal is None:
        return True, True
    dist = np.hypot(pose.x - facts.goal[0], pose.y - facts.goal[1])
    start = np.asarray(facts.start[:2] if facts.start else (pose.x[0], pose.y[0]))
    start_goal = float(np.hypot(*(np.asarray(facts.goal) - start)))
    well = bool(
        np.all(dist > 1e-2)
        and start_goal > 1e-2
        and np.all(np.abs(dist - facts.goal_tolerance_m) > 1e-9)
    )
    bearing = _wrap(np.arctan2(facts.goal[1] - pose.y, facts.goal[0] - pose.x) - pose.yaw)
    return well, bool(np.all(np.abs(bearing) < math.pi - 1e-6))


# --------------------------------------------------------------------------- properties


@PURE
@given(episodes())
def test_path_length_is_at_least_the_net_displacement(episode: Episode) -> None:
    m = compute_metrics(episode)
    first_last = math.hypot(
        episode.pose.x[-1] - episode.pose.x[0], episode.pose.y[-1] - episode.pose.y[0]
    )
    assert m.net_displacement_m == pytest.approx(first_last, rel=1e-12, abs=1e-12)
    assert m.path_length_m >= m.net_displacement_m * (1 - 1e-9)
    assert m.path_length_m <= np.sum(
        np.abs(np.diff(episode.pose.x)) + np.abs(np.diff(episode.pose.y))
    ) * (1 + 1e-9)


@PURE
@given(episodes(goal=False))
def test_distance_path_ratio_without_goal_is_at_most_one(episode: Episode) -> None:
    m = compute_metrics(episode)
    if m.path_length_m >= MIN_PATH_M:
        assert m.distance_path_ratio <= 1 + 1e-9
        assert m.distance_path_ratio >= 0
    else:
        assert math.isnan(m.distance_path_ratio)
    assert math.isnan(m.start_goal_distance_m)


#: Metrics checked under a rigid motion, with the order of the time derivative they take
#: of positions (their absolute rounding error grows as eps * |position| / dt_min**order).
RIGID_METRICS: dict[str, int] = {
    # path
    "path_length_m": 0,
    "net_displacement_m": 0,
    "distance_path_ratio": 0,
    "path_curvature_mean_radpm": 0,
    "angle_over_length_radpm": 0,
    # clearance time
    "clearance_time_s": 0,
    # velocities (from pose differences when there is no twist)
    "lin_vel_mean_mps": 1,
    "lin_vel_std_mps": 1,
    "ang_vel_mean_radps": 1,
    "ang_vel_std_radps": 1,
    "time_not_moving_s": 0,
    # accelerations and jerks
    "lin_acc_max_mps2": 2,
    "lin_acc_mean_mps2": 2,
    "yaw_acc_max_radps2": 2,
    "yaw_acc_mean_radps2": 2,
    "lin_jerk_max_mps3": 3,
    "lin_jerk_mean_mps3": 3,
    "yaw_jerk_max_radps3": 3,
    "yaw_jerk_mean_radps3": 3,
    # goal: heading error, distances, SPL and friends
    "heading_error_mean_rad": 0,
    "start_goal_distance_m": 0,
    "goal_dist_min_m": 0,
    "goal_dist_final_m": 0,
    "spl": 0,
    "soft_spl": 0,
    "success": 0,
    # scans are in the body frame: a rigid motion of the world leaves them alone
    "obstacle_dist_min_m": 0,
    "obstacle_dist_mean_m": 0,
    "scan_range_mean_m": 0,
    "collision_count": 0,
    "safety_violation_time_s": 0,
}


def _tolerance(order: int, size_m: float) -> float:
    """Absolute rounding allowance: 1000 eps of the coordinates, over dt_min**order."""
    return max(1e3 * EPS * size_m / (DT_MIN_NS * 1e-9) ** order, 1e-12)


#: Below this (m) a path or start-goal distance is ill-conditioned as a divisor; the
#: turning metrics merge positions closer than 1 cm, so their steps are at least this long.
SHORT_M = 1e-2


@PURE
@given(
    episodes(goal=True),
    st.floats(-math.pi, math.pi),
    st.tuples(st.floats(-60, 60), st.floats(-60, 60)),
)
def test_pose_frame_metrics_are_invariant_under_a_rigid_motion(
    episode: Episode, theta: float, shift: tuple[float, float]
) -> None:
    pose = episode.pose
    goal_ok, signed_ok = _goal_well_posed(episode)
    assume(goal_ok)
    assume(_turning_well_posed(pose.x, pose.y))
    assume(_stillness_well_posed(pose))
    length = float(np.sum(np.hypot(np.diff(pose.x), np.diff(pose.y))))
    assume(length == 0 or length > SHORT_M)
    moved = _rigid(episode, theta, shift)
    size = float(
        max(
            np.abs(pose.x).max(),
            np.abs(pose.y).max(),
            np.abs(moved.pose.x).max(),
            np.abs(moved.pose.y).max(),
            *np.abs(episode.facts.goal),
            1.0,
        )
    )
    tolerances = {name: _tolerance(order, size) for name, order in RIGID_METRICS.items()}
    # Quotients by a length >= 1 cm (ratio, SPL) and turns over steps >= 1 cm (curvature).
    for name in ("distance_path_ratio", "spl", "soft_spl"):
        tolerances[name] = _tolerance(0, size) / SHORT_M
    for name in ("path_curvature_mean_radpm", "angle_over_length_radpm"):
        tolerances[name] = len(pose) * _tolerance(0, size) / SHORT_M**2
    if signed_ok:
        tolerances["heading_error_signed_mean_rad"] = _tolerance(0, size)
    before, after = compute_metrics(episode), compute_metrics(moved)
    assert before.outcome == after.outcome
    assert _differences(before, after, tolerances, rel=1e-9) == {}


@PURE
@given(episodes(anything=True), st.integers(-1_000_000_000_000_000_000, 1_000_000_000_000_000_000))
def test_metrics_are_invariant_under_a_shift_of_every_stamp(episode: Episode, shift: int) -> None:
    pose = dataclasses.replace(episode.pose, t_ns=episode.pose.t_ns + shift)
    scan = episode.scan and dataclasses.replace(episode.scan, t_ns=episode.scan.t_ns + shift)
    facts = episode.facts
    if facts.outcome_stamp_ns is not None:
        facts = dataclasses.replace(facts, outcome_stamp_ns=facts.outcome_stamp_ns + shift)
    # The person's position is interpolated on float stamps, whose rounding moves with the
    # shift: the person is left out of this exact comparison.
    before = compute_metrics(dataclasses.replace(episode, person=None))
    after = compute_metrics(
        dataclasses.replace(episode, pose=pose, scan=scan, facts=facts, person=None)
    )
    differ = {
        name: (getattr(before, name), getattr(after, name))
        for name in METRIC_COLUMNS
        if not _same(getattr(before, name), getattr(after, name))
    }
    assert differ == {}


def _expected_scan_min_and_mean(scan: ScanSeries | None) -> tuple[float, float]:
    """REP 117 by hand: finite in [range_min, range_max] counts, -inf is range_min."""
    if scan is None or len(scan) == 0:
        return math.nan, math.nan
    values: list[float] = []
    for row, rmin, rmax in zip(scan.ranges, scan.range_min, scan.range_max, strict=True):
        for r in row:
            if r == -math.inf:
                values.append(float(rmin))
            elif math.isfinite(r) and rmin <= r <= rmax:
                values.append(float(r))
    if not values:
        return math.nan, math.nan
    return min(values), float(np.mean(values))


@PURE
@given(episodes(anything=True))
def test_no_exception_or_warning_escapes_and_results_are_in_range(episode: Episode) -> None:
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        m = compute_metrics(episode)
    facts, scan = episode.facts, episode.scan
    assert m.n_poses == len(episode.pose)
    assert m.n_scans == (len(scan) if scan is not None else 0)
    assert m.outcome in {o.value for o in Outcome}
    if facts.outcome is not None:
        assert m.outcome == facts.outcome.value
    expected_success = {"goal": 1.0, "collision": 0.0, "timeout": 0.0, "diverged": 0.0}.get(
        m.outcome, math.nan
    )
    if facts.goal is None and m.outcome != "goal":  # no goal: no success to speak of
        expected_success = math.nan
    assert _same(m.success, expected_success)
    span_s = (episode.pose.t_ns[-1] - episode.pose.t_ns[0]) * 1e-9
    assert 0 <= m.clearance_time_s <= span_s + 1e-9
    assert m.path_length_m >= 0 and m.net_displacement_m >= 0
    one_velocity = len(episode.pose) == 2 and episode.pose.vx is None  # no interval of two
    if one_velocity:
        assert math.isnan(m.time_not_moving_s) and math.isnan(m.lin_acc_max_mps2)
    else:
        assert 0 <= m.time_not_moving_s <= span_s + 1e-9
    for name in (
        "lin_vel_mean_mps",
        "lin_vel_std_mps",
        "ang_vel_mean_radps",
        "ang_vel_std_radps",
        "lin_acc_max_mps2",
        "lin_acc_mean_mps2",
        "yaw_acc_max_radps2",
        "yaw_acc_mean_radps2",
        "lin_jerk_max_mps3",
        "lin_jerk_mean_mps3",
        "yaw_jerk_max_radps3",
        "yaw_jerk_mean_radps3",
    ):
        value = getattr(m, name)
        assert math.isnan(value) or value >= 0, name
    if not one_velocity:
        assert m.lin_acc_mean_mps2 <= m.lin_acc_max_mps2 * (1 + 1e-9) + 1e-9
        assert m.yaw_acc_mean_radps2 <= m.yaw_acc_max_radps2 * (1 + 1e-9) + 1e-9
    # scans
    nearest, mean = _expected_scan_min_and_mean(scan)
    assert _same(m.obstacle_dist_min_m, nearest, rel=1e-12)
    assert _same(m.scan_range_mean_m, mean, rel=1e-9)
    if math.isfinite(m.obstacle_dist_min_m):
        assert m.obstacle_dist_min_m <= m.obstacle_dist_mean_m * (1 + 1e-9) + 1e-12
    else:
        assert math.isnan(m.obstacle_dist_mean_m)
    if facts.footprint is None or scan is None or len(scan) == 0 or math.isnan(nearest):
        # nothing to judge (no valid beam either): NaN, never a silent zero
        assert math.isnan(m.collision_count) and math.isnan(m.safety_violation_time_s)
    else:
        assert m.collision_count >= 0 and m.collision_count == int(m.collision_count)
        assert m.collision_count <= len(scan)
        scan_span_s = (scan.t_ns[-1] - scan.t_ns[0]) * 1e-9
        assert 0 <= m.safety_violation_time_s <= scan_span_s + 1e-9
    # goal
    goal_metrics = (
        "heading_error_mean_rad",
        "heading_error_signed_mean_rad",
        "goal_dist_min_m",
        "goal_dist_final_m",
        "spl",
        "soft_spl",
        "start_goal_distance_m",
    )
    if facts.goal is None:
        assert all(math.isnan(getattr(m, name)) for name in goal_metrics)
        assert math.isnan(m.barn_score)
    else:
        assert 0 <= m.heading_error_mean_rad <= math.pi + 1e-12
        assert abs(m.heading_error_signed_mean_rad) <= m.heading_error_mean_rad + 1e-9
        assert 0 <= m.goal_dist_min_m <= m.goal_dist_final_m
        for name in ("spl", "soft_spl"):
            value = getattr(m, name)
            assert math.isnan(value) or 0 <= value <= 1 + 1e-12, name
        # BARN: OT / clip(AT, 2 OT, 8 OT) is at most 1/2; 0 for a failure
        assert math.isnan(m.barn_score) or 0 <= m.barn_score <= 0.5 + 1e-12
    if facts.row_centerline is None:
        assert math.isnan(m.row_path_mae_m) and math.isnan(m.row_path_mse_m2)
    else:
        assert (
            m.row_path_mae_m >= 0 and m.row_path_mse_m2 >= m.row_path_mae_m**2 * (1 - 1e-9) - 1e-12
        )
    if episode.person is None:
        assert math.isnan(m.follow_heading_max_rad)
    elif math.isfinite(m.follow_heading_max_rad):
        assert m.follow_heading_mae_rad <= m.follow_heading_max_rad + 1e-12
        assert m.follow_heading_max_rad <= math.pi + 1e-12


def test_rectangle_edge_at_a_tiny_bearing_is_half_its_length_without_a_warning() -> None:
    """A beam at a subnormal bearing (sin underflows the division) is a beam straight ahead:
    its edge is L/2, and no RuntimeWarning leaks out of ``compute_metrics``."""
    pose = PoseSeries(np.array([0, 100_000_000], np.int64), np.zeros(2), np.zeros(2), np.zeros(2))
    scan = ScanSeries(
        np.array([0, 100_000_000], np.int64),
        np.array([[1.0, 2.0], [1.0, 2.0]]),
        np.array([[1e-310, math.pi / 2], [1e-310, math.pi / 2]]),
        np.array([0.05, 0.05]),
        np.array([10.0, 10.0]),
    )
    facts = EpisodeFacts(footprint=Footprint(length_m=1.0, width_m=0.5), safety_margin_m=0.6)
    episode = Episode(Path("tiny_bearing"), facts, pose, "/odom", scan=scan)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        edge = facts.footprint.signed_distance(np.array([[1.0, 1e-310]]))  # type: ignore[union-attr]
        m = compute_metrics(episode)
    assert edge[0] == pytest.approx(0.5)  # 1 m ahead, the box's front face at 0.5 m
    assert m.collision_count == 0
    assert m.safety_violation_time_s == pytest.approx(0.1)  # margin 1.0 - 0.5 <= 0.6


# --------------------------------------------------------------------------- random bags


@st.composite
def random_bag_inputs(draw: st.DrawFn) -> dict[str, object]:
    """Arguments of ``synthetic.write_episode_bag`` with random data (NaN poses included)."""
    n = draw(st.integers(1, 25))
    t_s = np.cumsum(draw(arrays(float, n, elements=st.floats(0.001, 0.5))))
    values = st.one_of(st.floats(-100, 100), st.just(math.nan))
    x, y, yaw = (draw(arrays(float, n, elements=values)) for _ in range(3))
    vx, vy, wz = (draw(arrays(float, n, elements=values)) for _ in range(3))
    track = synthetic.Track(t_s, x, y, yaw, vx, vy, wz)
    kwargs: dict[str, object] = {
        "pose_topic": draw(st.sampled_from(["/ground_truth", "/odom", "/robot/odom"])),
        "pose_type": draw(st.sampled_from(["odometry", "pose_stamped", "pose_cov"])),
        "cmd": draw(st.booleans()),
        "goal": draw(st.one_of(st.none(), points)),
        "receive_offset_ns": draw(st.integers(-(10**12), 10**12)),
    }
    kwargs["also_odom"] = kwargs["pose_topic"] != "/odom" or kwargs["pose_type"] == "odometry"
    if draw(st.booleans()):
        beams = draw(st.integers(1, 30))
        kwargs["scans"] = [
            draw(
                arrays(
                    np.float32,
                    beams,
                    elements=scan_values.map(lambda v: v if not math.isfinite(v) else min(v, 1e30)),
                )
            )
            for _ in range(n)
        ]
    if draw(st.booleans()):
        kwargs["facts"] = {"footprint": {"radius_m": draw(st.floats(0.05, 1.0))}, "agent": "random"}
    return {"track": track, **kwargs}


_NAN2 = np.array([math.nan, math.nan])


@BAGS
@given(random_bag_inputs())
@example(
    {  # every pose NaN: found by this test (reader._order indexed an empty array)
        "track": synthetic.Track(
            [0.5, 1.0], np.zeros(2), _NAN2, _NAN2, np.zeros(2), np.zeros(2), np.zeros(2)
        ),
        "pose_topic": "/ground_truth",
        "pose_type": "odometry",
        "cmd": False,
        "goal": None,
        "receive_offset_ns": 0,
        "also_odom": True,
    }
)
def test_reading_and_judging_random_bags_never_raises_anything_but_metrics_errors(
    inputs: dict[str, object],
) -> None:
    with tempfile.TemporaryDirectory() as tmp:
        bag = synthetic.write_episode_bag(Path(tmp) / "bag", **inputs)  # type: ignore[arg-type]
        files_before = {p: p.stat().st_size for p in bag.iterdir()}
        refused = None
        try:
            episode = read_episode(bag)
        except MetricsError as err:
            assert str(bag) in str(err)
            episode, refused = None, err
        result = judge_bag(bag)
        assert {p: p.stat().st_size for p in bag.iterdir()} == files_before
    track = inputs["track"]
    usable = np.isfinite(np.column_stack([track.x, track.y, track.yaw])).all(axis=1)  # type: ignore[attr-defined]
    if isinstance(refused, CorruptBagError):  # two tracks, or sustained impossible speeds
        assert result.error == str(refused) and result.metrics is None
        kept = PoseSeries(*(np.round(track.t_s * 1e9).astype(np.int64)[usable],  # type: ignore[attr-defined]
                            track.x[usable], track.y[usable], track.yaw[usable]))  # type: ignore[attr-defined]
        with pytest.raises(CorruptBagError):
            check_one_track(kept, None, "/ground_truth")
    elif episode is None:
        assert result.error and result.metrics is None
        assert int(usable.sum()) < 2
    else:
        assert result.error == ""
        assert result.metrics is not None and result.metrics.n_poses == int(usable.sum()) >= 2
        assert len(episode.pose) == int(usable.sum())
        assert np.all(np.diff(episode.pose.t_ns) > 0)
        if not usable.all():
            assert any("NaN" in w for w in episode.warnings)
