"""The world's static obstacles as the crowd's walls: for each person, the nearest point of
every box and cylinder (arrays built once per world, vectorised over people and obstacles)."""

from __future__ import annotations

import numpy as np

from ..worlds.spec import WorldSpec

_EPS = 1e-9


class Walls:
    """Boxes (centre, half sizes, yaw) and cylinders (centre, radius) of ``world``."""

    def __init__(self, world: WorldSpec) -> None:
        self._boxes = np.array([(b.x, b.y, b.size_x_m / 2, b.size_y_m / 2, b.yaw_rad)
                                for b in world.boxes]).reshape(-1, 5)
        self._cyls = np.array([(c.x, c.y, c.radius_m) for c in world.cylinders]).reshape(-1, 3)

    def nearest(self, pos: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Unit vectors (n × k × 2) from each obstacle's nearest point to each of ``pos``
        (n × 2), and the distances (n × k, m; 0 inside an obstacle)."""
        b, c = self._boxes, self._cyls
        dx = pos[:, None, 0] - b[None, :, 0]
        dy = pos[:, None, 1] - b[None, :, 1]
        cos, sin = np.cos(b[:, 4]), np.sin(b[:, 4])
        lx, ly = cos * dx + sin * dy, -sin * dx + cos * dy  # in each box's frame
        ox = lx - np.clip(lx, -b[:, 2], b[:, 2])
        oy = ly - np.clip(ly, -b[:, 3], b[:, 3])
        box_vec = np.stack((cos * ox - sin * oy, sin * ox + cos * oy), axis=-1)
        centre = pos[:, None, :] - c[None, :, :2]
        c_len = np.hypot(centre[..., 0], centre[..., 1])
        cyl_vec = centre / np.maximum(c_len, _EPS)[..., None] * np.maximum(
            c_len - c[:, 2], 0.0)[..., None]
        vec = np.concatenate((box_vec, cyl_vec), axis=1)
        dist = np.hypot(vec[..., 0], vec[..., 1])
        return vec / np.maximum(dist, _EPS)[..., None], dist
