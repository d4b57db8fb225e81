"""vineyard: projection on straight and arc lanes, lane choice and orientation, reward."""

from __future__ import annotations

import math

import numpy as np
import pytest

from pic4rl_base.geometry import Footprint, Pose2D
from pic4rl_bridge.config import EnvConfig
from pic4rl_bridge.errors import ConfigError
from pic4rl_bridge.readings.frame import ScanData, SensorFrame
from pic4rl_bridge.robot_info import RobotInfo
from pic4rl_bridge.tasks import make_task
from pic4rl_bridge.tasks.vineyard import VineyardTask, polyline_length, project
from pic4rl_metrics.contract import Outcome
from pic4rl_sim.engine.geometry import Twist2D
from pic4rl_sim.engine.worlds.spec import WorldSpec

STRAIGHT = ((0.0, 0.0), (10.0, 0.0))
OTHER = ((0.0, 2.5), (10.0, 2.5))
ROBOT = RobotInfo(name="test", footprint=Footprint(radius_m=0.3), omni=False,
                  min_linear_m_s=0.0, max_linear_m_s=0.5, max_angular_rad_s=1.0,
                  max_lateral_m_s=0.0, control_dt_s=0.1)
R, STEP = 5.0, math.radians(10.0)
ARC = np.array([(R * math.cos(k * STEP), R * math.sin(k * STEP)) for k in range(10)])
CHORD = 2 * R * math.sin(STEP / 2)


def frame(x: float, y: float = 0.0, yaw: float = 0.0, scan: ScanData | None = None):
    return SensorFrame(0, Pose2D(x, y, yaw), Twist2D(), scan=scan,
                       depth=np.full((60, 80), 2.0, np.float32))


def test_project_straight_line():
    line = np.array(STRAIGHT)
    assert project(line, (3.0, 0.5)) == pytest.approx((3.0, 0.5))
    assert project(line, (3.0, -0.5)) == pytest.approx((3.0, -0.5))
    assert project(line, (12.0, 0.0)) == pytest.approx((10.0, 2.0))  # beyond the end
    assert project(line[::-1], (3.0, 0.5)) == pytest.approx((7.0, -0.5))  # reversed


def test_project_on_an_arc():
    assert polyline_length(ARC) == pytest.approx(9 * CHORD)
    for k in (1, 4, 8):
        u = np.array([math.cos(k * STEP), math.sin(k * STEP)])
        s, offset = project(ARC, (R + 0.2) * u)  # outside a counter-clockwise arc: right
        assert s == pytest.approx(k * CHORD) and offset == pytest.approx(-0.2)
        s, offset = project(ARC, (R - 0.2) * u)  # inside: left, nearest on a neighbour chord
        assert offset == pytest.approx(0.2 * math.cos(STEP / 2))
        assert abs(s - k * CHORD) == pytest.approx(0.2 * math.sin(STEP / 2))
    # arc length approaches R * angle on a fine lane
    fine = np.array([(R * math.cos(t), R * math.sin(t)) for t in np.linspace(0, 1.0, 2001)])
    s, _ = project(fine, (R * math.cos(0.6), R * math.sin(0.6)))
    assert s == pytest.approx(R * 0.6, rel=1e-6)


def test_progress_along_an_arc_lane():
    config = EnvConfig().replace(**{"vineyard.centerline": ARC.ravel().tolist()})
    task = VineyardTask(config, ROBOT, [STRAIGHT])  # the config's centre line wins
    context = task.begin(frame(*ARC[0]))
    np.testing.assert_allclose(context.centerline, ARC)
    j = task.judge(frame(*ARC[2]), frame(*ARC[5]), context, 0)
    assert j.terms["progress"] == pytest.approx(10.0 * 3 * CHORD)
    assert j.terms["centering"] == pytest.approx(0.0, abs=1e-12) and j.outcome is None


