"""The explore task's classical references: frontier-based exploration and a random-walk floor.

``FrontierExplorer`` is Yamauchi's (1997): it integrates its scans into a seen grid, as the task
and the metrics do (``pic4rl_bridge.perception.frontiers.integrate_scan``), and marks their
returns on the mapless explorer's occupancy grid (``pic4rl_bridge.baselines.explorer_plan``);
it drives to the nearest reachable frontier (a known free cell next to an unseen one, reached
through seen cells clear of the inflated obstacles, on a ``FRONTIER_CELL_M`` grid), by the
explorer's shortest path on its own grid and the planner's pursuit law
(``pic4rl_bridge.control.pursuit``), keeping the plan's full margin even in a narrow door (it
turns in place at its targets, and hits a door jamb passed at the narrow margin), and picks
the next frontier on arrival: when within ``ARRIVE_M`` of the target, or when the target is no
longer a frontier (seen round it). A
target the explorer's plan finds no way to (its fallback, straight on through what was seen),
or one it has not come ``PROGRESS_M`` nearer to in ``PATIENCE_STEPS``, is given up for the rest
of the episode. With no frontier left it stops (and looks again every ``IDLE_STEPS``). A
return ahead within the circumscribed radius plus ``GUARD_M`` stops its forward motion (it
only turns): what its grid had not seen yet, a corner its pursuit cut.

``RandomWalk`` drives straight at full speed until an obstacle is within ``STOP_M`` of its
footprint's circumscribed disc ahead, then turns in place, a random way, for a random 0.5 to 3
s; its draws come from ``seed`` (given when made; ``reset`` does not reseed, so a run of
episodes is one sequence). Both read only the scan and the pose (no map), as an agent does.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from pic4rl_base.seen_area import SeenGrid

from ..control.actions import normalized_action
from ..control.pursuit import pursuit_command
from ..perception.frontiers import frontier_cells, grow, integrate_scan, neighbours
from ..readings.frame import SensorFrame
from ..robot_info import RobotInfo
from ..settings.baselines import ExplorerConfig
from .explorer_plan import ExplorerPlan

#: Cell size (m) of the grid the frontiers are searched on (coarser than the seen grid's).
FRONTIER_CELL_M = 0.1
ARRIVE_M = 0.4  # a target this near is reached
PROGRESS_M = 0.2  # ... and one not come this much nearer to
PATIENCE_STEPS = 60  # in this many steps is given up
_BAN_M = 0.5  # frontier cells this near a given-up target are not picked again
GUARD_M = 0.1  # the frontier explorer drives no nearer than this to a return ahead
IDLE_STEPS = 10  # with no frontier found, the search is made again this many steps later
_TRIES = 3  # targets tried in one step before driving to the last (its plan straight on)
STOP_M = 0.35  # the random walk turns when an obstacle is this near its disc, ahead


class FrontierExplorer:
    """Frontier-based exploration (see the module's docstring)."""

    def __init__(self, robot: RobotInfo, config: ExplorerConfig | None = None, *,
                 resolution_m: float = 0.05, lookahead_m: float = 0.4,
                 turn_in_place_rad: float = 0.8) -> None:
        config = config or ExplorerConfig()
        # no squeezing past a door jamb at the narrow margin: it turns in place at its targets
        self.robot = robot
        self.config = dataclasses.replace(
            config, narrow_margin_m=max(config.narrow_margin_m, config.margin_m))
        self.plan = ExplorerPlan(robot, self.config)
        self.seen = SeenGrid(resolution_m)
        self.lookahead_m, self.turn_in_place_rad = lookahead_m, turn_in_place_rad
        cap = self.config.max_linear_m_s
        self.max_linear_m_s = min(cap, robot.max_linear_m_s) if cap > 0 else robot.max_linear_m_s
        self.reset()

    def reset(self) -> None:
        """Forget the grids, the target and the given-up targets (a new episode)."""
        self.plan.reset()
        self.seen = SeenGrid(self.seen.resolution_m)
        self.target: tuple[float, float] | None = None
        self._frontier: tuple[float, float] | None = None  # the frontier cell beside it
        self.targets = 0  # frontiers picked this episode
        self._banned: list[tuple[float, float]] = []
        self._best_m, self._since = math.inf, 0

    def action(self, frame: SensorFrame) -> np.ndarray:
        return normalized_action(self.robot, *self.command(frame))

    def command(self, frame: SensorFrame) -> tuple[float, float]:
        """(v, ω) (m/s, rad/s) for ``frame``."""
        self.observe(frame)
        return self.steer(frame, self._arrived(frame))

    def observe(self, frame: SensorFrame) -> None:
        """Integrate ``frame``'s scan into the seen grid and the plan's occupancy grid."""
        if frame.scan is not None:
            integrate_scan(self.seen, frame.scan, frame.pose)
        self.plan.observe(frame)

    def pick(self, frame: SensorFrame) -> tuple[tuple[float, float],
                                                tuple[float, float]] | None:
        """The next target and its frontier cell (``nearest_frontier``'s); ``None``: none."""
        return self.nearest_frontier(frame)

    def steer(self, frame: SensorFrame, pick: bool) -> tuple[float, float]:
        """(v, ω) toward the target, a new one ``pick``ed first (up to ``_TRIES`` while the
        plan finds no way to the one picked)."""
        for _ in range(_TRIES):
            if pick:
                found = self.pick(frame)
                self.target, self._frontier = found or (None, None)
                self.targets += found is not None
                self._best_m, self._since = math.inf, 0 if found else 1
            if self.target is None:
                return 0.0, 0.0
            path, s = self.plan.update(frame, self.target)
            # the plan's fallback, straight on through what was seen: no way there
            pick = len(path) == 2 and not self.plan.visible(path[0], path[1:])[0]
            if not pick:
                break
            self._banned.append(self.target)
        v, w = pursuit_command(self.robot, frame.pose, path, s, self.plan.visible,
                               lookahead_m=self.lookahead_m,
                               turn_in_place_rad=self.turn_in_place_rad,
                               max_linear_m_s=self.max_linear_m_s)
        return (0.0 if _too_near(frame, self.robot) else v), w

    def _arrived(self, frame: SensorFrame) -> bool:
        """Whether to pick a new target: none yet (searched again every ``IDLE_STEPS`` while
        none is found), reached, no longer a frontier, or given up."""
        if self.target is None:
            due = self._since == 0 or self._since >= IDLE_STEPS
            self._since += 1
            return due
        d = math.hypot(self.target[0] - frame.pose.x, self.target[1] - frame.pose.y)
        if d <= ARRIVE_M:
            return True
        step = FRONTIER_CELL_M
        x, y = self._frontier or self.target
        round_it = np.array([[x + step, y], [x - step, y], [x, y + step], [x, y - step]])
        if self.seen.seen_at(round_it).all():
            return True
        if d < self._best_m - PROGRESS_M:
            self._best_m, self._since = d, 0
            return False
        self._since += 1
        if self._since >= PATIENCE_STEPS:
            self._banned.append(self.target)
            return True
        return False

    def search_grids(self, frame: SensorFrame) -> FrontierGrids:
        """The frontier search's grids round what was seen and the robot (``FRONTIER_CELL_M``
        cells): the frontier cells (beyond ``ARRIVE_M`` of the robot, none near a given-up
        target), the cells clear of the obstacles inflated by the circumscribed radius (whole
        cells, at most), the robot's start cells among them (a robot nearer a wall starts from
        the nearest clear cells) and the cells a robot may stand on, clear of the plan's
        margin too."""
        res = FRONTIER_CELL_M
        xmin, ymin, xmax, ymax = self.seen.bounds_m
        lo = np.floor(np.array([min(xmin, frame.pose.x), min(ymin, frame.pose.y)]) / res) - 1
        hi = np.floor(np.array([max(xmax, frame.pose.x), max(ymax, frame.pose.y)]) / res) + 2
        nx, ny = (hi - lo).astype(int)
        xs, ys = (lo[0] + np.arange(nx) + 0.5) * res, (lo[1] + np.arange(ny) + 0.5) * res
        gx, gy = np.meshgrid(xs, ys)
        seen = self.seen.seen_at(np.column_stack((gx.ravel(), gy.ravel()))).reshape(ny, nx)
        occupied = np.zeros((ny, nx), dtype=bool)
        cells = np.floor(self.plan.grid.centres() / res).astype(np.int64) - lo.astype(np.int64)
        inside = (cells >= 0).all(axis=1) & (cells[:, 0] < nx) & (cells[:, 1] < ny)
        occupied[cells[inside, 1], cells[inside, 0]] = True
        frontier = frontier_cells(seen, occupied)
        robot_d = np.hypot(gx - frame.pose.x, gy - frame.pose.y)
        frontier &= robot_d > ARRIVE_M
        for bx, by in self._banned:
            frontier &= np.hypot(gx - bx, gy - by) > _BAN_M
        radius = self.robot.footprint.bounding_radius_m
        inflated = occupied
        for k in range(math.floor(radius / res)):
            inflated = neighbours(inflated, diagonal=k % 2 == 1)
        clear = seen & ~inflated
        start = robot_d <= res
        near = seen & ~neighbours(occupied, diagonal=True)
        if not (start & clear).any():
            start, _ = grow(start, near | start, diagonal=True, stop=clear)
        wide = inflated
        for k in range(math.ceil((radius + self.config.margin_m) / res) - math.floor(radius / res)):
            wide = neighbours(wide, diagonal=k % 2 == 1)
        return FrontierGrids(gx, gy, seen, occupied, frontier, clear, start, wide, robot_d)

    def nearest_frontier(self, frame: SensorFrame) -> tuple[tuple[float, float],
                                                           tuple[float, float]] | None:
        """(the centre of the cell beside it, of the frontier cell) first reached growing from
        the robot through the ``search_grids``' clear cells; ``None``: none."""
        g = self.search_grids(frame)
        region, touched = grow(g.start, g.clear | g.start, diagonal=True, stop=g.frontier)
        if not touched.any():
            return None
        return stand_beside(g, region, touched)


@dataclasses.dataclass(frozen=True)
class FrontierGrids:
    """``FrontierExplorer.search_grids``: cell centres (m) and boolean grids, rows along y."""

    gx: np.ndarray
    gy: np.ndarray
    seen: np.ndarray
    occupied: np.ndarray
    frontier: np.ndarray
    clear: np.ndarray  # seen, clear of the obstacles inflated by the circumscribed radius
    start: np.ndarray  # the robot's cells the search grows from
    wide: np.ndarray  # the obstacles inflated by the radius and the plan's margin
    robot_d: np.ndarray  # each cell's distance (m) from the robot


def stand_beside(g: FrontierGrids, region: np.ndarray, front: np.ndarray) -> tuple[
        tuple[float, float], tuple[float, float]]:
    """(the target, the frontier cell beside it) for the frontier cells ``front`` the search's
    ``region`` reaches: the cell of the region within three cells of them that a robot can
    stand on (clear of the plan's margin too, else of the radius; else a frontier cell) nearest
    the robot, and the cell of ``front`` nearest that."""
    around = front
    for k in range(3):
        around = neighbours(around, diagonal=k % 2 == 1)
    beside = region & ~g.wide & around
    if not beside.any():
        beside = region & g.clear & neighbours(front, diagonal=True)
    if not beside.any():
        beside = front
    gx, gy = g.gx.ravel(), g.gy.ravel()
    best = np.flatnonzero(beside.ravel())[int(np.argmin(g.robot_d[beside]))]
    x, y = float(gx[best]), float(gy[best])
    cells = np.flatnonzero(front.ravel())
    nearest = cells[int(np.argmin(np.hypot(gx[cells] - x, gy[cells] - y)))]
    return (x, y), (float(gx[nearest]), float(gy[nearest]))


class RandomWalk:
    """The random-walk floor (see the module's docstring)."""

    def __init__(self, robot: RobotInfo, *, seed: int = 0) -> None:
        self.robot = robot
        self.rng = np.random.default_rng(seed)
        self.reset()

    def reset(self) -> None:
        """End any turn (a new episode); the draws go on."""
        self._turn_steps, self._turn_sign = 0, 1.0

    def action(self, frame: SensorFrame) -> np.ndarray:
        r = self.robot
        if self._turn_steps == 0 and self._blocked(frame):
            dt = r.control_dt_s
            self._turn_steps = int(self.rng.integers(round(0.5 / dt), round(3.0 / dt) + 1))
            self._turn_sign = float(self.rng.choice([-1.0, 1.0]))
        if self._turn_steps > 0:
            self._turn_steps -= 1
            return normalized_action(r, 0.0, self._turn_sign * r.max_angular_rad_s)
        return normalized_action(r, r.max_linear_m_s, 0.0)

    def _blocked(self, frame: SensorFrame) -> bool:
        """Whether a return lies ahead within ``STOP_M`` of the circumscribed disc."""
        if frame.scan is None:
            return False
        points = frame.scan.points()
        radius = self.robot.footprint.bounding_radius_m
        ahead = (points[:, 0] > 0) & (np.abs(points[:, 1]) < radius)
        return bool(ahead.any() and points[ahead, 0].min() < radius + STOP_M)


def _too_near(frame: SensorFrame, robot: RobotInfo) -> bool:
    """Whether a return ahead (x > 0 in the base frame) lies within the circumscribed radius
    plus ``GUARD_M`` of the robot's centre: it stops there and only turns."""
    if frame.scan is None:
        return False
    x, y = frame.scan.points().T
    reach = robot.footprint.bounding_radius_m + GUARD_M
    return bool(((x > 0) & (np.hypot(x, y) < reach)).any())
