"""Shortest collision-free paths against analytic answers: the straight line in open space, the
taut path through a wall's gap (tangents and arcs around the inflated corner), no path, a
narrow gap a larger robot cannot pass, snapped ends, the grid's corner rule."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pic4rl_base.errors import ConfigError
from pic4rl_sim.engine.paths import PathPlanner, clearance_grid, planner_for, shortest_path_length
from pic4rl_sim.engine.worlds.spec import Box, Cylinder, WorldSpec

OPEN = WorldSpec("open", (-5.0, -5.0, 5.0, 5.0))
RADIUS, THICKNESS, GAP_LOW = 0.25, 0.1, 1.0  # the wall: x in ±0.05, solid below y = 1, above 2


def gap_world(gap_high: float = 2.0) -> WorldSpec:
    """A wall along x = 0 across the arena with one gap, y in (GAP_LOW, gap_high)."""
    lower = Box(0.0, (-3.0 + GAP_LOW) / 2, THICKNESS, GAP_LOW + 3.0, 1.0)
    upper = Box(0.0, (gap_high + 3.0) / 2, THICKNESS, 3.0 - gap_high, 1.0)
    return WorldSpec("gap", (-3.0, -3.0, 3.0, 3.0), boxes=(lower, upper))


def around_the_corner(x: float, y: float) -> float:
    """The shortest path from (x, y) to (-x, y) (x < 0, below the gap) for a disc of RADIUS:
    tangent to the circle of RADIUS about the wall's corner (-t/2, GAP_LOW), its arc up to the
    top, straight across the wall's thickness, and the mirror image."""
    cx, cy = -THICKNESS / 2, GAP_LOW
    d = math.hypot(x - cx, y - cy)
    tangent = math.sqrt(d * d - RADIUS * RADIUS)
    toward_start = math.atan2(y - cy, x - cx) % (2 * math.pi)
    touch = toward_start - math.acos(RADIUS / d)  # the tangent point's angle about the corner
    return 2 * (tangent + RADIUS * (touch - math.pi / 2)) + THICKNESS


@settings(max_examples=40, deadline=None)
@given(st.tuples(*[st.floats(-4.9, 4.9)] * 4))
def test_open_space_is_the_straight_line(points: tuple[float, float, float, float]) -> None:
    """No obstacle: the taut path is the straight segment (the 8-connected grid alone would be
    up to 8 % longer)."""
    start, goal = points[:2], points[2:]
    found = shortest_path_length(OPEN, start, goal, robot_radius_m=0.3)
    assert found == pytest.approx(math.dist(start, goal), abs=1e-9)


@pytest.mark.parametrize("resolution_m", [0.02, 0.05, 0.1])
@pytest.mark.parametrize("start", [(-2.0, 0.0), (-2.5, -2.0), (-1.0, 0.5), (-0.6, -2.5)])
def test_a_wall_with_a_gap_gives_the_taut_detour(start: tuple[float, float],
                                                resolution_m: float) -> None:
    """Through the gap: within a fifth of a cell of the analytic length. The taut path bends
    where the interpolated clearance meets the radius, so it can be a little shorter."""
    world = gap_world()
    goal = (-start[0], start[1])
    want = around_the_corner(*start)
    found = PathPlanner(world, robot_radius_m=RADIUS,
                        resolution_m=resolution_m).length(start, goal)
    assert found == pytest.approx(want, abs=0.2 * resolution_m)
    assert found > math.dist(start, goal) + 0.1  # a real detour


def test_a_gap_narrower_than_the_robot_is_no_path() -> None:
    """A 0.4 m gap: a 0.15 m disc passes, a 0.25 m disc does not (inf), nor does any disc when
    the goal is walled in."""
    world = gap_world(gap_high=GAP_LOW + 0.4)
    start, goal = (-2.0, 0.0), (2.0, 0.0)
    assert math.isfinite(shortest_path_length(world, start, goal, robot_radius_m=0.15))
    assert shortest_path_length(world, start, goal, robot_radius_m=0.25) == math.inf
    box = WorldSpec("box", (-3.0, -3.0, 3.0, 3.0), boxes=tuple(
        Box(x, y, sx, sy, 1.0) for x, y, sx, sy in ((2, 1, 2.2, 0.2), (2, -1, 2.2, 0.2),
                                                    (1, 0, 0.2, 2.2), (3, 0, 0.2, 2.2))))
    assert shortest_path_length(box, start, goal, robot_radius_m=0.1) == math.inf


def test_max_length_stops_the_search_and_the_cache_keeps_exact_answers() -> None:
    planner = PathPlanner(gap_world(), robot_radius_m=RADIUS)
    start, goal = (-2.0, 0.0), (2.0, 0.0)
    assert planner.length(start, goal, max_length_m=4.5) == math.inf  # the detour is 4.75 m
    full = planner.length(start, goal)
    assert full == pytest.approx(around_the_corner(*start), abs=0.01)
    assert planner.length(start, goal, max_length_m=4.5) == math.inf  # from the cache
    assert planner.length(start, goal, max_length_m=5.0) == full


