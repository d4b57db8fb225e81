"""``render_mode="rgb_array"``: every registered env draws its top-down view (and passes
Gymnasium's checker with it), the robot, goal, obstacles and path land on their pixels,
``RecordVideo`` records it unchanged, rendering off builds nothing, and MuJoCo's camera either
renders (an OpenGL backend exists) or says which backend is missing."""

from __future__ import annotations

import os
import subprocess
import sys
import warnings
from pathlib import Path

import gymnasium as gym
import imageio.v3 as iio
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env
from ros_helpers import ARENA_MJCF

import pic4rl_bridge  # noqa: F401 - registers the envs
from pic4rl_bridge.env import NavEnv
from pic4rl_bridge.errors import BridgeError, ConfigError
from pic4rl_bridge.render import make_view
from pic4rl_metrics.viz.raster import COLORS
from bridge_helpers import ENV_CONFIGS, LIDAR_CONFIG, REPO

FORWARD = np.array([1.0, 0.0], np.float32)  # full speed ahead, no turn


@pytest.fixture(scope="module")
def arena(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("world") / "arena.xml"
    path.write_text(ARENA_MJCF)
    return path


def pixel(env: NavEnv, img: np.ndarray, x: float, y: float) -> tuple[int, ...]:
    view = env._view.view  # type: ignore[union-attr]
    col, row = (int(round(float(v))) for v in view.pixels(x, y))
    return tuple(int(c) for c in img[row, col])


@pytest.mark.parametrize("env_id", sorted(ENV_CONFIGS))
def test_every_env_renders_its_top_down_view_and_passes_the_checker(env_id: str) -> None:
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        env = gym.make(env_id, config=str(ENV_CONFIGS[env_id]), render_mode="rgb_array")
        try:
            check_env(env.unwrapped)
            env.reset(seed=3)
            img = env.render()
        finally:
            env.close()
    assert [str(w.message) for w in caught] == []
    assert img.dtype == np.uint8 and img.ndim == 3 and img.shape[2] == 3
    assert img.shape[0] % 16 == 0 and img.shape[1] % 16 == 0  # what H.264 encoders want
    dt = env.unwrapped.scenario.robot.control_dt_s
    assert env.metadata["render_fps"] == pytest.approx(1 / dt)
    assert np.all(img == COLORS["robot"], axis=-1).sum() > 20
    band = env.unwrapped._view.band
    if "depth" in env.unwrapped.task.required:  # the depth image above the map
        assert band > 0 and (img[:band] != 255).any(axis=-1).sum() > 100 * 100
    else:
        assert band == 0


def test_robot_goal_obstacle_and_path_are_drawn_where_they_are(arena: Path) -> None:
    env = NavEnv(LIDAR_CONFIG, sim={"world": str(arena)}, render_mode="rgb_array")
    try:
        env.reset(seed=0, options={"start": [-2.0, 0.0, 0.0], "goal": [2.0, -2.0]})
        img = env.render()
        assert pixel(env, img, -2.15, 0.1) == COLORS["robot"]  # behind the centre, off-axis
        assert pixel(env, img, -1.5, 0.1) != COLORS["robot"]  # ahead of its front edge
        assert pixel(env, img, 2.0, -2.0) == COLORS["goal"]
        assert pixel(env, img, 3.0, 3.0) == COLORS["obstacle"]  # the crate
        assert pixel(env, img, 0.0, -3.0) == COLORS["background"]
        for _ in range(15):
            env.step(FORWARD)
        img = env.render()
        x = env.frame.pose.x
        assert x > -1.3
        assert pixel(env, img, -2.0, 0.0) == COLORS["path"]  # where it came from
        assert pixel(env, img, x - 0.15, 0.1) == COLORS["robot"]
        scan = np.all(img == COLORS["scan"], axis=-1)
        assert scan.sum() > 10 and pixel(env, img, 0.0, 0.0) != COLORS["scan"]
    finally:
        env.close()


def test_record_video_records_it_unchanged(arena: Path, tmp_path: Path) -> None:
    pytest.importorskip("moviepy", reason="gymnasium's RecordVideo encodes with moviepy")
    env = NavEnv(LIDAR_CONFIG, sim={"world": str(arena)}, render_mode="rgb_array",
                 overrides={"episode_max_steps": 12})
    recorder = gym.wrappers.RecordVideo(env, str(tmp_path / "videos"),
                                        episode_trigger=lambda _: True,
                                        name_prefix="ep")
    try:
        recorder.reset(seed=0, options={"start": [-2.0, 0.0, 0.0], "goal": [2.0, 2.0]})
        steps, done = 0, False
        while not done:
            _, _, terminated, truncated, _ = recorder.step(np.array([-1.0, 0.5], np.float32))
            steps, done = steps + 1, terminated or truncated
    finally:
        recorder.close()
    frames = iio.imread(tmp_path / "videos" / "ep-episode-0.mp4")
    assert steps == 12 and len(frames) == steps + 1  # the reset's frame, then one per step


def test_rendering_off_builds_nothing_and_returns_none(arena: Path) -> None:
    env = NavEnv(LIDAR_CONFIG, sim={"world": str(arena)})
    try:
        assert env._view is None
        env.reset(seed=0)
        env.step(FORWARD)
        assert env.render() is None
    finally:
        env.close()


def test_bad_render_settings_say_what_is_expected(arena: Path) -> None:
    with pytest.raises(ConfigError, match=r"render_mode: 'human' is invalid; expected "
                                          r"'rgb_array' or None"):
        NavEnv(LIDAR_CONFIG, sim={"world": str(arena)}, render_mode="human")
    with pytest.raises(ConfigError, match=r"render_view: 'side' is invalid; expected one of "
                                          r"top, mujoco"):
        NavEnv(LIDAR_CONFIG, sim={"world": str(arena)}, render_mode="rgb_array",
               render_view="side")
    env = NavEnv(LIDAR_CONFIG, sim={"world": str(arena)}, render_mode="rgb_array")
    try:
        with pytest.raises(BridgeError, match="render\\(\\) before the first reset"):
            env.render()
        with pytest.raises(ConfigError, match="needs transport: inprocess"):
            make_view("mujoco", env.scenario, object(), 0.3)  # a transport with no engine
    finally:
        env.close()


CAMERA = """
import sys
import pic4rl_bridge
from pic4rl_bridge.env import NavEnv
from pic4rl_bridge.errors import ConfigError
try:
    env = NavEnv(sys.argv[1], render_mode="rgb_array", render_view="mujoco")
except ConfigError as err:
    print("ConfigError:", err)
    raise SystemExit(3)
env.reset(seed=0)
img = env.render()
print(img.shape, img.dtype, int(img.std() > 5))
env.close()
"""


def camera(backend: str) -> subprocess.CompletedProcess[str]:
    env = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "WAYLAND_DISPLAY")}
    env.update(MUJOCO_GL=backend, PYTHONPATH=os.pathsep.join([str(REPO), *sys.path]))
    return subprocess.run([sys.executable, "-c", CAMERA, str(LIDAR_CONFIG)], env=env,
                          capture_output=True, text=True, timeout=300, check=False)


