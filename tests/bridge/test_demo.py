"""The demo behind ``make demo``: the proportional baseline through the env, recorded, judged."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from pic4rl_bridge.baselines import GoToGoalController
from pic4rl_bridge.demo import main
from pic4rl_bridge.frame import SensorFrame
from pic4rl_bridge.robot import RobotInfo
from pic4rl_metrics.batch import compute
from pic4rl_sim.geometry import Footprint, Pose2D, Twist2D

ROBOT = RobotInfo("r", Footprint(radius_m=0.2), omni=False, min_linear_m_s=0.0,
                  max_linear_m_s=0.5, max_angular_rad_s=1.0, max_lateral_m_s=0.0,
                  control_dt_s=0.1)


def _frame(x: float, y: float, yaw: float, goal: tuple[float, float]) -> SensorFrame:
    return SensorFrame(0, Pose2D(x, y, yaw), Twist2D(), goal)


def test_the_controller_turns_toward_the_goal_and_drives_when_facing_it() -> None:
    controller = GoToGoalController(ROBOT)
    ahead = controller.action(_frame(0, 0, 0, (3.0, 0.0)))
    assert ahead.tolist() == [1.0, 0.0]  # full speed (clipped), no turn
    left = controller.action(_frame(0, 0, 0, (0.0, 3.0)))
    assert left[1] == 1.0 and left[0] == -1.0  # goal at +90°: turn left on the spot (v = 0)
    right = controller.action(_frame(0, 0, math.pi / 2, (3.0, 0.0)))
    assert right[1] == -1.0
    near = controller.action(_frame(0, 0, 0, (0.2, 0.0)))
    assert np.isclose(near[0], 2 * 0.2 / 0.5 - 1)  # v = distance, mapped to [-1, 1]


def test_the_demo_records_episodes_the_metrics_judge(tmp_path: Path) -> None:
    assert main(["--episodes", "3", "--bags", str(tmp_path), "--run", "d"]) == 0
    result = compute([tmp_path / "d"])
    rows = result.results
    assert len(rows) == 3 and all(r.error == "" for r in rows)
    assert {r.metrics.outcome for r in rows} <= {"goal", "collision", "timeout"}
    assert any(r.metrics.success == 1.0 for r in rows)  # open space: some goals reached
    assert main(["--episodes", "1", "--bags", str(tmp_path), "--run", "d"]) == 0
    assert len(compute([tmp_path / "d"]).results) == 4  # appended, nothing overwritten
