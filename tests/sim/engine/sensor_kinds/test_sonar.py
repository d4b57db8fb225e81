"""The sonar ring against analytic answers: a wall at a known distance inside a cone, a wall
between cones, its noise and dropouts, the floor, and its registration in the sim's and the
bridge's tables."""

from __future__ import annotations

import math

import mujoco
import numpy as np
import pytest

from pic4rl_base.geometry import Pose2D
from pic4rl_sim.engine.sensor_kinds.sonar import MAX_CONES, SonarRing, SonarSpec


def world(geoms: str) -> tuple[mujoco.MjModel, mujoco.MjData, int]:
    xml = f"""<mujoco><worldbody><geom name="floor" type="plane" size="0 0 1"/>{geoms}
      <body name="robot"><geom type="box" size="0.1 0.1 0.1" pos="0 0 0.2"/></body>
      </worldbody></mujoco>"""
    model = mujoco.MjModel.from_xml_string(xml)
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    return model, data, model.body("robot").id


def panel(distance_m: float, bearing_rad: float, half_width_m: float) -> str:
    """A tall panel whose near face is ``distance_m`` ahead along +x, centred on a bearing."""
    y = distance_m * math.tan(bearing_rad)
    return (f'<geom type="box" pos="{distance_m + 0.05} {y} 1" '
            f'size="0.05 {half_width_m} 1"/>')


ORIGIN = Pose2D(0.0, 0.0, 0.0)


def read(geoms: str, spec: SonarSpec, pose: Pose2D = ORIGIN,
         seed: int = 0) -> np.ndarray:
    model, data, robot = world(geoms)
    return SonarRing(model, spec, exclude_body=robot).read(data, pose, np.random.default_rng(seed))


EXACT = SonarSpec(noise_std_m=0.0)


@pytest.mark.parametrize("distance_m", [0.5, 1.3, 2.0, 4.2])
def test_a_wall_across_a_cone_s_axis_reads_its_distance(distance_m: float) -> None:
    ranges = read(panel(distance_m, 0.0, 3.0), EXACT)
    assert ranges.dtype == np.float32 and ranges.shape == (8,)
    assert ranges[0] == pytest.approx(distance_m, abs=1e-5)
    assert np.isposinf(ranges[3:6]).all()  # the cones facing away


def test_a_panel_off_the_axis_but_inside_the_cone_reads_within_the_cone_s_slant() -> None:
    ranges = read(panel(2.0, math.radians(10.0), 0.15), EXACT)
    assert 2.0 <= ranges[0] <= 2.0 / math.cos(math.radians(15.0))
    assert np.isinf(ranges[1:]).all()


def test_a_panel_between_two_cones_reads_beyond_range() -> None:
    ranges = read(panel(2.0, math.radians(22.5), 0.1), EXACT)  # cones at 0 and 45°, ±15°
    assert np.isposinf(ranges).all()
    wide = read(panel(2.0, math.radians(22.5), 0.1), SonarSpec(noise_std_m=0.0, cone_deg=60.0))
    assert np.isfinite(wide[:2]).all()  # 60° cones overlap at 22.5°


def test_the_ring_turns_with_the_robot_and_ignores_the_floor() -> None:
    geoms = '<geom type="box" pos="0 2.05 1" size="3 0.05 1"/>'  # a wall 2 m to the left
    ranges = read(geoms, EXACT, Pose2D(0.0, 0.0, math.pi / 2))
    assert ranges[0] == pytest.approx(2.0, abs=1e-5)
    assert np.isposinf(read("", SonarSpec(cone_deg=120.0))).all()  # the floor: no echo


