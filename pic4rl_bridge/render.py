"""The env's pictures for ``render_mode="rgb_array"``: a top-down view drawn with numpy (no
OpenGL, so headless and on any CPU), or MuJoCo's own camera where an OpenGL backend exists.

The top-down view shows the world's obstacles (drawn once), the memory's occupied cells
(goToPose's ``memory.enabled``), the plan, the row's centre line,
the goal and its tolerance, the path so far, the scan's returns, the person, the robot's
footprint and heading, and the depth image in an inset when the robot has one. It uses the
episode videos' drawing (``pic4rl_metrics.viz.raster``) and colours, so both look alike.
"""

from __future__ import annotations

import math
import os
from dataclasses import replace
from typing import Any

import numpy as np

from pic4rl_metrics.viz import raster
from pic4rl_metrics.viz.raster import COLORS, View

from .errors import ConfigError
from .scenario import Scenario
from .tasks.base import EpisodeContext
from .readings.frame import SensorFrame

#: ``render_view`` values: the drawn top-down view, or MuJoCo's camera.
RENDER_VIEWS = ("top", "mujoco")
#: The width of the top-down view, and the height of the depth inset (pixels).
VIEW_PX = 480
INSET_PX = 160


def _multiple_of_16(value: float) -> int:
    return int(min(max(16 * round(value / 16), 240), 960))


class TopDownView:
    """The top-down picture of an episode: ``begin`` at reset, ``track`` at every step,
    ``render`` when asked. With ``depth``, a band above the map shows the depth image.

    ``view`` maps world points to pixels of the rendered picture."""

    def __init__(self, scenario: Scenario, goal_tolerance_m: float, *,
                 depth: bool = False) -> None:
        self.scenario = scenario
        self.world = scenario.world
        self.footprint = scenario.robot.footprint
        self.goal_tolerance_m = goal_tolerance_m
        self.band = INSET_PX + 16 if depth else 0  # a multiple of 16, as the map's height
        self.view: View | None = None
        self.background: np.ndarray | None = None
        self.path: list[tuple[float, float]] = []
        if self.world is not None:
            self._fit_world()

    def _fit_world(self) -> None:
        """The still picture of the current world, fitted to its bounds."""
        xmin, ymin, xmax, ymax = self.world.bounds
        height = _multiple_of_16(VIEW_PX * (ymax - ymin) / (xmax - xmin))
        self._draw_world(View.fit(self.world.bounds, VIEW_PX, height))

    def _draw_world(self, view: View) -> None:
        """The still picture: the band, then the map in ``view`` (of the map alone)."""
        img = np.full((self.band + view.height, view.width, 3), COLORS["background"], np.uint8)
        self.map_view = view
        self.view = replace(view, row0=view.row0 + self.band, height=self.band + view.height)
        self.background = img
        img = img[self.band:]
        if self.world is not None:
            for box in self.world.boxes:
                corners = raster.rectangle(box.x, box.y, box.yaw_rad, box.size_x_m, box.size_y_m)
                raster.convex_polygon(img, view, corners, COLORS["obstacle"])
            for cyl in self.world.cylinders:
                if cyl.kind != "person":
                    raster.disc(img, view, cyl.x, cyl.y, cyl.radius_m, COLORS["obstacle"])
            xmin, ymin, xmax, ymax = self.world.bounds
            raster.polyline(img, view, [(xmin, ymin), (xmax, ymin), (xmax, ymax), (xmin, ymax),
                                        (xmin, ymin)], COLORS["obstacle"])

    def begin(self, frame: SensorFrame, context: EpisodeContext) -> None:
        """A new episode: its path restarts; its world is drawn anew when it has one of its own
        (``episodes.world_variants``); without a world, the view centres on its start and
        reaches the scan's range and the goal."""
        self.path = [(frame.pose.x, frame.pose.y)]
        if self.scenario.world is not self.world:  # a world per episode: this one's
            self.world = self.scenario.world
            self._fit_world()
        if self.world is None:
            reach = min(frame.scan.range_max_m, 10.0) if frame.scan is not None else 5.0
            if context.goal is not None:
                reach = max(reach, math.dist(context.goal, self.path[0]) + 1.0)
            x, y = self.path[0]
            self._draw_world(View.fit((x - reach, y - reach, x + reach, y + reach),
                                      VIEW_PX, VIEW_PX))

    def track(self, frame: SensorFrame) -> None:
        self.path.append((frame.pose.x, frame.pose.y))

    def close(self) -> None:
        """Nothing to free: the pictures are arrays."""

    def render(self, frame: SensorFrame, context: EpisodeContext) -> np.ndarray:
        """The picture now (height × width × 3, ``uint8``)."""
        assert self.background is not None  # drawn by __init__ or begin
        picture = self.background.copy()
        img, view = picture[self.band:], self.map_view
        memory = context.extra.get("memory")
        if memory is not None and len(memory.cells):  # goToPose's memory: the cells seen
            raster.points(img, view, *memory.centres().T, COLORS["map"], size=1)
        explorer = context.extra.get("explorer")  # goal_input explorer: its grid and plan
        if explorer is not None and len(explorer.grid.cells):
            raster.points(img, view, *explorer.grid.centres().T, COLORS["map"], size=1)
        for plan in (frame.plan, explorer.path if explorer is not None else None):
            if plan is not None and len(plan):
                raster.polyline(img, view, plan, COLORS["plan"], width=2)
        if context.centerline is not None:
            raster.polyline(img, view, context.centerline, COLORS["centerline"], width=2)
        goal = frame.goal if frame.goal is not None else context.goal
        if goal is not None:
            raster.disc(img, view, goal[0], goal[1], self.goal_tolerance_m, COLORS["goal"],
                        ring_px=2)
            raster.disc(img, view, goal[0], goal[1], 0.1, COLORS["goal"])
        raster.polyline(img, view, self.path, COLORS["path"], width=2)
        if frame.scan is not None:
            raster.points(img, view, *scan_world(frame), COLORS["scan"], size=2)
        if frame.person is not None:
            raster.disc(img, view, frame.person.x, frame.person.y, 0.25, COLORS["person"])
        pose = frame.pose
        raster.footprint(img, view, pose.x, pose.y, pose.yaw, self.footprint)
        if frame.depth is not None and self.band:
            inset(picture[:self.band], depth_image(frame.depth))
        return picture