def test_an_end_inside_the_inflation_is_joined_to_the_nearest_free_cell() -> None:
    """A goal 0.1 m from a cylinder's surface, robot radius 0.3: the path ends with the
    straight step out of the inflated disc, so it is the straight line plus at most a cell."""
    world = WorldSpec("pillar", (-3.0, -3.0, 3.0, 3.0), cylinders=(Cylinder(2.0, 0.0, 0.5, 1.0),))
    goal = (1.4, 0.0)  # clearance 0.1 < 0.3
    found = shortest_path_length(world, (-2.0, 0.0), goal, robot_radius_m=0.3)
    assert 3.4 <= found <= 3.4 + 0.05 * math.sqrt(2)


def test_no_corner_cutting_between_diagonal_cells() -> None:
    """Two obstacles touching at a corner leave the diagonal cells free but the grid refuses
    the step between them (and the disc does not fit through the corner): the path goes
    round."""
    world = WorldSpec("corner", (-2.0, -2.0, 2.0, 2.0), boxes=(
        Box(-0.5, 0.5, 1.0, 1.0, 1.0), Box(0.5, -0.5, 1.0, 1.0, 1.0)))
    planner = PathPlanner(world, robot_radius_m=0.01, resolution_m=0.1)
    # The only meeting point of the two free quadrants is the obstacles' shared corner.
    assert planner.length((-1.0, -1.0), (1.0, 1.0)) > math.dist((-1, -1), (1, 1)) + 1.0


def test_planners_are_built_once_per_world_radius_and_resolution() -> None:
    world = gap_world()
    first = planner_for(world, robot_radius_m=0.2)
    assert planner_for(world, robot_radius_m=0.2) is first
    assert planner_for(world, robot_radius_m=0.3) is not first


def test_a_worlds_clearance_is_computed_once_for_every_radius() -> None:
    """The planners of one world for two radii threshold the same clearance field (computed
    once, the world's exact clearance at the cell centres); another world, even an equal one,
    or another resolution gets its own."""
    world = gap_world()
    grid = clearance_grid(world, 0.05)
    assert grid.shape == (120, 120) and not grid.flags.writeable
    assert clearance_grid(world, 0.05) is grid
    np.testing.assert_array_equal(grid[0, :3], world.clearance(np.array(
        [[-2.975, -2.975], [-2.925, -2.975], [-2.875, -2.975]])))
    small, large = PathPlanner(world, robot_radius_m=0.1), PathPlanner(world, robot_radius_m=0.3)
    assert clearance_grid(world, 0.05) is grid
    assert small.free.sum() > large.free.sum()  # the same field, thresholded apart
    other = gap_world()
    assert clearance_grid(other, 0.05) is not grid
    np.testing.assert_array_equal(clearance_grid(other, 0.05), grid)
    assert clearance_grid(world, 0.1).shape == (60, 60)


def test_a_repeated_query_reuses_its_path(monkeypatch: pytest.MonkeyPatch) -> None:
    """The runs of one start-goal pair ask for the same path: searched once, each caller gets
    its own copy; another goal is searched anew."""
    from pic4rl_sim.engine import paths

    searches = []
    real = paths.grid_search
    monkeypatch.setattr(paths, "grid_search", lambda *a, **k: searches.append(a[2:4]) or real(
        *a, **k))
    planner = PathPlanner(gap_world(), robot_radius_m=RADIUS)
    first = planner.path((-2.0, -2.0), (2.0, -2.0))
    assert first is not None and len(first) > 2 and len(searches) == 1
    first[:] = 0.0  # the caller's copy
    again = planner.path((-2.0, -2.0), (2.0, -2.0))
    assert again is not None and len(searches) == 1 and again[0].tolist() == [-2.0, -2.0]
    assert planner.length((-2.0, -2.0), (2.0, -2.0)) == pytest.approx(
        float(np.hypot(*np.diff(again, axis=0).T).sum()))
    planner.path((-2.0, -2.0), (2.0, -1.5))
    assert len(searches) == 2


@pytest.mark.parametrize(("key", "value"), [("robot_radius_m", -0.1),
                                            ("resolution_m", 0.0)])
def test_bad_parameters_and_points_outside_are_refused(key: str, value: float) -> None:
    kwargs = {"robot_radius_m": 0.2, "resolution_m": 0.05, key: value}
    with pytest.raises(ConfigError, match=f"paths.{key}"):
        PathPlanner(OPEN, **kwargs)
    with pytest.raises(ValueError, match=r"start \(6.000, 0.000\) is outside the bounds"):
        shortest_path_length(OPEN, (6.0, 0.0), (0.0, 0.0), robot_radius_m=0.2)


def test_the_taut_path_keeps_the_clearance() -> None:
    """Every point of the returned path is at least the radius (less half a cell's sampling
    step) from the obstacles, checked with the world's exact clearance."""
    world = gap_world()
    points = PathPlanner(world, robot_radius_m=RADIUS).path((-2.5, -2.0), (2.0, 2.5))
    assert points is not None and len(points) >= 3
    t = np.linspace(0, 1, 200)[:, None]
    dense = np.vstack([a + (b - a) * t for a, b in zip(points, points[1:])])
    assert world.clearance(dense).min() >= RADIUS - 0.025
