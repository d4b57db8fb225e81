"""The vineyard's baselines: the privileged centre-line follower and the classical row follower
reach the row's end without collision on straight and waved rows (the real in-process env:
MuJoCo, the scan, the task's judgement), the row follower reads the lane's middle from an
analytic scan, and each baseline is refused in a task it does not drive."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from pic4rl_base.geometry import Footprint, Pose2D, project
from pic4rl_bridge.baselines.registry import BASELINE_TASKS, check_fits, make_baseline
from pic4rl_bridge.baselines.row_followers import RowFollower
from pic4rl_bridge.config import EnvConfig
from pic4rl_bridge.env import NavEnv
from pic4rl_bridge.errors import ConfigError
from pic4rl_bridge.readings.frame import ScanData, SensorFrame
from pic4rl_bridge.robot_info import RobotInfo
from pic4rl_sim.engine.geometry import Twist2D

ROOT = Path(__file__).resolve().parents[3]
CONFIG = ROOT / "config" / "env_vineyard_depth.yaml"
JACKAL = RobotInfo(name="jackal", footprint=Footprint(length_m=0.508, width_m=0.430), omni=False,
                   min_linear_m_s=0.0, max_linear_m_s=0.5, max_angular_rad_s=1.0,
                   max_lateral_m_s=0.0, control_dt_s=0.1, mounts={"lidar": Pose2D(0.0, 0.0, 0.0)})
LAYOUTS = {
    "straight": {"world.vineyard.rows": 3, "world.vineyard.gap_prob": 0.2},
    "waved": {"world.vineyard.rows": 3, "world.vineyard.bend_m": 0.6,
              "world.vineyard.spacing_jitter_m": 0.5, "world.vineyard.row_length_m": 12.0},
}


def drive(name: str, sim: dict, seed: int) -> tuple[str, list[float]]:
    """One episode of baseline ``name``: its outcome and the robot's offsets from the row's
    centre line (m), one per step."""
    env = NavEnv(CONFIG, sim=sim, overrides={"episode_max_steps": 400})
    offsets: list[float] = []
    try:
        controller = make_baseline(name, env.config, env.scenario.robot, env.scenario.world)
        env.reset(seed=seed)
        controller.reset()
        line = env._context.centerline  # the task's own centre line for this episode
        done, info = False, {}
        while not done:
            _, _, terminated, truncated, info = env.step(controller.action(env.frame))
            offsets.append(project(line, (env.frame.pose.x, env.frame.pose.y))[1])
            done = terminated or truncated
    finally:
        env.close()
    return str(info["outcome"]), offsets


@pytest.mark.parametrize("layout", sorted(LAYOUTS))
@pytest.mark.parametrize("name", ["centerline", "row_follower"])
def test_each_follower_reaches_the_row_end_without_collision(name: str, layout: str) -> None:
    outcome, offsets = drive(name, {"world_variant": 1, **LAYOUTS[layout]}, seed=0)
    assert outcome == "goal"
    mae = float(np.mean(np.abs(offsets)))
    limit = 0.05 if name == "centerline" else 0.25
    assert mae < limit, f"{name} on {layout} rows: offset MAE {mae:.3f} m"


def _scan(ranges: np.ndarray) -> ScanData:
    n = len(ranges)
    return ScanData(np.asarray(ranges, dtype=np.float32), -math.pi, 2 * math.pi / n, 0.1, 10.0)


def _rows_scan(offset_m: float, width_m: float, n: int = 720) -> ScanData:
    """A 360° scan of two lines of trunk points (every 0.5 m) at y = ±width/2 - offset."""
    ranges = np.full(n, np.inf)
    for y in (0.5 * width_m - offset_m, -0.5 * width_m - offset_m):
        for x in np.arange(-1.0, 4.0, 0.5):
            beam = int(round((math.atan2(y, x) + math.pi) / (2 * math.pi / n))) % n
            ranges[beam] = min(ranges[beam], math.hypot(x, y))
    assert np.isfinite(ranges).sum() >= 16
    return _scan(ranges)


@pytest.mark.parametrize("offset_m", [-0.4, 0.0, 0.3])
def test_the_row_follower_reads_the_middle_of_the_lane_and_steers_to_it(offset_m: float) -> None:
    follower = RowFollower(JACKAL)
    frame = SensorFrame(0, Pose2D(0.0, 0.0, 0.0), Twist2D(), scan=_rows_scan(offset_m, 2.2))
    middle, heading, width = follower.lane(frame)  # type: ignore[misc]
    assert middle == pytest.approx(-offset_m, abs=0.03)  # the middle seen from the robot
    assert heading == pytest.approx(0.0, abs=0.02)
    assert width == pytest.approx(2.2, abs=0.05) and follower.width_m == width
    _, w = follower.command(frame)
    assert w == pytest.approx(0.0, abs=0.02) if offset_m == 0 else np.sign(w) == -np.sign(offset_m)


def test_a_baseline_that_does_not_fit_the_task_is_refused() -> None:
    vineyard = EnvConfig(task="vineyard", sensor="depth")
    for name, tasks in BASELINE_TASKS.items():
        other = EnvConfig() if "vineyard" in tasks else vineyard
        with pytest.raises(ConfigError, match=rf"--baseline {name}: it drives .*this env's task"):
            check_fits(name, other)
    with pytest.raises(ConfigError, match="Test it with --baseline centerline or row_follower"):
        make_baseline("dwa", vineyard, JACKAL)
    with pytest.raises(ConfigError, match="--baseline centerline: .* has none"):
        make_baseline("centerline", vineyard, JACKAL)
