"""The vineyard generator, measured on the shapes it makes: an analytic straight layout,
concentric arcs, waved rows, lanes of drawn widths, gaps, end posts and bad parameters."""

from __future__ import annotations

import math

import numpy as np
import pytest

from pic4rl_base.errors import ConfigError
from pic4rl_base.geometry import project
from pic4rl_sim.engine.worlds.generators import make_world
from pic4rl_sim.engine.worlds.spec import WorldSpec, clearance
from pic4rl_sim.engine.worlds.vineyard import POST_OFFSET_M


def trunks(world: WorldSpec) -> np.ndarray:
    return np.array([(c.x, c.y) for c in world.cylinders if c.kind == "trunk"])


def posts(world: WorldSpec) -> np.ndarray:
    return np.array([(c.x, c.y) for c in world.cylinders if c.kind == "post"])


def canopy_centres(world: WorldSpec) -> np.ndarray:
    return np.array([(b.x, b.y) for b in world.boxes if b.kind == "canopy"])


def test_straight_rows_an_analytic_layout() -> None:
    world = make_world("vineyard", seed=0, rows=4, row_spacing_m=2.5, gap_prob=0.2)
    xy = trunks(world)
    rows = np.unique(xy[:, 1].round(9))
    assert rows == pytest.approx([-3.75, -1.25, 1.25, 3.75])
    assert len(xy) < 4 * 11  # some plants missing
    assert np.allclose(np.diff(np.unique(xy[:, 0].round(6))), 1.0)
    # A missing plant is a gap in the hedge too: one canopy box per trunk, centred on it.
    assert sorted(map(tuple, canopy_centres(world).round(9))) == sorted(map(tuple, xy.round(9)))
    canopy = [b for b in world.boxes if b.kind == "canopy"]
    assert all(b.z_base_m == 0.8 and b.size_y_m == 0.5 and b.yaw_rad == 0 for b in canopy)
    assert {round(b.size_x_m, 9) for b in canopy} == {1.0}
    # Posts in line with each row, POST_OFFSET_M beyond its end plants at x = -5 and 5.
    expected = {(s * (5.0 + POST_OFFSET_M), y) for s in (-1, 1) for y in rows}
    assert set(map(tuple, posts(world).round(9))) == expected
    assert len(world.lanes) == 3
    for k, lane in enumerate(world.lanes):
        pts = np.array(lane)
        assert pts[:, 1] == pytest.approx(np.full(len(pts), 0.5 * (rows[k] + rows[k + 1])))
        assert clearance(pts, (), world.cylinders).min() == pytest.approx(1.25 - 0.05, abs=1e-6)
        assert world.clearance(pts).min() == pytest.approx(1.25 - 0.25, abs=1e-6)
        assert world.spawn_poses[k][:2] == pytest.approx(lane[0])
        assert world.spawn_poses[k].yaw == pytest.approx(0.0)
        assert world.goal_points[k] == pytest.approx(lane[-1])
        assert np.hypot(*(pts[-1] - pts[0])) == pytest.approx(10.0)


@pytest.mark.parametrize("radius_m", [6.0, 15.0])
def test_curved_rows_are_concentric_arcs(radius_m: float) -> None:
    world = make_world("vineyard", seed=1, rows=5, row_spacing_m=2.5, row_radius_m=radius_m)
    centre = np.array([world.params["arc_center_x_m"], world.params["arc_center_y_m"]])
    r = np.hypot(*(trunks(world) - centre).T)
    k = (r - radius_m) / 2.5
    assert np.allclose(k, k.round(), atol=1e-9) and set(k.round()) == {0, 1, 2, 3, 4}
    post_r = np.hypot(*(posts(world) - centre).T)  # beyond each end, along its last chord
    assert (post_r - np.repeat(radius_m + 2.5 * np.arange(5), 2) >= 0).all()
    assert (post_r - np.repeat(radius_m + 2.5 * np.arange(5), 2) < 0.1).all()
    nearest = np.hypot(*(posts(world)[:, None] - trunks(world)[None]).T).min(axis=0)
    assert nearest == pytest.approx(np.full(10, POST_OFFSET_M))
    for i, lane in enumerate(world.lanes):
        lane_r = np.hypot(*(np.array(lane) - centre).T)
        assert lane_r == pytest.approx(np.full(len(lane), radius_m + (i + 0.5) * 2.5))
        assert clearance(np.array(lane), (), world.cylinders).min() >= 2.5 / 2 - 0.05 - 1e-6
        d = np.subtract(lane[1], lane[0])
        assert world.spawn_poses[i].yaw == pytest.approx(math.atan2(d[1], d[0]))


