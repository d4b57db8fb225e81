"""The sonar ring and the stereo camera observed (issue 40 items 1-2): ``sensors: [lidar, sonar]``
and ``[stereo]`` give a Dict key each, its value the sensor's own reading encoded; a sensor the
sim does not enable is refused in one line; the sonar's echoes are the collision check's points
when it is the only range sensor; every observed sensor's topics are recorded."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
import pytest

from pic4rl_base.geometry import Footprint, Pose2D
from pic4rl_bridge.config import EnvConfig
from pic4rl_bridge.env import NavEnv
from pic4rl_bridge.errors import ConfigError
from pic4rl_bridge.perception.collision import obstacle_distance, sensed_points
from pic4rl_bridge.perception.observations import depth_observation
from pic4rl_bridge.readings.frame import ScanData, SensorFrame
from pic4rl_bridge.robot_info import RobotInfo
from pic4rl_sim.engine.geometry import Twist2D
from pic4rl_sim.engine.sensor_kinds.sonar import SonarSpec

CONFIG = Path(__file__).resolve().parents[3] / "config" / "env_goto_lidar.yaml"
SONAR = {"sonar.enabled": True, "sonar.count": 6, "sonar.noise_std_m": 0.0}
STEREO = {"stereo.enabled": True, "stereo.width": 40, "stereo.height": 24}


def _episode(sim: dict[str, Any], overrides: dict[str, Any],
             steps: int = 6) -> tuple[gym.Space[Any], list[tuple[Any, Any]]]:
    """The space, and each step's observation beside the engine's own reading of ``sensor``
    (its sim kind), over one seeded episode of fixed random actions."""
    env = NavEnv(str(CONFIG), sim=sim, overrides={**overrides, "episode_max_steps": steps})
    rng = np.random.default_rng(3)
    engine = env.transport.engine
    kind = next(k for k in ("sonar", "stereo") if k in engine.sensors)
    try:
        obs, _ = env.reset(seed=4)
        seen = [(obs, engine.read(kind))]
        for _ in range(steps - 1):
            obs, _, terminated, truncated, _ = env.step(
                rng.uniform(-1, 1, env.action_space.shape).astype(np.float32))
            seen.append((obs, engine.read(kind)))
            if terminated or truncated:
                break
        return env.observation_space, seen
    finally:
        env.close()


@pytest.mark.parametrize("normalize", [False, True])
def test_lidar_and_sonar_give_a_key_each_the_sonar_a_range_a_cone(normalize: bool) -> None:
    space, seen = _episode(SONAR, {"sensors": ["lidar", "sonar"], "sonar.clip_m": 2.0,
                                   "normalize_observations": normalize})
    assert isinstance(space, gym.spaces.Dict) and set(space) == {"lidar", "sonar", "goal"}
    assert space["sonar"].shape == (6,) and space["sonar"].high.max() == (
        1.0 if normalize else 2.0)
    assert len(seen) >= 5
    for step, (obs, ranges) in enumerate(seen):
        assert space.contains(obs), f"step {step} outside the space"
        expected = np.clip(np.nan_to_num(ranges, posinf=2.0, neginf=0.0), 0.0, 2.0)
        expected = expected / 2.0 if normalize else expected
        np.testing.assert_allclose(obs["sonar"], expected, rtol=1e-6, err_msg=f"step {step}")
    assert any(np.isfinite(r).any() for _, r in seen)  # some cone hears a wall


def test_the_stereo_camera_alone_is_its_depth_image_encoded_as_depths() -> None:
    space, seen = _episode(STEREO, {"sensor": "stereo", "stereo.obs_width": 20,
                                    "stereo.obs_height": 12, "stereo.clip_m": 6.0})
    assert set(space) == {"stereo", "goal"} and space["stereo"].shape == (1, 12, 20)
    assert space["stereo"].dtype == np.uint8
    for step, (obs, reading) in enumerate(seen):
        expected = depth_observation(reading.depth, 20, 12, 6.0, "uint8")
        np.testing.assert_array_equal(obs["stereo"], expected, err_msg=f"step {step}")
    assert len({obs["stereo"].tobytes() for obs, _ in seen}) > 1  # it sees the robot move


def test_lidar_and_stereo_observe_both() -> None:
    space, seen = _episode(STEREO, {"sensors": ["lidar", "stereo"]})
    assert set(space) == {"lidar", "stereo", "goal"} and space["stereo"].shape == (1, 48, 80)
    assert all(space.contains(obs) for obs, _ in seen)


@pytest.mark.parametrize(("overrides", "kind"), [
    ({"sensors": ["lidar", "sonar"]}, "sonar"), ({"sensor": "stereo"}, "stereo")])
def test_a_sensor_the_sim_does_not_enable_is_refused_in_one_line(overrides: dict[str, Any],
                                                                 kind: str) -> None:
    with pytest.raises(ConfigError) as err:
        NavEnv(str(CONFIG), overrides=overrides)
    message = str(err.value)
    assert "\n" not in message and message.startswith(f"sensors: '{kind}'")
    assert f"'{kind}.enabled: true'" in message and "'jackal'" in message


def _sonar_frame(ranges: list[float], scan: ScanData | None = None) -> SensorFrame:
    readings = {f"sonar_{i}": float(np.float32(r)) for i, r in enumerate(ranges)}
    return SensorFrame(0, Pose2D(0.0, 0.0, 0.0), Twist2D(), readings=readings, scan=scan)


SONAR_ROBOT = RobotInfo(name="ring", footprint=Footprint(radius_m=0.3), omni=False,
                        min_linear_m_s=0.0, max_linear_m_s=0.5, max_angular_rad_s=1.0,
                        max_lateral_m_s=0.0, control_dt_s=0.1,
                        mounts={"sonar": Pose2D(0.1, 0.0, 0.0)},
                        specs={"sonar": SonarSpec(count=4, range_min_m=0.15)})


def test_the_sonar_alone_gives_the_collision_check_a_point_a_cone_on_its_axis() -> None:
    # Four cones at 0, 90, 180, 270 deg from (0.1, 0): an echo at 1 m ahead, none left, one
    # too close behind (REP 117 -inf: at the minimum range), one at 2 m right.
    points = sensed_points(_sonar_frame([1.0, math.inf, -math.inf, 2.0]), SONAR_ROBOT)
    np.testing.assert_allclose(points, [[1.1, 0.0], [-0.05, 0.0], [0.1, -2.0]], atol=1e-6)
    assert obstacle_distance(_sonar_frame([1.0, math.inf, -math.inf, 2.0]),
                             SONAR_ROBOT) == pytest.approx(0.05 - 0.3)
    assert obstacle_distance(_sonar_frame([math.inf] * 4), SONAR_ROBOT) == math.inf
    assert len(sensed_points(_sonar_frame([1.0, 1.0, 1.0]), SONAR_ROBOT)) == 0  # a cone missing


def test_a_scan_comes_before_the_sonar() -> None:
    scan = ScanData(np.full(4, 3.0, np.float32), -math.pi, math.pi / 2, 0.1, 10.0)
    distance = obstacle_distance(_sonar_frame([0.5] * 4, scan=scan), SONAR_ROBOT)
    assert distance == pytest.approx(3.0 - 0.3)


def test_every_observed_sensors_topics_are_recorded_the_others_as_configured() -> None:
    plain = EnvConfig()
    assert plain.recorded_topics == plain.record.topics
    sonar = EnvConfig(sensors=("lidar", "sonar"))
    cones = [f"sonar/cone{i}" for i in range(8)]
    assert sonar.recorded_topics == (*plain.record.topics, *cones)
    assert EnvConfig(sensor="stereo").recorded_topics == (*plain.record.topics,
                                                          "stereo/depth/image_raw")
