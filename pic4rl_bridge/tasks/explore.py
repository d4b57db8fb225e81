"""explore: see as much of an unknown world's floor as the time budget allows, without colliding.

From LiDAR (``ExploreLidar-v0``), a depth camera (``ExploreDepth-v0``: its image's pseudo-scan,
every row's nearest obstacle per column, the floor's pixels dropped) or both (``sensors:
[lidar, depth]``): the env's observed sensors (``occupancy.sensed_scans``).

There is no goal: the simulator still draws one with each start (its sampler's pairs), and
the task reads none of it (its context's goal is ``None``, so the bag's facts carry none).
What the robot has seen is its own scans counted by a ``pic4rl_base.seen_area.SeenTrack`` per
observed sensor, on one grid at the metrics' resolution (``pic4rl_metrics``'
``SEEN_RESOLUTION_M``), kept in the episode's context (``SeenBySensors``): the count the
metrics make of the episode's bag, the same scans thinned the same way, so the reward is the
bags' area seen, live (``reward.area`` times the m² newly seen this step), and an episode ended
at its target reads at least that coverage from its bag. A bag holds the LiDAR's scans only
(not the depth pseudo-scan), so that holds for the LiDAR alone; from depth, the bag's area is
the LiDAR's the sim still runs for the collision check, the env's the camera's. Add
``reward.collision`` on the collision that ends the episode. The episode also
ends, as a goal, once the area seen reaches ``explore.coverage_target`` of the world's free
area: the floor (clearance > 0) connected to the start, on the simulated world's 5 cm
clearance grid (``pic4rl_sim.engine.paths.clearance_grid``); it is the bag's
``free_area_m2`` fact, from which the metrics give coverage in %. On a real robot there is no
world: no target and no fact, the area in m² only.

The observation is a flat vector: the sectors (``lidar.*``) of ``sensor``'s scan (the LiDAR's,
or the depth pseudo-scan's: beyond the camera's field of view, ``lidar.clip_m``; m, or /
``lidar.clip_m`` normalised), the
last action (2) and a crop of the seen grid, ``explore.crop_px`` square pixels of
``explore.crop_cell_m`` round the robot, heading up (row 0 farthest ahead, column 0 farthest
left), 1 where the grid cell at the pixel's centre is seen.
"""

from __future__ import annotations

import math
from typing import Any

import gymnasium as gym
import numpy as np

from pic4rl_base.geometry import Pose2D
from pic4rl_base.seen_area import SeenGrid, SeenTrack
from pic4rl_metrics.contract import Outcome
from pic4rl_metrics.core.tasks.seen import SEEN_RESOLUTION_M
from pic4rl_sim.engine.geometry import Twist2D
from pic4rl_sim.engine.paths import clearance_grid

from ..config import EnvConfig
from ..control.actions import planar_action_space, planar_command
from ..perception.collision import assess
from ..perception.frontiers import component, scan_beams
from ..perception.observations import clipped_action, lidar_sectors
from ..perception.occupancy import sensed_scans
from ..readings.frame import SensorFrame
from ..robot_info import RobotInfo
from ..settings.observations import OBSERVED_TABLE
from ..settings.tasks import ExploreReward
from .base import EpisodeContext, Judgement, Task

#: Cell size (m) of the world's free-area grid (the planner's).
FREE_RESOLUTION_M = 0.05


def free_area_m2(world: Any, start: tuple[float, float]) -> float:
    """The world's free floor (m²) that can be seen from ``start``: the cells of its clearance
    grid with clearance > 0 that are 4-connected to the start's cell (a start inside an obstacle
    counts from the nearest free cell)."""
    clear = clearance_grid(world, FREE_RESOLUTION_M)
    xmin, ymin = world.bounds[:2]
    ny, nx = clear.shape
    ix = min(max(int((start[0] - xmin) / FREE_RESOLUTION_M), 0), nx - 1)
    iy = min(max(int((start[1] - ymin) / FREE_RESOLUTION_M), 0), ny - 1)
    return float(np.count_nonzero(component(clear > 0, (iy, ix)))) * FREE_RESOLUTION_M**2


def seen_crop(grid: SeenGrid, pose: Pose2D, size: int, cell_m: float) -> np.ndarray:
    """The egocentric crop (size × size, float32, 1 seen, 0 not) of pixels ``cell_m`` wide
    round ``pose``, heading up, each the grid's cell at the pixel's centre."""
    ahead = (0.5 * size - 0.5 - np.arange(size)) * cell_m  # row r: this far ahead
    left = (0.5 * size - 0.5 - np.arange(size)) * cell_m  # column k: this far left
    fwd, lat = np.meshgrid(ahead, left, indexing="ij")
    c, s = math.cos(pose.yaw), math.sin(pose.yaw)
    xy = np.column_stack(((pose.x + c * fwd - s * lat).ravel(),
                          (pose.y + s * fwd + c * lat).ravel()))
    return grid.seen_at(xy).reshape(size, size).astype(np.float32)