def test_limits_and_a_narrower_arc() -> None:
    assert np.isneginf(read(panel(0.1, 0.0, 3.0), EXACT)[0])
    assert np.isposinf(read(panel(5.5, 0.0, 3.0), EXACT)[0])
    spec = SonarSpec(count=3, fov_deg=90.0, noise_std_m=0.0)
    assert np.degrees(spec.cone_yaws_rad()) == pytest.approx([-45.0, 0.0, 45.0])
    assert read(panel(1.0, 0.0, 3.0), spec)[1] == pytest.approx(1.0, abs=1e-5)


def test_noise_and_dropouts_have_their_stated_statistics() -> None:
    model, data, robot = world(panel(2.0, 0.0, 3.0))
    ring = SonarRing(model, SonarSpec(noise_std_m=0.05, dropout_prob=0.2), exclude_body=robot)
    rng = np.random.default_rng(1)
    axis = []
    for t in range(4000):
        data.time = t  # a new instant: a new draw
        axis.append(ring.read(data, Pose2D(0.0, 0.0, 0.0), rng)[0])
    axis = np.array(axis)
    kept = axis[np.isfinite(axis)]
    assert 1.0 - len(kept) / len(axis) == pytest.approx(0.2, abs=0.02)
    assert kept.mean() == pytest.approx(2.0, abs=0.005)
    assert kept.std() == pytest.approx(0.05, rel=0.05)


def test_one_instant_is_one_draw() -> None:
    model, data, robot = world(panel(2.0, 0.0, 3.0))
    ring = SonarRing(model, SonarSpec(noise_std_m=0.05), exclude_body=robot)
    rng = np.random.default_rng(0)
    first = ring.read(data, Pose2D(0.0, 0.0, 0.0), rng)
    assert ring.read(data, Pose2D(0.0, 0.0, 0.0), rng) is first
    assert ring.read(data, Pose2D(0.1, 0.0, 0.0), rng)[0] != first[0]
    again = ring.read(data, Pose2D(0.0, 0.0, 0.0), np.random.default_rng(0))  # a new episode
    assert again is not first and again[0] == first[0]  # a fresh draw, from the same seed


def test_bad_settings_name_their_key() -> None:
    with pytest.raises(Exception, match="sonar.count"):
        SonarSpec(count=MAX_CONES + 1)
    with pytest.raises(Exception, match="sonar.range_max_m"):
        SonarSpec(range_min_m=2.0, range_max_m=1.0)


def test_it_is_registered_off_by_default_and_not_recorded_by_default() -> None:
    import pic4rl_bridge  # noqa: F401 - the tables, loaded as a program loads them
    from pic4rl_bridge.readings.sensor_table import BY_NAME
    from pic4rl_sim.engine.robot_specs import JACKAL
    from pic4rl_sim.engine.sensors import KINDS_BY_NAME
    from pic4rl_sim.interfaces import RECORDED, interface

    assert KINDS_BY_NAME["sonar"].optional and not KINDS_BY_NAME["sonar"].carried
    assert JACKAL.sensors["sonar"] is None
    assert interface("sonar/cone7").type == "sensor_msgs/msg/Range"
    assert not any(name.startswith("sonar") for name in RECORDED)
    assert BY_NAME["sonar_3"].interface.name == "sonar/cone3"


def test_the_engine_reads_the_ring_of_a_robot_that_carries_one() -> None:
    from pic4rl_sim.engine.core import Engine
    from pic4rl_sim.engine.robot_specs import JACKAL
    from pic4rl_sim.engine.worlds.spec import Box, WorldSpec

    wall = Box(2.05, 0.0, 0.1, 6.0, 1.0)  # its near face 2 m ahead of the start
    world = WorldSpec("field", (-20.0, -20.0, 20.0, 20.0), boxes=(wall,))
    engine = Engine(JACKAL.with_sensors(sonar=EXACT), world, seed=3)
    engine.reset(start=Pose2D(0.0, 0.0, 0.0), goal=(-5.0, 0.0))
    ranges = engine.read("sonar")
    assert ranges[0] == pytest.approx(2.0, abs=1e-4)
    assert np.isposinf(ranges[4])
