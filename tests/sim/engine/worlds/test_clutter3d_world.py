"""The ``clutter3d`` world: seeded, its obstacles below and above the default LiDAR's plane,
pairs sampled off every obstacle, and what the LiDAR and a depth camera see of a low box."""

from __future__ import annotations

import math

import numpy as np
import pytest

from pic4rl_base.errors import ConfigError
from pic4rl_base.geometry import Pose2D
from pic4rl_sim.engine.core import Engine
from pic4rl_sim.engine.ray_sensors import DepthCameraSpec
from pic4rl_sim.engine.robot_specs import JACKAL
from pic4rl_sim.engine.sampling import sample_start_goal
from pic4rl_sim.engine.worlds.clutter3d import LIDAR_PLANE_M
from pic4rl_sim.engine.worlds.generators import make_world


def test_the_world_is_seeded_and_its_obstacles_straddle_the_lidar_plane():
    world = make_world("clutter3d", seed=4)
    assert world == make_world("clutter3d", seed=4) != make_world("clutter3d", seed=5)
    assert JACKAL.lidar.mount_xyz_m[2] == LIDAR_PLANE_M
    low = [b for b in world.boxes if b.kind == "obstacle"]
    tops = [b for b in world.boxes if b.kind == "furniture"]
    assert len(low) == 6 and all(b.z_base_m + b.height_m < LIDAR_PLANE_M for b in low)
    assert len(tops) == 4 and all(b.z_base_m > LIDAR_PLANE_M for b in tops)
    assert len(world.cylinders) == 16 and all(c.radius_m == 0.015 for c in world.cylinders)
    assert all(b.z_base_m == 0 and b.height_m >= LIDAR_PLANE_M for b in world.boxes
               if b.kind == "wall")
    assert world.params["shelves_placed"] == sum(b.height_m > 0.5 for b in tops)


def test_sampled_pairs_keep_off_every_obstacle_even_under_a_table_top():
    world = make_world("clutter3d", seed=2)
    rng = np.random.default_rng(0)
    radius = JACKAL.footprint.bounding_radius_m
    for _ in range(10):
        start, goal = sample_start_goal(world, rng, clearance_m=radius)
        assert world.clearance(np.array([start[:2], goal])).min() >= radius - 1e-9


def test_out_of_range_parameters_name_their_key():
    with pytest.raises(ConfigError, match=r"world\.clutter3d\.low_height_m"):
        make_world("clutter3d", low_height_m=0.3)
    with pytest.raises(ConfigError, match=r"world\.clutter3d\.top_z_m"):
        make_world("clutter3d", top_z_m=0.3)
    with pytest.raises(ConfigError, match=r"world\.clutter3d\.low_boxes"):
        make_world("clutter3d", size_m=4.0, inner_walls=0, tables=0, low_boxes=100)


def test_the_lidar_reads_past_a_low_box_that_the_depth_camera_sees():
    """The robot 1.5 m from the only low box, between it and the arena's centre, facing it:
    the LiDAR's forward beam reads the wall beyond the box, a level depth camera 0.1 m up the
    box's face."""
    world = make_world("clutter3d", seed=1, low_boxes=1, tables=0, inner_walls=0)
    box = next(b for b in world.boxes if b.kind == "obstacle")
    toward = math.atan2(box.y, box.x)
    start = Pose2D(box.x - 1.5 * math.cos(toward), box.y - 1.5 * math.sin(toward), toward)
    robot = JACKAL.with_sensors(depth=DepthCameraSpec(mount_xyz_m=(0.0, 0.0, 0.1)))
    engine = Engine(robot, world, seed=1)
    engine.reset(start=start, goal=(start.x - math.cos(toward), start.y - math.sin(toward)))
    lidar = engine.lidar
    assert lidar is not None
    beams = lidar.angle_min_rad + lidar.angle_increment_rad * np.arange(lidar.spec.beams)
    forward = float(engine.scan()[np.argmin(np.abs(np.angle(np.exp(1j * beams))))])
    reach = 0.5 * math.hypot(box.size_x_m, box.size_y_m)
    lidar_x = lidar.spec.mount_xyz_m[0]
    assert forward > 1.5 + reach - lidar_x  # past the box: the wall beyond it
    depth = engine.depth_image()
    rows = depth.shape[0] // 2
    centre = float(depth[rows - 2:rows + 2, depth.shape[1] // 2 - 2:depth.shape[1] // 2 + 2].min())
    assert 1.5 - reach - 1e-3 < centre <= 1.5  # the box's near face
