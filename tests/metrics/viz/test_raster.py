"""The numpy drawing of videos and the env's view (``raster``), against hand-placed pixels."""

from __future__ import annotations

import math

import numpy as np
import pytest

from pic4rl_base.geometry import Footprint
from pic4rl_metrics.viz import raster
from pic4rl_metrics.viz.raster import COLORS, View

RED = (255, 0, 0)


def canvas() -> tuple[np.ndarray, View]:
    """100 × 50 pixels showing x in [0, 10] m and y in [0, 5] m, 10 pixels a metre."""
    view = View.fit((0.0, 0.0, 10.0, 5.0), 100, 50, margin_px=0)
    return np.zeros((50, 100, 3), np.uint8), view


def painted(img: np.ndarray, color: tuple[int, int, int] = RED) -> np.ndarray:
    return np.all(img == color, axis=-1)


def test_fit_maps_the_corners_and_keeps_y_up() -> None:
    _, view = canvas()
    cols, rows = view.pixels([0.0, 10.0, 5.0], [0.0, 5.0, 2.5])
    np.testing.assert_allclose(cols, [0, 100, 50])
    np.testing.assert_allclose(rows, [50, 0, 25])
    wide = View.fit((0.0, 0.0, 1.0, 1.0), 200, 100, margin_px=0)  # equal scale, centred
    assert wide.sx == wide.sy == 100
    np.testing.assert_allclose(wide.pixels(0.5, 0.5), (100, 50))


def test_a_disc_covers_its_radius_and_a_ring_only_its_edge() -> None:
    img, view = canvas()
    raster.disc(img, view, 5.0, 2.5, 1.0, RED)
    area = painted(img).sum()
    assert area == pytest.approx(math.pi * 10**2, rel=0.1)
    assert painted(img)[25, 50] and not painted(img)[25, 62]
    img, _ = canvas()
    raster.disc(img, view, 5.0, 2.5, 1.0, RED, ring_px=2)
    assert not painted(img)[25, 50] and painted(img)[25, 60]


def test_a_rotated_rectangle_footprint_and_its_heading() -> None:
    img, view = canvas()
    raster.footprint(img, view, 5.0, 2.5, math.pi / 2, Footprint(length_m=2.0, width_m=1.0),
                     RED)
    robot = painted(img)
    # Length along +y now: 20 pixels tall, 10 wide, minus the heading line drawn over it.
    assert robot[25 - 6, 50 - 3] and robot[25 + 8, 50 + 3]
    assert not robot[25, 50 + 8] and not robot[25 - 12, 50]
    heading = painted(img, COLORS["heading"])
    assert heading[25 - 8, 50] and not heading[25 + 8, 50]  # from the centre to the front


def test_points_and_lines_skip_what_lies_outside_or_is_not_finite() -> None:
    img, view = canvas()
    raster.points(img, view, [1.0, 20.0, np.nan], [1.0, 1.0, 1.0], RED)
    assert painted(img).sum() == 1 and painted(img)[40, 10]
    img, _ = canvas()
    raster.polyline(img, view, [(0.0, 1.0), (5.0, 1.0)], RED)  # columns 0 to 50, no gap
    assert painted(img)[40, 0:51].all() and painted(img).sum() == 51
