"""Drawing on RGB arrays with numpy: a world-to-pixel view, points, lines, discs, footprints.

Episode videos (``video``) and the env's top-down view (``pic4rl_bridge.render``) draw the
moving parts of every frame with these: a frame is a copy of a background plus a few hundred
pixels, so rendering costs far less than encoding, needs no display, no OpenGL and no figure
per frame. Images are ``uint8`` (height, width, 3); world x points right and y up.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

#: One colour per thing drawn (RGB), shared by the videos and the env's view.
COLORS: dict[str, tuple[int, int, int]] = {
    "background": (255, 255, 255),
    "obstacle": (120, 120, 120),
    "map": (150, 150, 150),
    "scan": (214, 39, 40),
    "robot": (31, 119, 180),
    "heading": (8, 48, 107),
    "path": (255, 127, 14),
    "goal": (44, 160, 44),
    "plan": (148, 103, 189),
    "person": (227, 119, 194),
    "centerline": (188, 189, 34),
    "cursor": (0, 0, 0),
}


@dataclass(frozen=True)
class View:
    """The affine map from world (m) to pixel (column, row) of a ``width`` × ``height`` image:
    ``col = col0 + sx * x``, ``row = row0 - sy * y``."""

    col0: float
    row0: float
    sx: float  # pixels per metre along x
    sy: float  # pixels per metre along y
    width: int
    height: int

    @classmethod
    def fit(cls, bounds: tuple[float, float, float, float], width: int, height: int, *,
            margin_px: int = 8) -> View:
        """The largest equal-scale view that shows ``bounds`` (xmin, ymin, xmax, ymax),
        centred in the image."""
        xmin, ymin, xmax, ymax = bounds
        span_x, span_y = max(xmax - xmin, 1e-6), max(ymax - ymin, 1e-6)
        scale = min((width - 2 * margin_px) / span_x, (height - 2 * margin_px) / span_y)
        col0 = width / 2 - scale * (xmin + xmax) / 2
        row0 = height / 2 + scale * (ymin + ymax) / 2
        return cls(col0, row0, scale, scale, width, height)

    @classmethod
    def of_axes(cls, ax: Any, height: int) -> View:
        """The view of matplotlib axes ``ax`` on a drawn canvas ``height`` pixels high
        (display coordinates start at the bottom)."""
        (c0, r0), (c1, r1) = ax.transData.transform([(0.0, 0.0), (1.0, 1.0)])
        width = int(round(ax.figure.bbox.width))
        return cls(float(c0), float(height - r0), float(c1 - c0), float(r1 - r0), width, height)

    def pixels(self, x: Any, y: Any) -> tuple[np.ndarray, np.ndarray]:
        """Column and row (float) of world points."""
        return (self.col0 + self.sx * np.asarray(x, float),
                self.row0 - self.sy * np.asarray(y, float))

    @property
    def metres_per_pixel(self) -> float:
        return 1.0 / min(abs(self.sx), abs(self.sy))


def _put(img: np.ndarray, cols: np.ndarray, rows: np.ndarray, color: Any) -> None:
    c, r = np.rint(cols).astype(np.intp), np.rint(rows).astype(np.intp)
    inside = (c >= 0) & (c < img.shape[1]) & (r >= 0) & (r < img.shape[0])
    img[r[inside], c[inside]] = color


def points(img: np.ndarray, view: View, x: Any, y: Any, color: Any, *, size: int = 1) -> None:
    """Dots of ``size`` × ``size`` pixels at the finite world points (x, y)."""
    cols, rows = view.pixels(x, y)
    cols, rows = np.ravel(cols), np.ravel(rows)
    keep = np.isfinite(cols) & np.isfinite(rows)
    cols, rows = cols[keep], rows[keep]
    for dc in range(size):
        for dr in range(size):
            _put(img, cols + dc - (size - 1) / 2, rows + dr - (size - 1) / 2, color)


def polyline(img: np.ndarray, view: View, xy: Any, color: Any, *, width: int = 1) -> None:
    """The line through world points ``xy`` (n × 2), sampled every half pixel."""
    xy = np.asarray(xy, float).reshape(-1, 2)
    xy = xy[np.isfinite(xy).all(axis=1)]
    if len(xy) == 0:
        return
    cols, rows = view.pixels(xy[:, 0], xy[:, 1])
    if len(xy) > 1:
        steps = np.maximum(np.ceil(2 * np.hypot(np.diff(cols), np.diff(rows))), 1).astype(int)
        seg = np.repeat(np.arange(len(steps)), steps)
        start = np.cumsum(steps) - steps
        frac = (np.arange(int(steps.sum())) - start[seg]) / steps[seg]
        cols = np.append(cols[seg] + frac * (cols[seg + 1] - cols[seg]), cols[-1])
        rows = np.append(rows[seg] + frac * (rows[seg + 1] - rows[seg]), rows[-1])
    for dc in range(width):
        for dr in range(width):
            _put(img, cols + dc - (width - 1) / 2, rows + dr - (width - 1) / 2, color)


def _box(img: np.ndarray, cols: np.ndarray, rows: np.ndarray) -> tuple[slice, slice] | None:
    c0, c1 = max(int(np.floor(cols.min())), 0), min(int(np.ceil(cols.max())) + 1, img.shape[1])
    r0, r1 = max(int(np.floor(rows.min())), 0), min(int(np.ceil(rows.max())) + 1, img.shape[0])
    if c0 >= c1 or r0 >= r1:
        return None
    return slice(r0, r1), slice(c0, c1)


def disc(img: np.ndarray, view: View, x: float, y: float, radius_m: float, color: Any, *,
         ring_px: float | None = None) -> None:
    """A filled disc (or, with ``ring_px``, a ring that wide) of ``radius_m`` around (x, y);
    at least one pixel across."""
    col, row = view.pixels(x, y)
    r_px = max(radius_m / view.metres_per_pixel, 0.5)
    box = _box(img, np.array([col - r_px, col + r_px]), np.array([row - r_px, row + r_px]))
    if box is None:
        return
    rr, cc = np.mgrid[box]
    dist = np.hypot(cc - col, rr - row)
    inside = dist <= r_px if ring_px is None else np.abs(dist - r_px) <= ring_px / 2
    img[box][inside] = color


def convex_polygon(img: np.ndarray, view: View, xy: Any, color: Any) -> None:
    """A filled convex polygon with world vertices ``xy`` (n × 2, either winding)."""
    cols, rows = view.pixels(*np.asarray(xy, float).T)
    box = _box(img, cols, rows)
    if box is None:
        return
    rr, cc = np.mgrid[box]
    ec, er = np.roll(cols, -1) - cols, np.roll(rows, -1) - rows
    cross = (ec[:, None, None] * (rr - rows[:, None, None])
             - er[:, None, None] * (cc - cols[:, None, None]))
    inside = (cross >= 0).all(axis=0) | (cross <= 0).all(axis=0)
    img[box][inside] = color


def rectangle(x: float, y: float, yaw: float, length_m: float, width_m: float) -> np.ndarray:
    """Corners (4 × 2, world) of a ``length_m`` × ``width_m`` rectangle centred at (x, y),
    its length along ``yaw``."""
    c, s = math.cos(yaw), math.sin(yaw)
    half = np.array([(1, 1), (-1, 1), (-1, -1), (1, -1)]) * (length_m / 2, width_m / 2)
    return np.column_stack([x + c * half[:, 0] - s * half[:, 1],
                            y + s * half[:, 0] + c * half[:, 1]])


def footprint(img: np.ndarray, view: View, x: float, y: float, yaw: float, shape: Any,
              color: Any = COLORS["robot"]) -> None:
    """The robot at (x, y, yaw): its footprint (anything with ``radius_m`` or ``length_m``
    and ``width_m``; a 0.2 m disc when ``None``) and a heading line to its front edge."""
    radius = getattr(shape, "radius_m", None) if shape is not None else 0.2
    if radius is not None:
        disc(img, view, x, y, radius, color)
        reach = radius
    else:
        convex_polygon(img, view, rectangle(x, y, yaw, shape.length_m, shape.width_m), color)
        reach = shape.length_m / 2
    tip = (x + reach * math.cos(yaw), y + reach * math.sin(yaw))
    polyline(img, view, [(x, y), tip], COLORS["heading"], width=2)