def scan_world(frame: SensorFrame) -> tuple[np.ndarray, np.ndarray]:
    """The scan's returns (the collision test's points) in the world (m)."""
    assert frame.scan is not None
    base, pose = frame.scan.points(), frame.pose
    c, s = math.cos(pose.yaw), math.sin(pose.yaw)
    return (pose.x + c * base[:, 0] - s * base[:, 1], pose.y + s * base[:, 0] + c * base[:, 1])


def depth_image(depth: np.ndarray) -> np.ndarray:
    """A depth image (m, ±inf out of range) as grey levels, near bright, far and none dark."""
    d = np.asarray(depth, float)
    finite = np.isfinite(d)
    far = float(d[finite].max()) if finite.any() else 1.0
    grey = np.where(finite, 255 * (1 - np.clip(d, 0, far) / max(far, 1e-6)), 0)
    return np.repeat(grey.astype(np.uint8)[..., None], 3, axis=2)


def inset(img: np.ndarray, picture: np.ndarray) -> None:
    """``picture`` scaled (nearest pixel) to ``img``'s height less a margin, framed, at its
    left."""
    height = img.shape[0] - 10
    width = min(max(int(round(height * picture.shape[1] / picture.shape[0])), 2),
                img.shape[1] - 10)
    rows = np.arange(height) * picture.shape[0] // height
    cols = np.arange(width) * picture.shape[1] // width
    img[3:height + 7, 3:width + 7] = 0
    img[5:height + 5, 5:width + 5] = picture[rows][:, cols]


class CameraView:
    """MuJoCo's own picture of the in-process engine: a camera following the robot from above
    and behind (``mujoco.Renderer``, which needs OpenGL: EGL or OSMesa when headless)."""

    def __init__(self, engine: Any, width: int = 640, height: int = 480) -> None:
        import mujoco

        self.engine = engine
        try:
            self.renderer = mujoco.Renderer(engine.model, height, width)
        except (mujoco.FatalError, RuntimeError, ImportError, AttributeError, OSError) as err:
            backend = os.environ.get("MUJOCO_GL", "")
            raise ConfigError(
                f"render_view: 'mujoco' needs an OpenGL backend for mujoco.Renderer and "
                f"{'MUJOCO_GL=' + backend if backend else 'the default (GLFW, a display)'} "
                f"does not work here ({type(err).__name__}: {err}); on a headless machine "
                "install EGL (apt install libegl1) and set MUJOCO_GL=egl, or OSMesa "
                "(apt install libosmesa6) and MUJOCO_GL=osmesa; render_view: 'top' needs "
                "none") from err
        self.camera = mujoco.MjvCamera()
        self.camera.distance, self.camera.elevation = 6.0, -50.0

    def begin(self, frame: SensorFrame, context: EpisodeContext) -> None:
        """Nothing to keep: the engine holds the scene."""

    def track(self, frame: SensorFrame) -> None:
        """Nothing to keep: the engine holds the scene."""

    def render(self, frame: SensorFrame, context: EpisodeContext) -> np.ndarray:
        pose = frame.pose
        self.camera.lookat[:] = (pose.x, pose.y, 0.0)
        self.camera.azimuth = math.degrees(pose.yaw)
        self.renderer.update_scene(self.engine.data, camera=self.camera)
        return self.renderer.render()

    def close(self) -> None:
        self.renderer.close()


def make_view(view: str, scenario: Scenario, transport: Any, goal_tolerance_m: float, *,
              depth: bool = False) -> TopDownView | CameraView:
    """The picture-maker ``render_view`` names: ``top`` (default; ``depth``: the frames carry
    a depth image to show) or ``mujoco``."""
    if view == "top":
        return TopDownView(scenario, goal_tolerance_m, depth=depth)
    if view != "mujoco":
        raise ConfigError(f"render_view: {view!r} is invalid; expected one of "
                          f"{', '.join(RENDER_VIEWS)}")
    engine = getattr(transport, "engine", None)
    if engine is None:
        raise ConfigError("render_view: 'mujoco' needs transport: inprocess (the MuJoCo model "
                          "lives in this process); render_view: 'top' works with any")
    return CameraView(engine)