def test_lane_choice_reversal_and_offset_sign():
    task = VineyardTask(EnvConfig(), ROBOT, [STRAIGHT, OTHER])
    context = task.begin(frame(9.8, 2.4, math.pi))
    np.testing.assert_array_equal(context.centerline, [[10.0, 2.5], [0.0, 2.5]])
    assert context.goal == (0.0, 2.5) and context.start == Pose2D(9.8, 2.4, math.pi)
    # heading -x, left is -y: 0.1 m below the line is 0.1 m left
    j = task.judge(frame(9.8, 2.4, math.pi), frame(9.3, 2.4, math.pi), context, 0)
    assert j.terms["progress"] == pytest.approx(10.0 * 0.5)
    assert j.terms["centering"] == pytest.approx(-0.1)
    assert project(context.centerline, (9.3, 2.4)) == pytest.approx((0.7, 0.1))
    forward = task.begin(frame(0.3, -0.2))
    np.testing.assert_array_equal(forward.centerline, STRAIGHT)


def test_row_end_and_collision():
    config = EnvConfig().replace(**{"reward.progress": 2.0, "reward.step": -0.5})
    task = VineyardTask(config, ROBOT, [STRAIGHT])
    context = task.begin(frame(0.0))
    keys = {"progress", "centering", "row_end", "collision", "step"}
    j = task.judge(frame(9.0), frame(9.5, 0.2), context, 0)
    assert set(j.terms) == keys and j.outcome is Outcome.GOAL
    assert j.terms["row_end"] == 100.0 and j.terms["step"] == -0.5
    assert j.reward == pytest.approx(2.0 * 0.5 - 0.2 + 100.0 - 0.5)
    # The end of the row reached from the next lane (through a gap) is not this row's end.
    beside = task.judge(frame(9.0, 2.4), frame(9.5, 2.5), context, 0)
    assert beside.outcome is None and beside.terms["row_end"] == 0.0
    edge = task.judge(frame(9.0), frame(9.5, -0.9), context, 0)
    assert edge.outcome is Outcome.GOAL  # max_offset_m 0.9: within it is still the row
    ranges = np.full(360, np.inf, np.float32)
    ranges[180] = 0.3  # touching ahead
    wall = ScanData(ranges, -math.pi, 2 * math.pi / 360, 0.1, 30.0)
    crash = task.judge(frame(4.0), frame(4.0, scan=wall), context, 0)
    assert set(crash.terms) == keys and crash.outcome is Outcome.COLLISION
    assert crash.terms["collision"] == -150.0 and crash.terms["row_end"] == 0.0


def test_observation_facts_and_required():
    task = VineyardTask(EnvConfig(), ROBOT, [STRAIGHT])
    f = frame(0.0)
    context = task.begin(f)
    obs = task.observe(f, context, np.zeros(2))
    assert task.observation_space.contains(obs) and obs.shape == (1, 60, 80)
    assert task.required == {"depth"} and task.name == "vineyard"
    assert task.facts(context) == {"row_centerline": [[0.0, 0.0], [10.0, 0.0]]}
    assert task.command(np.array([1.0, 0.0])) == pytest.approx(Twist2D(0.5, 0.0, 0.0))


def test_make_task_lanes():
    config = EnvConfig().replace(task="vineyard", sensor="depth")
    with pytest.raises(ConfigError, match="vineyard.centerline"):
        make_task(config, ROBOT)
    empty = WorldSpec("indoor", (0.0, 0.0, 5.0, 5.0))
    with pytest.raises(ConfigError, match="'indoor' has no lanes"):
        make_task(config, ROBOT, empty)
    world = WorldSpec("vineyard", (-1.0, -1.0, 11.0, 4.0), lanes=(STRAIGHT, OTHER))
    task = make_task(config, ROBOT, world)
    assert isinstance(task, VineyardTask) and len(task.lanes) == 2
    own = config.replace(**{"vineyard.centerline": [0.0, 0.0, 5.0, 0.0]})
    assert isinstance(make_task(own, ROBOT), VineyardTask)