def test_waved_rows_follow_their_sine_and_lanes_stay_centred() -> None:
    length, bend = 12.0, 0.8
    world = make_world("vineyard", seed=3, rows=4, row_spacing_m=2.4, row_length_m=length,
                       bend_m=bend, gap_prob=0.0, trunk_spacing_m=0.25)
    wavelength, phase = world.params["bend_wavelength_m"], world.params["bend_phase_rad"]
    assert length <= wavelength <= 2 * length
    xy = trunks(world)
    wave = bend * np.sin(2 * math.pi * (xy[:, 0] + length / 2) / wavelength + phase)
    offsets = np.unique((xy[:, 1] - wave).round(9))
    assert offsets == pytest.approx([-3.6, -1.2, 1.2, 3.6])  # straight rows, bent alike
    assert np.ptp(wave) > bend  # the rows do bend
    rows = [xy[np.isclose(xy[:, 1] - wave, o)] for o in offsets]
    for lane in world.lanes:
        pts = np.array(lane)
        lane_wave = bend * np.sin(2 * math.pi * (pts[:, 0] + length / 2) / wavelength + phase)
        assert np.unique((pts[:, 1] - lane_wave).round(9)).size == 1
        # Centred: the rows on either side (polylines through their trunks) are equally far.
        k = world.lanes.index(lane)
        for side in (rows[k], rows[k + 1]):
            assert min(abs(project(side, p)[1]) for p in pts) > 1.2 * math.cos(0.45)
        gaps = [abs(project(rows[k], p)[1]) - abs(project(rows[k + 1], p)[1])
                for p in pts[1:-1]]  # the ends project onto the rows' ends
        assert np.abs(gaps).max() < 0.01


def test_lane_widths_are_drawn_within_the_jitter_and_variants_differ() -> None:
    layouts = [make_world("vineyard", seed=v, rows=6, row_spacing_m=2.4, spacing_jitter_m=0.6,
                          bend_m=0.5)
               for v in range(4)]
    widths = [[w.params[f"lane_width_{k}_m"] for k in range(5)] for w in layouts]
    assert all(1.8 <= x <= 3.0 for row in widths for x in row)
    assert np.ptp(np.array(widths)) > 0.3  # lanes of several widths
    assert len({round(w.params["bend_phase_rad"], 6) for w in layouts}) == 4
    assert len(set(layouts)) == 4  # training and test variants differ
    straight = make_world("vineyard", seed=2, rows=6, row_spacing_m=2.4, spacing_jitter_m=0.6)
    rows = np.unique(trunks(straight)[:, 1].round(9))
    assert np.diff(rows) == pytest.approx([straight.params[f"lane_width_{k}_m"]
                                           for k in range(5)])
    again = make_world("vineyard", seed=2, rows=6, row_spacing_m=2.4, spacing_jitter_m=0.6)
    assert again == straight


@pytest.mark.parametrize(("params", "key"), [
    ({"spacing_jitter_m": 2.0}, "spacing_jitter_m"),
    ({"row_spacing_m": 1.0}, "row_spacing_m"),
    ({"bend_m": 4.0}, "bend_m"),
    ({"bend_m": -0.1}, "bend_m"),
    ({"row_radius_m": 3.0, "bend_m": 3.0}, "bend_m"),
    ({"row_radius_m": 1.0, "row_length_m": 30.0}, "row_radius_m"),
    ({"gap_prob": 1.0}, "gap_prob"),
    ({"rows": 1}, "rows"),
])
def test_a_bad_parameter_is_an_error_naming_its_key(params: dict, key: str) -> None:
    with pytest.raises(ConfigError, match=rf"^world\.vineyard\.{key}: .* is invalid; expected"):
        make_world("vineyard", seed=0, **params)
    with pytest.raises(ConfigError, match=r"world\.vineyard\.bend_m: 'x' is invalid"):
        make_world("vineyard", bend_m="x")
