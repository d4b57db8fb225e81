"""Raytrace clearing (``OccupancyGrid.clear_scan``, the explorer's ``clear_free``): a cell a
scan marked is freed by a later beam passing through it, not by one ending on or short of it;
+inf frees up to the range limit, NaN nothing; the mount places the beams. With the mode on
a walking disc leaves no trail and the explorer's clearance field equals one built anew from
the grid; with it off (the default) the grid is bit for bit the marks of every return."""

from __future__ import annotations

import math

import numpy as np
from pic4rl_base.geometry import Footprint, Pose2D

from pic4rl_bridge.baselines.explorer_plan import ExplorerPlan, _Clearance
from pic4rl_bridge.perception.occupancy import OccupancyGrid
from pic4rl_bridge.readings.frame import ScanData, SensorFrame
from pic4rl_bridge.robot_info import RobotInfo
from pic4rl_bridge.settings.baselines import ExplorerConfig
from pic4rl_sim.engine.geometry import Twist2D

BEAMS = 360
ROBOT = RobotInfo(name="disc", footprint=Footprint(radius_m=0.2), omni=False,
                  min_linear_m_s=0.0, max_linear_m_s=0.5, max_angular_rad_s=1.0,
                  max_lateral_m_s=0.0, control_dt_s=0.1)


def _scan(beams: dict[int, float], mount: Pose2D = Pose2D(0.0, 0.0, 0.0),
          fill: float = np.inf) -> ScanData:
    """A full turn of 1° beams from -180°, ``fill`` (default: nothing in range) but ``beams``
    (index: range)."""
    ranges = np.full(BEAMS, fill, np.float32)
    for k, r in beams.items():
        ranges[k] = r
    return ScanData(ranges, -math.pi, 2 * math.pi / BEAMS, 0.05, 10.0, mount)


AHEAD = BEAMS // 2  # the beam along +x of the base frame


def test_a_later_beam_through_a_marked_cell_frees_it():
    grid, pose = OccupancyGrid(0.05), Pose2D(0.0, 0.0, 0.0)
    grid.mark_scan(_scan({AHEAD: 1.21}), pose)
    assert grid.cells.tolist() == [[24, 0]]
    freed = grid.clear_scan(_scan({AHEAD: 3.0}), pose)
    assert freed.tolist() == [[24, 0]] and len(grid.cells) == 0
    assert not grid.occupied(np.array([[1.21, 0.01]]))[0]


def test_a_cell_on_or_behind_the_return_stays():
    grid, pose = OccupancyGrid(0.05), Pose2D(0.0, 0.0, 0.0)
    grid.mark_scan(_scan({AHEAD: 2.01}), pose)  # the cell [2, 2.05) x [0, 0.05)
    # returns short of it (something nearer now), and on its face a cell nearer
    assert len(grid.clear_scan(_scan({}, fill=1.0), pose)) == 0
    assert len(grid.clear_scan(_scan({}, fill=1.98), pose)) == 0
    # the beams at ±2° pass 7 cm off the axis at 2 m, beside the cell: those within end short
    near = {k: 1.0 for k in range(AHEAD - 1, AHEAD + 2)}
    assert len(grid.clear_scan(_scan(near), pose)) == 0
    assert grid.cells.tolist() == [[40, 0]]
    assert len(grid.clear_scan(_scan({}, fill=2.2), pose)) == 1


def test_inf_frees_to_the_range_limit_and_nan_frees_nothing():
    grid, pose = OccupancyGrid(0.05), Pose2D(0.0, 0.0, 0.0)
    grid.mark_scan(_scan({AHEAD: 1.21, 0: 9.99}), pose)  # ahead, and behind near the limit
    nan = _scan({})
    nan.ranges[:] = np.nan
    assert len(grid.clear_scan(nan, pose)) == 0
    freed = grid.clear_scan(_scan({}), pose)  # +inf everywhere: free up to 10 m less 2 cells
    assert freed.tolist() == [[24, 0]] and grid.cells.tolist() == [[-200, -1]]