class SeenBySensors:
    """An episode's area seen: a ``SeenTrack`` for each of ``sensors`` (its scans, thinned on
    their own), all on one ``grid``."""

    def __init__(self, sensors: tuple[str, ...], robot: RobotInfo) -> None:
        self.grid = SeenGrid(SEEN_RESOLUTION_M)
        self.robot = robot
        self.tracks = {sensor: SeenTrack(self.grid) for sensor in sensors}

    def see(self, frame: SensorFrame) -> int:
        """Offer each sensor's scan in ``frame`` (stamped by the frame); the cells added."""
        new = 0
        for sensor, track in self.tracks.items():
            for scan in sensed_scans(frame, self.robot, (sensor,)):
                new += track.offer(frame.stamp_ns, *scan_beams(scan, frame.pose))
        return new

    def flush(self) -> int:
        """Integrate each track's scan held (``SeenTrack.flush``); the cells added."""
        return sum(track.flush() for track in self.tracks.values())


class Explore(Task):
    """explore (see the module's docstring); ``world``: the simulated world of the episodes
    (``None``: a real robot)."""

    name = "explore"

    def __init__(self, config: EnvConfig, robot: RobotInfo, world: Any = None) -> None:
        super().__init__(config, robot)
        self.world = world
        self.required = frozenset().union(
            *(OBSERVED_TABLE[s].part.readings(robot) for s in config.observed))
        self.action_space = planar_action_space()
        e, lidar = config.explore, config.lidar
        far = 1.0 if config.normalize_observations else lidar.clip_m
        low = np.concatenate((np.zeros(lidar.sectors), [-1.0, -1.0], np.zeros(e.crop_px**2)))
        high = np.concatenate((np.full(lidar.sectors, far), [1.0, 1.0], np.ones(e.crop_px**2)))
        self.observation_space = gym.spaces.Box(low.astype(np.float32), high.astype(np.float32),
                                                dtype=np.float32)

    def command(self, action: np.ndarray) -> Twist2D:
        return planar_command(action, self.robot)

    def begin(self, frame: SensorFrame) -> EpisodeContext:
        seen = SeenBySensors(self.config.observed, self.robot)
        seen.see(frame)
        free = (free_area_m2(self.world, (frame.pose.x, frame.pose.y))
                if self.world is not None else None)
        return EpisodeContext(start=frame.pose, extra={"seen": seen, "free_area_m2": free})

    def observe(self, frame: SensorFrame, context: EpisodeContext,
                last_action: np.ndarray) -> np.ndarray:
        sensor = self.config.sensor
        scans = sensed_scans(frame, self.robot, (sensor,))
        if not scans:
            raise ValueError(f"explore ({sensor}): the frame has no {sensor} reading")
        lidar, e = self.config.lidar, self.config.explore
        sectors = lidar_sectors(scans[0], lidar)
        if self.config.normalize_observations:
            sectors /= np.float32(lidar.clip_m)
        crop = seen_crop(context.extra["seen"].grid, frame.pose, e.crop_px, e.crop_cell_m)
        return np.concatenate((sectors, clipped_action(last_action, 2), crop.ravel()))

    def judge(self, previous: SensorFrame, frame: SensorFrame, context: EpisodeContext,
              collision_streak: int) -> Judgement:
        reward: ExploreReward = self.config.reward
        seen: SeenBySensors = context.extra["seen"]
        new, grid = seen.see(frame), seen.grid
        free, target = context.extra["free_area_m2"], self.config.explore.coverage_target
        covered = bool(free and target > 0 and grid.area_m2 >= target * free)
        safety = assess(frame, self.robot, self.config, collision_streak)
        crashed = safety.ended and not covered
        terms = {"area": reward.area * new * grid.resolution_m**2, "step": reward.step,
                 "collision": reward.collision if crashed else 0.0}
        outcome = Outcome.GOAL if covered else Outcome.COLLISION if crashed else None
        return Judgement(terms=terms, outcome=outcome, collision=safety.collision,
                         collision_streak=safety.streak, warning=safety.warning,
                         min_obstacle_m=safety.min_obstacle_m)

    def facts(self, context: EpisodeContext) -> dict[str, Any]:
        free = context.extra["free_area_m2"]
        return {} if free is None else {"free_area_m2": free}


def build(config: EnvConfig, robot: RobotInfo, world: Any = None) -> Explore:
    """explore (its table entry's ``build``)."""
    return Explore(config, robot, world)
