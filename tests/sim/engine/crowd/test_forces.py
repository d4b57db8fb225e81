"""The social force model's equations (``pic4rl_sim.engine.crowd.forces``) against the
formulas of Helbing & Molnár (1995) and Moussaïd et al. (2010), value by value."""

from __future__ import annotations

import math

import numpy as np
import pytest

from pic4rl_sim.engine.crowd import forces
from pic4rl_sim.engine.crowd.obstacles import Walls
from pic4rl_sim.engine.worlds.spec import Box, Cylinder, WorldSpec


def test_the_driving_force_relaxes_to_the_desired_velocity_in_tau():
    v = np.array([[0.2, 0.0]])
    e = np.array([[0.0, 1.0]])
    f = forces.driving(v, e, np.array([1.34]))
    np.testing.assert_allclose(f, [[-0.2 / 0.5, 1.34 / 0.5]])
    # integrated alone, the velocity approaches v0 e as 1 - exp(-t / tau)
    vel, dt = np.zeros((1, 2)), 0.001
    for _ in range(500):  # one tau
        vel = vel + forces.driving(vel, e, np.array([1.0])) * dt
    assert vel[0, 1] == pytest.approx(1.0 - math.exp(-1.0), abs=2e-3)


def test_a_walker_at_rest_repels_with_v0_over_sigma_exp_minus_d_over_sigma():
    d = 0.8
    r = np.array([[d, 0.0]])  # from b to a
    f = forces.pair_forces(r, np.zeros((1, 2)))
    expected = 2.1 / 0.3 * math.exp(-d / 0.3)
    np.testing.assert_allclose(f, [[expected, 0.0]], rtol=1e-9)


def test_a_moving_walker_repels_with_the_gradient_of_the_elliptic_potential():
    r = np.array([[0.7, -0.4]])
    step = np.array([[0.9, 0.3]]) * forces.STEP_TIME_S
    b = forces.semi_minor_axis(r, step)[0]
    # 2b = sqrt((|r| + |r - s|)^2 - |s|^2)
    assert 2 * b == pytest.approx(math.sqrt((np.hypot(*r[0]) + np.hypot(*(r - step)[0])) ** 2
                                            - np.hypot(*step[0]) ** 2))
    h = 1e-6
    grad = [(forces.potential(r + dr, step) - forces.potential(r - dr, step))[0] / (2 * h)
            for dr in (np.array([[h, 0.0]]), np.array([[0.0, h]]))]
    np.testing.assert_allclose(forces.pair_forces(r, step)[0], -np.array(grad), rtol=1e-5)


def test_the_distance_between_two_people_runs_between_their_surfaces():
    r = forces.surface_vectors(np.array([[1.0, 0.0]]), np.array([0.25]),
                               np.array([[0.0, 0.0]]), np.array([0.3]))
    np.testing.assert_allclose(r, [[[0.45, 0.0]]])


def test_overlapping_bodies_are_still_pushed_apart_along_their_centres():
    r = forces.surface_vectors(np.array([[0.3, 0.0]]), np.array([0.25]),
                               np.array([[0.0, 0.0]]), np.array([0.25]))
    np.testing.assert_allclose(r, [[[forces.MIN_GAP_M, 0.0]]])
    f = forces.pair_forces(r[0], np.zeros((1, 2)))
    assert f[0, 0] == pytest.approx(2.1 / 0.3 * math.exp(-forces.MIN_GAP_M / 0.3))


def test_a_point_inside_an_obstacle_is_pushed_out_through_the_nearest_face():
    world = WorldSpec("w", (-5, -5, 5, 5), boxes=(Box(0.0, 0.0, 2.0, 1.0, 1.0),),
                      cylinders=(Cylinder(3.0, 0.0, 0.5, 1.0),))
    away, dist = Walls(world).nearest(np.array([[0.8, 0.1], [0.1, -0.3], [3.2, 0.0]]))
    np.testing.assert_allclose(dist[:, 0][:2], [0.0, 0.0])
    np.testing.assert_allclose(away[0, 0], [1.0, 0.0], atol=1e-12)  # 0.2 from the east face
    np.testing.assert_allclose(away[1, 0], [0.0, -1.0], atol=1e-12)  # 0.2 from the south one
    assert dist[2, 1] == 0.0
    np.testing.assert_allclose(away[2, 1], [1.0, 0.0], atol=1e-12)


def test_a_force_whose_source_is_behind_weighs_c_and_one_from_ahead_weighs_1():
    e = np.array([[1.0, 0.0]])
    # pushed forward: the source is behind; pushed back: it is ahead; pushed 95° off the
    # heading: the source lies 85° off it, inside the 100° half field of view
    f = np.array([[[1.0, 0.0], [-1.0, 0.0], [math.cos(math.radians(95)),
                                              math.sin(math.radians(95))]]])
    np.testing.assert_allclose(forces.field_of_view(e, f), [[0.5, 1.0, 1.0]])
    # a walker at rest 0.5 m ahead of a walker heading for it repels it with full weight
    r = np.array([[[-0.5, 0.0]]])  # from the one ahead to the walker
    pushed = forces.pair_forces(r, np.zeros_like(r))
    np.testing.assert_allclose(forces.field_of_view(e, pushed), [[1.0]])


def test_a_wall_repels_with_u0_over_r_exp_minus_d_over_r_from_its_nearest_point():
    world = WorldSpec("w", (-5, -5, 5, 5), boxes=(Box(0.0, 0.0, 2.0, 1.0, 1.0),),
                      cylinders=(Cylinder(3.0, 0.0, 0.5, 1.0),))
    away, dist = Walls(world).nearest(np.array([[0.0, 1.2], [1.6, 0.0]]))
    np.testing.assert_allclose(dist, [[0.7, math.hypot(3.0, 1.2) - 0.5], [0.6, 0.9]])
    np.testing.assert_allclose(away[0, 0], [0.0, 1.0], atol=1e-12)
    np.testing.assert_allclose(away[1, 1], [-1.0, 0.0], atol=1e-12)
    f = forces.wall_forces(away[:, :1], dist[:, :1])
    np.testing.assert_allclose(f[0], [0.0, 10.0 / 0.2 * math.exp(-0.7 / 0.2)])


def test_a_group_member_is_drawn_to_the_others_and_slowed_when_they_are_out_of_sight():
    pos = np.array([[0.0, 0.0], [0.0, 3.0], [10.0, 0.0]])
    vel = np.array([[0.0, -1.0], [0.0, 0.0], [1.0, 0.0]])
    f = forces.group_forces(pos, vel, 0.25, np.array([0, 0, 1]))
    # beyond (2 - 1) / 2 m: beta2 towards the centre of mass; it lies 180° off the heading,
    # 90° outside the half field of view: -beta1 * (pi / 2) * v
    np.testing.assert_allclose(f[0], [0.0, 3.0 + 4.0 * math.pi / 2], atol=1e-9)
    np.testing.assert_allclose(f[2], [0.0, 0.0])  # alone in its group


def test_speed_is_capped_at_1_3_times_the_desired_speed():
    v = forces.cap_speed(np.array([[3.0, 4.0], [0.1, 0.0]]), np.array([1.0, 1.0]))
    np.testing.assert_allclose(v, [[0.78, 1.04], [0.1, 0.0]])
