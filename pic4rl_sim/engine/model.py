"""MuJoCo model of a robot in a world, built with ``mujoco.MjSpec``.

The base is planar (slide x, slide y, hinge yaw) and driven by three velocity servos at a
body-fixed site: forward, lateral and yaw. Servo forces are capped at mass × acceleration
limit, so a commanded step gives a physical ramp, and a wall stops the robot by contact.
A differential-drive robot's lateral servo holds zero velocity with the wheels' grip
(friction × weight): the non-holonomic constraint, with skidding if something pushes harder.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import mujoco

from ..errors import WorldError
from .crowd.params import CrowdParams
from .robot_specs import Drive, RobotSpec
from .sensors import STANDARD_GRAVITY_M_S2
from .worlds.spec import WorldSpec

ROBOT_BODY = "pic4rl_robot"
PERSON_BODY = "pic4rl_person"
CROWD_BODY = "pic4rl_crowd"  # + the person's index in the crowd
MOVER_BODY = "pic4rl_mover"  # + the moving obstacle's index in ``WorldSpec.moving``
# Collision bits: the robot's geom also accepts bit 2, which only the crowd's people and the
# moving obstacles carry, so they touch the robot and nothing else (not the walls, not each
# other); the walls and the single person keep MuJoCo's default bit 1.
_CROWD_CONTYPE = 2
SERVO_TIME_CONSTANT_S = 0.01  # velocity servos settle this fast below their force caps
GRIP_TIME_CONSTANT_S = 0.001  # a wheel's sideways grip is stiff: slip = v·ω·this on an arc
WHEEL_GRIP = 1.0  # friction coefficient of the wheels on the floor (lateral force cap / weight)
GROUND_CLEARANCE_M = 0.02  # the robot's geom floats this high: it never touches the floor

_RGBA = {
    "wall": (0.75, 0.75, 0.72, 1.0),
    "furniture": (0.55, 0.38, 0.22, 1.0),
    "obstacle": (0.35, 0.45, 0.6, 1.0),
    "trunk": (0.4, 0.26, 0.13, 1.0),
    "canopy": (0.2, 0.55, 0.2, 1.0),
    "post": (0.6, 0.6, 0.58, 1.0),
    "person": (0.9, 0.55, 0.2, 1.0),
}


@dataclass(frozen=True)
class ModelIds:
    """Indices into the compiled model, so no other code reads raw ``qpos`` offsets."""

    robot_body: int
    robot_geom: int
    qpos_x: int
    qpos_y: int
    qpos_yaw: int
    dof_x: int
    dof_y: int
    dof_yaw: int
    act_vx: int
    act_vy: int
    act_wz: int
    person_mocap: int  # -1 when the world has no person
    crowd_mocap: tuple[int, ...] = ()  # the crowd's people, in the crowd's order
    mover_mocap: tuple[int, ...] = ()  # the moving obstacles, in ``WorldSpec.moving``'s order


def yaw_inertia_kg_m2(robot: RobotSpec) -> float:
    """Moment of inertia about the vertical axis of a uniform box or cylinder (kg m²)."""
    fp = robot.footprint
    if fp.radius_m is not None:
        return 0.5 * robot.mass_kg * fp.radius_m**2
    return robot.mass_kg * (fp.length_m**2 + fp.width_m**2) / 12.0  # type: ignore[operator]


def _add_world(spec: mujoco.MjSpec, world: WorldSpec) -> None:
    """Floor, light and obstacles of a generated world (a user's MJCF file has its own), the
    person as a mocap body that the engine moves along its waypoints, and the moving
    obstacles as mocap bodies that it moves on their trajectories."""
    body = spec.worldbody
    if world.mjcf_path is None:
        body.add_geom(name="floor", type=mujoco.mjtGeom.mjGEOM_PLANE, size=[0, 0, 0.05],
                      contype=0, conaffinity=0, rgba=[0.9, 0.9, 0.88, 1])
        body.add_light(pos=[0, 0, 10], dir=[0, 0, -1])  # for viewers; sensors need none
        for i, box in enumerate(world.boxes):
            body.add_geom(
                name=f"box{i}_{box.kind}", type=mujoco.mjtGeom.mjGEOM_BOX,
                size=[box.size_x_m / 2, box.size_y_m / 2, box.height_m / 2],
                pos=[box.x, box.y, box.z_base_m + box.height_m / 2],
                quat=[math.cos(box.yaw_rad / 2), 0, 0, math.sin(box.yaw_rad / 2)],
                rgba=_RGBA.get(box.kind, _RGBA["obstacle"]),
            )
        for i, cyl in enumerate(world.cylinders):
            body.add_geom(
                name=f"cylinder{i}_{cyl.kind}", type=mujoco.mjtGeom.mjGEOM_CYLINDER,
                size=[cyl.radius_m, cyl.height_m / 2, 0],
                pos=[cyl.x, cyl.y, cyl.z_base_m + cyl.height_m / 2],
                rgba=_RGBA.get(cyl.kind, _RGBA["obstacle"]),
            )
    if world.person is not None:
        p = world.person
        person = body.add_body(name=PERSON_BODY, mocap=True)
        person.add_geom(name="person", type=mujoco.mjtGeom.mjGEOM_CYLINDER,
                        size=[p.radius_m, p.height_m / 2, 0], pos=[0, 0, p.height_m / 2],
                        rgba=_RGBA["person"])
    if world.moving is not None:
        m = world.moving
        for i, (x, y) in enumerate(m.starts):
            mover = body.add_body(name=f"{MOVER_BODY}{i}", mocap=True, pos=[x, y, 0])
            mover.add_geom(name=f"{MOVER_BODY}{i}_geom", type=mujoco.mjtGeom.mjGEOM_CYLINDER,
                           size=[m.radius_m, m.height_m / 2, 0], pos=[0, 0, m.height_m / 2],
                           rgba=_RGBA["obstacle"], contype=_CROWD_CONTYPE, conaffinity=0)


def _add_crowd(spec: mujoco.MjSpec, crowd: CrowdParams) -> None:
    """The crowd's people: mocap cylinders that the engine moves (``crowd.Crowd``)."""
    for i in range(crowd.count):
        person = spec.worldbody.add_body(name=f"{CROWD_BODY}{i}", mocap=True)
        person.add_geom(name=f"{CROWD_BODY}{i}_geom", type=mujoco.mjtGeom.mjGEOM_CYLINDER,
                        size=[crowd.radius_m, crowd.height_m / 2, 0],
                        pos=[0, 0, crowd.height_m / 2], rgba=_RGBA["person"],
                        contype=_CROWD_CONTYPE, conaffinity=0)


def _add_robot(spec: mujoco.MjSpec, robot: RobotSpec) -> None:
    fp = robot.footprint
    body = spec.worldbody.add_body(name=ROBOT_BODY, pos=[0, 0, 0])
    for name, axis in (("x", [1, 0, 0]), ("y", [0, 1, 0])):
        body.add_joint(name=f"{ROBOT_BODY}_{name}", type=mujoco.mjtJoint.mjJNT_SLIDE, axis=axis)
    body.add_joint(name=f"{ROBOT_BODY}_yaw", type=mujoco.mjtJoint.mjJNT_HINGE, axis=[0, 0, 1])
    half_h = (robot.height_m - GROUND_CLEARANCE_M) / 2
    z = GROUND_CLEARANCE_M + half_h
    izz = yaw_inertia_kg_m2(robot)
    inertia = [izz, izz, izz]  # only yaw turns; x and y equal to it keep the tensor valid
    body.add_geom(
        name=f"{ROBOT_BODY}_footprint",
        type=mujoco.mjtGeom.mjGEOM_CYLINDER if fp.is_circle else mujoco.mjtGeom.mjGEOM_BOX,
        size=([fp.radius_m, half_h, 0] if fp.is_circle
              else [fp.length_m / 2, fp.width_m / 2, half_h]),
        pos=[0, 0, z], rgba=[0.15, 0.15, 0.15, 1], mass=0, conaffinity=1 | _CROWD_CONTYPE,
    )
    body.mass = robot.mass_kg
    body.inertia = inertia
    body.explicitinertial = True
    body.add_site(name=f"{ROBOT_BODY}_base", pos=[0, 0, 0])
    weight_n = robot.mass_kg * STANDARD_GRAVITY_M_S2
    lateral_cap = (robot.mass_kg * robot.max_linear_accel_m_s2 if robot.drive is Drive.OMNI
                   else WHEEL_GRIP * weight_n)
    grip = SERVO_TIME_CONSTANT_S / GRIP_TIME_CONSTANT_S
    lateral_gain = 1.0 if robot.drive is Drive.OMNI else grip
    servos = (
        ("vx", [1, 0, 0, 0, 0, 0], robot.mass_kg, robot.mass_kg * robot.max_linear_accel_m_s2),
        ("vy", [0, 1, 0, 0, 0, 0], robot.mass_kg * lateral_gain, lateral_cap),
        ("wz", [0, 0, 0, 0, 0, 1], izz, izz * robot.max_angular_accel_rad_s2),
    )
    for name, gear, inertia_1d, force_cap in servos:  # kv = inertia / time constant
        act = spec.add_actuator(name=f"{ROBOT_BODY}_{name}", target=f"{ROBOT_BODY}_base",
                                trntype=mujoco.mjtTrn.mjTRN_SITE, gear=gear)
        act.set_to_velocity(kv=inertia_1d / SERVO_TIME_CONSTANT_S)
        act.forcelimited = True
        act.forcerange = [-force_cap, force_cap]


def build_model(robot: RobotSpec, world: WorldSpec, *, physics_dt_s: float,
                crowd: CrowdParams = CrowdParams()) -> tuple[mujoco.MjModel, ModelIds]:
    """Compile ``robot`` in ``world`` (generated, or the user's MJCF file) at ``physics_dt_s``,
    with ``crowd``'s people."""
    if world.mjcf_path is not None:
        try:
            spec = mujoco.MjSpec.from_file(str(world.mjcf_path))
        except Exception as err:  # MuJoCo raises ValueError or its own error types
            raise WorldError(f"{str(world.mjcf_path)!r}: MuJoCo cannot parse it: {err}") from err
    else:
        spec = mujoco.MjSpec()
        spec.modelname = f"pic4rl_{world.name}"
    spec.option.timestep = physics_dt_s
    # Fully implicit: with the stiff wheel grip, implicitfast lets arcs drift by centimetres.
    spec.option.integrator = mujoco.mjtIntegrator.mjINT_IMPLICIT
    _add_world(spec, world)
    _add_crowd(spec, crowd)
    _add_robot(spec, robot)
    try:
        model = spec.compile()
    except Exception as err:
        where = str(world.mjcf_path) if world.mjcf_path else f"world {world.name!r}"
        raise WorldError(f"{where}: the model does not compile with the robot: {err}") from err
    return model, _ids(model, world, crowd.count)


def _ids(model: mujoco.MjModel, world: WorldSpec, people: int) -> ModelIds:
    def joint(name: str) -> mujoco._structs._MjModelJointViews:
        return model.joint(f"{ROBOT_BODY}_{name}")

    person = -1
    if world.person is not None:
        person = int(model.body_mocapid[model.body(PERSON_BODY).id])
    return ModelIds(
        robot_body=model.body(ROBOT_BODY).id,
        robot_geom=model.geom(f"{ROBOT_BODY}_footprint").id,
        qpos_x=int(joint("x").qposadr[0]), qpos_y=int(joint("y").qposadr[0]),
        qpos_yaw=int(joint("yaw").qposadr[0]),
        dof_x=int(joint("x").dofadr[0]), dof_y=int(joint("y").dofadr[0]),
        dof_yaw=int(joint("yaw").dofadr[0]),
        act_vx=model.actuator(f"{ROBOT_BODY}_vx").id, act_vy=model.actuator(f"{ROBOT_BODY}_vy").id,
        act_wz=model.actuator(f"{ROBOT_BODY}_wz").id,
        person_mocap=person,
        crowd_mocap=tuple(int(model.body_mocapid[model.body(f"{CROWD_BODY}{i}").id])
                          for i in range(people)),
        mover_mocap=tuple(int(model.body_mocapid[model.body(f"{MOVER_BODY}{i}").id])
                          for i in range(len(world.moving.starts) if world.moving else 0)),
    )
