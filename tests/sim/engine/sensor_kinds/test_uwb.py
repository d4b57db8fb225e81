"""UWB ranging against analytic answers: the Euclidean distance to an anchor and to the goal's
tag, the positive bias when a box blocks the line of sight (means over many samples), the
noise and the dropout rate, the spec's checks and the sensor's registration."""

from __future__ import annotations

import math

import mujoco
import numpy as np
import pytest

from pic4rl_base.errors import ConfigError
from pic4rl_base.geometry import Pose2D
from pic4rl_sim.engine.sensor_kinds.uwb import UwbSpec, UwbTag

BLOCK = '<geom type="box" pos="2 0 1" size="0.1 1 1"/>'  # between (0, 0) and (4, 0), 2 m tall


ORIGIN = Pose2D(0.0, 0.0, 0.0)


def tag(geoms: str, spec: UwbSpec) -> tuple[UwbTag, mujoco.MjData]:
    xml = f"""<mujoco><worldbody><geom name="floor" type="plane" size="0 0 1"/>{geoms}
      <body name="robot"><geom type="box" size="0.2 0.2 0.2" pos="0 0 0.2"/></body>
      </worldbody></mujoco>"""
    model = mujoco.MjModel.from_xml_string(xml)
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    return UwbTag(model, spec, exclude_body=model.body("robot").id), data


def samples(geoms: str, spec: UwbSpec, n: int, goal=(0.0, 0.0),
            pose: Pose2D = ORIGIN) -> np.ndarray:
    sensor, data = tag(geoms, spec)
    rng = np.random.default_rng(7)
    out = []
    for t in range(n):
        data.time = t  # a new instant: a new draw
        out.append(sensor.read(data, pose, goal, rng))
    return np.array(out)


ANCHORS = UwbSpec(anchors_xy_m=(4.0, 0.0, 0.0, 3.0, -2.0, -2.0), goal_tag=False,
                  noise_std_m=0.0, nlos_bias_m=0.0)


def test_the_ranges_are_the_3d_distances_from_the_tag_to_each_anchor_and_the_goal() -> None:
    spec = UwbSpec(anchors_xy_m=(4.0, 0.0, 0.0, 3.0), anchor_height_m=2.4, goal_tag=True,
                   goal_tag_height_m=1.0, noise_std_m=0.0, mount_xyz_m=(0.1, 0.0, 0.4))
    pose = Pose2D(0.5, -0.5, math.pi / 2)  # the tag at (0.5, -0.4, 0.4)
    ranges = samples("", spec, 1, goal=(-3.0, 2.0), pose=pose)[0]
    expected = [math.dist((0.5, -0.4, 0.4), p) for p in
                ((4.0, 0.0, 2.4), (0.0, 3.0, 2.4), (-3.0, 2.0, 1.0))]
    assert ranges.dtype == np.float32 and spec.targets == ("a0", "a1", "goal")
    np.testing.assert_allclose(ranges, expected, atol=1e-5)


def test_a_box_on_the_line_of_sight_adds_a_positive_bias_of_the_stated_mean() -> None:
    spec = UwbSpec(anchors_xy_m=(4.0, 0.0, 0.0, 3.0), goal_tag=False, noise_std_m=0.1,
                   nlos_bias_m=0.4)
    ranges = samples(BLOCK, spec, 4000)
    blocked, clear = ranges[:, 0], ranges[:, 1]
    d_blocked = math.dist((0, 0, 0.4), (4, 0, 2))
    d_clear = math.dist((0, 0, 0.4), (0, 3, 2))
    assert clear.mean() == pytest.approx(d_clear, abs=0.01)
    assert clear.std() == pytest.approx(0.1, rel=0.05)
    assert blocked.mean() - d_blocked == pytest.approx(0.4, abs=0.03)
    # noise and an exponential of mean b: variance σ² + b²
    assert blocked.std() == pytest.approx(math.hypot(0.1, 0.4), rel=0.06)
    unblocked = samples("", spec, 2000)[:, 0]
    assert unblocked.mean() == pytest.approx(d_blocked, abs=0.01)


