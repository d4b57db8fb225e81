"""A user's MJCF world as a ``WorldSpec``: its static geoms become the boxes and cylinders
that sampling, paths and markers read, and the engine loads the file itself."""

from __future__ import annotations

import math
from pathlib import Path

import mujoco
import numpy as np

from ...errors import WorldError
from .spec import Box, Cylinder, WorldSpec


def world_from_mjcf(path: str | Path) -> WorldSpec:
    """A user's MJCF world; its static geoms become boxes and cylinders for sampling.

    Static means welded to the world body (mocap and jointed bodies move). Planes are the
    floor; upright boxes, cylinders, capsules and spheres keep their shape; anything else
    (and tilted shapes) becomes the box around its extent.
    """
    path = Path(path).expanduser().resolve()
    try:
        model = mujoco.MjModel.from_xml_path(str(path))
    except ValueError as err:  # MuJoCo's error for unreadable and invalid files alike
        raise WorldError(f"{path}: cannot load the MJCF world: {err}") from err
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    geom = mujoco.mjtGeom
    boxes: list[Box] = []
    cylinders: list[Cylinder] = []
    extents: list[np.ndarray] = []  # xmin, ymin, xmax, ymax of each geom
    for g in range(model.ngeom):
        gtype = int(model.geom_type[g])  # numpy ints never equal MuJoCo's enums
        if model.body_weldid[model.geom_bodyid[g]] != 0 or gtype == geom.mjGEOM_PLANE:
            continue
        pos, rot, size = data.geom_xpos[g], data.geom_xmat[g].reshape(3, 3), model.geom_size[g]
        upright = abs(rot[2, 2]) > 0.999
        center = pos + rot @ model.geom_aabb[g, :3]
        half = np.abs(rot) @ model.geom_aabb[g, 3:]  # world-aligned half extents
        extents.append(np.concatenate([center[:2] - half[:2], center[:2] + half[:2]]))
        z_base, height = float(center[2] - half[2]), float(max(2 * half[2], 1e-3))
        if gtype == geom.mjGEOM_BOX and upright:
            boxes.append(Box(float(pos[0]), float(pos[1]), 2 * float(size[0]), 2 * float(size[1]),
                             height, math.atan2(rot[1, 0], rot[0, 0]), z_base, kind="obstacle"))
        elif gtype in (geom.mjGEOM_CYLINDER, geom.mjGEOM_CAPSULE, geom.mjGEOM_SPHERE) and (
                upright or gtype == geom.mjGEOM_SPHERE):
            cylinders.append(Cylinder(float(pos[0]), float(pos[1]), float(size[0]), height,
                                      z_base))
        else:
            boxes.append(Box(float(center[0]), float(center[1]), float(max(2 * half[0], 1e-3)),
                             float(max(2 * half[1], 1e-3)), height, 0.0, z_base,
                             kind="obstacle"))
    if not extents:
        raise WorldError(f"{path}: the MJCF world has no static geoms besides planes, so its "
                         "extent is unknown; add walls or obstacles to the world body")
    e = np.array(extents)
    bounds = (float(e[:, 0].min()), float(e[:, 1].min()), float(e[:, 2].max()),
              float(e[:, 3].max()))
    return WorldSpec(path.stem, bounds, tuple(boxes), tuple(cylinders), mjcf_path=path)
