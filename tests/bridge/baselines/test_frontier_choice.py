"""The frontier choice's candidates on synthetic scans: steps through clear cells counted as
rings (a corridor's frontier is its length away), two doors of a round room offered as two
candidates with their bearings, the candidate chosen becomes the target, and a closed room
offers none (the explorer waits)."""

from __future__ import annotations

import math

import numpy as np

from pic4rl_base.geometry import Footprint, Pose2D
from pic4rl_bridge.baselines.exploration import FrontierGrids
from pic4rl_bridge.baselines.frontier_choice import (
    CHOICES,
    FAR_M,
    FEATURES,
    GROUP_M,
    OBSERVATION_SIZE,
    ChoosingExplorer,
    frontier_steps,
)
from pic4rl_bridge.readings.frame import ScanData, SensorFrame
from pic4rl_bridge.robot_info import RobotInfo
from pic4rl_sim.engine.geometry import Twist2D

BEAMS = 720
ANGLES = -math.pi + 2 * math.pi / BEAMS * np.arange(BEAMS)
ROBOT = RobotInfo(name="test", footprint=Footprint(radius_m=0.2), omni=False,
                  min_linear_m_s=0.0, max_linear_m_s=0.5, max_angular_rad_s=1.0,
                  max_lateral_m_s=0.0, control_dt_s=0.1)


def frame(ranges: np.ndarray) -> SensorFrame:
    scan = ScanData(ranges.astype(np.float32), -math.pi, 2 * math.pi / BEAMS, 0.05, 10.0)
    return SensorFrame(0, Pose2D(0.0, 0.0, 0.0), Twist2D(), scan=scan)


def _grids(clear: np.ndarray, start: np.ndarray, frontier: np.ndarray) -> FrontierGrids:
    ny, nx = clear.shape
    gx, gy = np.meshgrid(np.arange(nx) * 0.1, np.arange(ny) * 0.1)
    none = np.zeros_like(clear)
    return FrontierGrids(gx, gy, clear, none, frontier, clear, start, none, gx * 0)


def test_a_corridors_frontier_is_its_length_in_steps():
    clear = np.zeros((5, 30), dtype=bool)
    clear[2, :] = True  # a corridor one cell wide
    start, frontier = np.zeros_like(clear), np.zeros_like(clear)
    start[2, 0], frontier[2, 17] = True, True
    frontier[0, 5] = True  # beside no clear cell the region reaches: never touched
    region, steps = frontier_steps(_grids(clear, start, frontier))
    assert steps[2, 17] == 17 and steps[0, 5] == -1
    assert region[2].all() and not region[[0, 1, 3, 4]].any()
    # diagonal steps count one each, as the explorer's 8-connected search grows
    clear[:, :] = True
    frontier[:, :] = False
    frontier[4, 4] = True
    assert frontier_steps(_grids(clear, start, frontier))[1][4, 4] == 4


def _room(doors_deg: tuple[float, ...]) -> np.ndarray:
    ranges = np.full(BEAMS, 2.0)
    for door in doors_deg:
        ranges[np.abs(np.angle(np.exp(1j * (ANGLES - math.radians(door))))) < math.radians(15)] = np.inf
    return ranges


def test_two_doors_are_two_candidates_nearest_first_and_the_choice_is_the_target():
    explorer = ChoosingExplorer(ROBOT)
    observation = explorer.due(frame(_room((90.0, -90.0))))
    assert observation is not None and observation.shape == (OBSERVATION_SIZE,)
    rows = observation[:CHOICES * FEATURES].reshape(CHOICES, FEATURES)
    n = len(explorer.candidates)
    assert n >= 2 and (rows[:n, 0] == 1).all() and not rows[n:].any()
    assert np.all(np.diff(rows[:n, 1]) >= 0)  # nearest first, by steps
    assert (np.abs(observation) <= 1).all()
    sides = np.sign(rows[:n, 4])  # sin of the bearing: left and right doors both offered
    assert {1.0, -1.0} <= set(sides.tolist())
    for (target, cell), row in zip(explorer.candidates, rows):
        # the cell the arrival rule watches lies in the candidate's group, within GROUP_M
        assert abs(math.hypot(*cell) - row[2] * FAR_M) <= GROUP_M
        assert math.hypot(target[0] - cell[0], target[1] - cell[1]) < 0.5
    assert len({c for _, c in explorer.candidates}) == n  # each a stretch of its own
    right = int(np.flatnonzero(rows[:n, 4] < 0)[0])
    v, w = explorer.drive(frame(_room((90.0, -90.0))), right)
    assert explorer.target == explorer.candidates[right][0]
    assert v == 0.0 and w < 0.0  # it turns in place toward the right-hand door


def test_a_choice_beyond_the_offer_takes_the_nearest():
    explorer = ChoosingExplorer(ROBOT)
    explorer.due(frame(_room((90.0, -90.0))))
    explorer.drive(frame(_room((90.0, -90.0))), CHOICES - 1 + len(explorer.candidates))
    assert explorer.target == explorer.candidates[0][0]


def test_a_closed_room_offers_nothing_and_the_explorer_waits():
    explorer = ChoosingExplorer(ROBOT)
    observation = explorer.due(frame(np.full(BEAMS, 2.0)))
    assert observation is not None and explorer.candidates == []
    assert not observation[:CHOICES * FEATURES].any() and observation[-1] == 0.0
    assert 0.0 < observation[-2] <= 1.0  # the area seen: the room
    assert explorer.drive(frame(np.full(BEAMS, 2.0)), 0) == (0.0, 0.0)
    assert explorer.target is None