def test_a_line_of_sight_passing_over_a_low_box_is_clear() -> None:
    low = '<geom type="box" pos="2 0 0.1" size="0.1 1 0.1"/>'
    spec = UwbSpec(anchors_xy_m=(4.0, 0.0), goal_tag=False, noise_std_m=0.0, nlos_bias_m=1.0)
    assert samples(low, spec, 1)[0, 0] == pytest.approx(math.dist((0, 0, 0.4), (4, 0, 2)),
                                                      abs=1e-5)
    assert samples(BLOCK, spec, 50)[:, 0].min() > math.dist((0, 0, 0.4), (4, 0, 2))


def test_dropouts_and_range_limit() -> None:
    spec = UwbSpec(anchors_xy_m=(4.0, 0.0), goal_tag=True, noise_std_m=0.0, dropout_prob=0.25)
    ranges = samples("", spec, 4000, goal=(1.0, 1.0))
    lost = np.isposinf(ranges).mean(axis=0)
    np.testing.assert_allclose(lost, [0.25, 0.25], atol=0.02)
    far = UwbSpec(anchors_xy_m=(40.0, 0.0), goal_tag=False, noise_std_m=0.0, range_max_m=30.0)
    assert np.isposinf(samples("", far, 1)[0, 0])


def test_one_instant_is_one_draw() -> None:
    sensor, data = tag("", UwbSpec(anchors_xy_m=(4.0, 0.0)))
    rng = np.random.default_rng(0)
    first = sensor.read(data, Pose2D(0, 0, 0), (1.0, 1.0), rng)
    assert sensor.read(data, Pose2D(0, 0, 0), (1.0, 1.0), rng) is first
    assert sensor.read(data, Pose2D(0, 0, 0), (2.0, 1.0), rng)[1] != first[1]  # a new goal


@pytest.mark.parametrize(("changes", "message"), [
    ({"anchors_xy_m": (1.0, 2.0, 3.0)}, "uwb.anchors_xy_m"),
    ({"anchors_xy_m": tuple(float(i) for i in range(10))}, "at most 4 anchors"),
    ({"anchors_xy_m": (1.0, math.nan)}, "uwb.anchors_xy_m"),
    ({"anchors_xy_m": (), "goal_tag": False}, "uwb.goal_tag"),
    ({"nlos_bias_m": -1.0}, "uwb.nlos_bias_m"),
])
def test_bad_settings_name_their_key(changes, message) -> None:
    with pytest.raises(ConfigError, match=message):
        UwbSpec(**changes)


def test_it_is_registered_off_by_default() -> None:
    import pic4rl_bridge  # noqa: F401 - the tables, loaded as a program loads them
    from pic4rl_bridge.readings.sensor_table import BY_NAME
    from pic4rl_sim.engine.robot_specs import JACKAL
    from pic4rl_sim.engine.sensors import KINDS_BY_NAME
    from pic4rl_sim.interfaces import RECORDED, interface

    assert KINDS_BY_NAME["uwb"].optional and not KINDS_BY_NAME["uwb"].carried
    assert JACKAL.sensors["uwb"] is None
    assert interface("uwb/a3").type == interface("uwb/goal").type == "sensor_msgs/msg/Range"
    assert interface("uwb/anchors").qos.value.transient_local
    assert not any(name.startswith("uwb") for name in RECORDED)
    assert BY_NAME["uwb_goal"].interface.name == "uwb/goal"


def test_the_engine_ranges_to_the_goal_it_samples() -> None:
    from pic4rl_sim.engine.core import Engine
    from pic4rl_sim.engine.robot_specs import JACKAL
    from pic4rl_sim.engine.worlds.spec import WorldSpec

    spec = UwbSpec(anchors_xy_m=(5.0, 5.0), noise_std_m=0.0)
    engine = Engine(JACKAL.with_sensors(uwb=spec), WorldSpec("field", (-20, -20, 20, 20)),
                    seed=3)
    engine.reset(start=Pose2D(0.0, 0.0, 0.0), goal=(-6.0, 8.0))
    ranges = engine.read("uwb")
    assert ranges[0] == pytest.approx(math.dist((0, 0, 0.4), (5, 5, 2)), abs=1e-4)
    assert ranges[1] == pytest.approx(math.dist((0, 0, 0.4), (-6, 8, 1)), abs=1e-4)
