"""Row followers for the vineyard task, run by ``pic4rl-test --baseline NAME`` like an agent.

- ``centerline``: the privileged follower. It reads the row's centre line (the world's lane
  the task judges by, or ``vineyard.centerline``) and pursues a point ``lookahead_m`` ahead on
  it. No agent sees that line: it is the reference for what the task allows, and the expert
  that labels states for imitation (``pic4rl_agents.training.imitation``).
- ``row_follower``: the classical follower with no privileged information (Martini et al.
  2022 compare their agent with such a one). From the sensed points (the scan's, else the
  depth image's nearest pixel per column) it fits a line to the nearest row on each side, a
  window ahead of the robot, and steers to the middle of the two: the lateral offset of the
  middle line balances the clearance to left and right, its slope gives the heading along the
  rows. With one side unseen (a gap, the row's end) it keeps the last lane width; with neither,
  it drives straight on. The fit is ``pic4rl_metrics.core.crop_rows``': the row metrics of a
  bag with no centre line read the lane the same way.

Both command (v, ω) within the env's ranges as the task's 2-D normalised action; pure numpy
over the env's decoded frame.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np

from pic4rl_base.geometry import project
from pic4rl_metrics.core.crop_rows import LaneFit, LaneWindow, fit_lane
from pic4rl_sim.engine.geometry import point_along

from ..config import EnvConfig
from ..control.actions import normalized_action
from ..errors import ConfigError
from ..perception.collision import sensed_points
from ..perception.observations import target_polar
from ..perception.rows import centerlines, row_centerline
from ..readings.frame import SensorFrame
from ..robot_info import RobotInfo

if TYPE_CHECKING:
    from pic4rl_sim.engine.worlds.spec import WorldSpec


def _drive(robot: RobotInfo, bearing: float, turn_gain: float,
           slow_rad: float) -> tuple[float, float]:
    """(v, ω) toward a heading error ``bearing`` (rad): ω proportional, v at full speed when
    facing it, falling linearly to none at ``slow_rad`` off."""
    w = float(np.clip(turn_gain * bearing, -robot.max_angular_rad_s, robot.max_angular_rad_s))
    v = robot.max_linear_m_s * min(max(1.0 - abs(bearing) / slow_rad, 0.0), 1.0)
    return float(min(max(v, robot.min_linear_m_s, 0.0), robot.max_linear_m_s)), w


class CenterlineFollower:
    """The privileged centre-line follower (see the module's docstring)."""

    def __init__(self, robot: RobotInfo, lanes: Sequence[np.ndarray], *,
                 lookahead_m: float = 0.6, turn_gain: float = 2.5,
                 slow_rad: float = 1.2) -> None:
        self.robot, self.lanes = robot, list(lanes)
        self.lookahead_m, self.turn_gain, self.slow_rad = lookahead_m, turn_gain, slow_rad
        self._line: np.ndarray | None = None

    def reset(self) -> None:
        """Forget the row: the next frame picks the lane nearest the robot, as the task does."""
        self._line = None

    @property
    def line(self) -> np.ndarray | None:
        """The centre line being followed (n × 2, m), or ``None`` before the first frame."""
        return self._line

    def command(self, frame: SensorFrame) -> tuple[float, float]:
        """(v, ω) (m/s, rad/s) toward the centre line's point ``lookahead_m`` ahead."""
        xy = (frame.pose.x, frame.pose.y)
        if self._line is None:
            self._line = row_centerline(self.lanes, xy)
        s, _ = project(self._line, xy)
        target = point_along(self._line, s + self.lookahead_m)
        _, bearing = target_polar(frame.pose, float(target[0]), float(target[1]))
        return _drive(self.robot, bearing, self.turn_gain, self.slow_rad)

    def action(self, frame: SensorFrame) -> np.ndarray:
        return normalized_action(self.robot, *self.command(frame))


class RowFollower:
    """The classical row follower: clearance balanced between the rows (see the module)."""

    def __init__(self, robot: RobotInfo, *, window: LaneWindow = LaneWindow(),
                 offset_gain: float = 1.2, heading_gain: float = 2.0, slow_rad: float = 1.2,
                 lane_width_m: float = 2.5) -> None:
        self.robot, self.window = robot, window
        self.offset_gain, self.heading_gain, self.slow_rad = offset_gain, heading_gain, slow_rad
        self.default_width_m = lane_width_m
        self.width_m = lane_width_m  # the last lane width seen

    def reset(self) -> None:
        """Forget the lane width seen: the next row may be wider or narrower."""
        self.width_m = self.default_width_m

    def lane(self, frame: SensorFrame) -> LaneFit | None:
        """The lane's middle line in the base frame (``pic4rl_metrics.core.crop_rows.fit_lane``), or
        ``None`` when no row is seen."""
        points = sensed_points(frame, self.robot)
        fit = fit_lane(points[:, 0], points[:, 1], self.width_m, self.window)
        if fit is not None:
            self.width_m = fit.width_m
        return fit

    def command(self, frame: SensorFrame) -> tuple[float, float]:
        """(v, ω) (m/s, rad/s) that steers onto the lane's middle line."""
        fit = self.lane(frame)
        if fit is None:
            return _drive(self.robot, 0.0, 0.0, self.slow_rad)
        error = fit.heading_rad + math.atan(self.offset_gain * fit.offset_m)
        return _drive(self.robot, error, self.heading_gain, self.slow_rad)

    def action(self, frame: SensorFrame) -> np.ndarray:
        return normalized_action(self.robot, *self.command(frame))


def make_row_follower(name: str, config: EnvConfig, robot: RobotInfo,
                      world: WorldSpec | None) -> CenterlineFollower | RowFollower:
    """``centerline`` on the env's centre lines (``vineyard.centerline``, else the world's
    lanes), or ``row_follower``."""
    if name == "row_follower":
        return RowFollower(robot)
    lanes = world.lanes if world is not None else ()
    if not lanes and not config.vineyard.centerline:
        raise ConfigError("--baseline centerline: it follows the row's centre line, and this "
                          "env has none (no vineyard world, no vineyard.centerline)")
    return CenterlineFollower(robot, centerlines(config, lanes))