def test_mujoco_camera_renders_where_egl_exists() -> None:
    done = camera("egl")
    if done.returncode == 3:
        assert "MUJOCO_GL=egl" in done.stdout and "apt install" in done.stdout
        pytest.skip(f"no EGL here: {done.stdout.strip()}")
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip().splitlines()[-1] == "(480, 640, 3) uint8 1"


def test_mujoco_camera_without_a_backend_says_which_is_missing() -> None:
    done = camera("glfw")  # GLFW needs a display, and there is none
    assert done.returncode == 3, done.stdout + done.stderr
    message = done.stdout.strip()
    assert "MUJOCO_GL=glfw does not work here" in message
    assert "MUJOCO_GL=egl" in message and "render_view: 'top' needs none" in message
    assert "Traceback" not in done.stderr


def test_the_memory_s_cells_are_drawn_when_it_is_on(arena: Path) -> None:
    """goToPose's memory (memory.enabled): its occupied cells, in the map colour; none
    without memory."""
    counts = []
    for memory in (False, True):
        env = NavEnv(LIDAR_CONFIG, sim={"world": str(arena)}, render_mode="rgb_array",
                     overrides={"memory.enabled": memory})
        try:
            env.reset(seed=0, options={"start": [-2.0, 0.0, 0.0], "goal": [2.0, -2.0]})
            for _ in range(5):
                env.step(FORWARD)
            counts.append(int(np.all(env.render() == COLORS["map"], axis=-1).sum()))
        finally:
            env.close()
    assert counts[0] == 0 and counts[1] > 20