def test_the_beams_leave_from_the_mount_turned_with_the_pose():
    grid, mount = OccupancyGrid(0.05), Pose2D(0.5, 0.0, math.pi)  # 0.5 m ahead, backwards
    pose = Pose2D(1.0, 2.0, math.pi / 2)  # facing +y: the sensor at (1, 2.5) looking -y
    grid.mark_scan(_scan({AHEAD: 1.01}, mount), pose)
    assert grid.cells.tolist() == [[19, 29]]  # (1.0, 1.49)
    # 1.03 m from the sensor (0.53 m from the base): beams of 0.9 m end short of it
    assert len(grid.clear_scan(_scan({}, mount, fill=0.9), pose)) == 0
    assert grid.clear_scan(_scan({}, mount, fill=1.2), pose).tolist() == [[19, 29]]


def _room_with_disc(origin: np.ndarray, centre: np.ndarray, radius: float = 0.3,
                    half: float = 4.0) -> ScanData:
    """A scan from ``origin`` (heading +x) in a square room of ``half`` m round (0, 0) with a
    disc at ``centre``."""
    angles = -math.pi + np.arange(BEAMS) * 2 * math.pi / BEAMS
    d = np.column_stack((np.cos(angles), np.sin(angles)))
    with np.errstate(divide="ignore", invalid="ignore"):
        walls = np.min(np.where(d != 0, (np.sign(d) * half - origin) / d, np.inf), axis=1)
    rel = centre - origin
    along = d @ rel
    miss = along ** 2 - (rel @ rel - radius ** 2)
    disc = np.where((miss >= 0) & (along > 0), along - np.sqrt(np.maximum(miss, 0.0)), np.inf)
    return ScanData(np.minimum(walls, disc).astype(np.float32), -math.pi,
                    2 * math.pi / BEAMS, 0.05, 10.0)


def _walk(clear_free: bool) -> tuple[ExplorerPlan, list[ScanData]]:
    """A disc walking across the room past the robot at the origin, the plan kept to a goal
    beyond; the explorer's plan and the scans."""
    plan = ExplorerPlan(ROBOT, ExplorerConfig(clear_free=clear_free))
    pose, scans = Pose2D(0.0, 0.0, 0.0), []
    for k, y in enumerate(np.linspace(-2.5, 2.5, 26)):
        scans.append(_room_with_disc(np.zeros(2), np.array([1.5, y])))
        plan.update(SensorFrame(k, pose, Twist2D(), goal=(3.0, 0.0), scan=scans[-1]))
    return plan, scans


def _trail(grid: OccupancyGrid) -> int:
    """The occupied cells the disc's front swept across the way (1.15-1.5 m ahead, within
    1.5 m of the axis; its last place is 2.5 m to the left)."""
    xy = grid.centres()
    return int(((xy[:, 0] > 1.15) & (xy[:, 0] < 1.5) & (np.abs(xy[:, 1]) < 1.5)).sum())


def _field_anew(plan: ExplorerPlan) -> _Clearance:
    field = plan._field
    return _Clearance(plan.grid.cells, field.lo, field.hi, field.res, field.cap_m)


def test_off_the_grid_is_every_return_marked_bit_for_bit():
    plan, scans = _walk(clear_free=False)
    marks = OccupancyGrid(plan.grid.resolution_m)
    for scan in scans:
        marks.mark_scan(scan, Pose2D(0.0, 0.0, 0.0))
    assert np.array_equal(plan.grid.cells, marks.cells)
    assert _trail(plan.grid) > 30
    assert np.array_equal(plan._field.clear, _field_anew(plan).clear)


def test_on_a_walking_disc_leaves_no_trail_and_the_field_matches_a_new_one():
    plan, scans = _walk(clear_free=True)
    last = OccupancyGrid(plan.grid.resolution_m)
    last.mark_scan(scans[-1], Pose2D(0.0, 0.0, 0.0))
    # the walls and the disc's last place stay; of the trail across the way nothing
    assert set(map(tuple, last.cells)) <= set(map(tuple, plan.grid.cells))
    assert _trail(plan.grid) == 0
    fresh = _field_anew(plan)
    assert np.array_equal(plan._field.clear, fresh.clear)
    assert plan._field.at(np.array([[1.3, 0.0]]))[0] == np.float32(fresh.cap_m)
