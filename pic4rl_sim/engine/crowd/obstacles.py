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
        (n × 2), and the distances (n × k, m). A point inside an obstacle is at distance 0
        and its vector points out: through a box's nearest face, away from a cylinder's
        axis."""
        b, c = self._boxes, self._cyls
        dx = pos[:, None, 0] - b[None, :, 0]
        dy = pos[:, None, 1] - b[None, :, 1]
        cos, sin = np.cos(b[:, 4]), np.sin(b[:, 4])
        lx, ly = cos * dx + sin * dy, -sin * dx + cos * dy  # in each box's frame
        ox = lx - np.clip(lx, -b[:, 2], b[:, 2])
        oy = ly - np.clip(ly, -b[:, 3], b[:, 3])
        box_dist = np.hypot(ox, oy)
        through_x = b[:, 2] - np.abs(lx) <= b[:, 3] - np.abs(ly)  # the nearer face, inside
        inside = box_dist == 0.0
        ox = np.where(inside, np.where(through_x, np.where(lx >= 0, 1.0, -1.0), 0.0), ox)
        oy = np.where(inside, np.where(through_x, 0.0, np.where(ly >= 0, 1.0, -1.0)), oy)
        box_dir = np.stack((cos * ox - sin * oy, sin * ox + cos * oy), axis=-1)
        centre = pos[:, None, :] - c[None, :, :2]
        c_len = np.hypot(centre[..., 0], centre[..., 1])
        vec = np.concatenate((box_dir, centre), axis=1)
        dist = np.concatenate((box_dist, np.maximum(c_len - c[:, 2], 0.0)), axis=1)
        return vec / np.maximum(np.hypot(vec[..., 0], vec[..., 1]), _EPS)[..., None], dist
