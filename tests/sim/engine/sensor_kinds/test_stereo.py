"""The stereo depth camera against analytic answers: depth from quantised disparity, its
error's standard deviation growing as z²·subpixel/(f·B), the limits of the disparity search
and of depth, the bands an occluding edge hides from the right camera, the disparity image's
consistency with depth, and the sensor's registration."""

from __future__ import annotations

import math

import mujoco
import numpy as np
import pytest

from pic4rl_base.errors import ConfigError
from pic4rl_base.geometry import Pose2D
from pic4rl_sim.engine.sensor_kinds.stereo import INVALID_DISPARITY, StereoCamera, StereoCameraSpec

ORIGIN = Pose2D(0.0, 0.0, 0.0)
MOUNT = (0.0, 0.0, 0.4)


def wall(z_m: float) -> str:
    """A wall facing the camera, its face ``z_m`` ahead of the mount."""
    return f'<geom type="box" pos="{z_m + 0.05} 0 1" size="0.05 30 10"/>'


def camera(geoms: str, spec: StereoCameraSpec) -> tuple[StereoCamera, mujoco.MjData]:
    xml = f"""<mujoco><worldbody>{geoms}
      <body name="robot"><geom type="box" size="0.05 0.05 0.05" pos="-0.2 0 0.4"/></body>
      </worldbody></mujoco>"""
    model = mujoco.MjModel.from_xml_string(xml)
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    return StereoCamera(model, spec, exclude_body=model.body("robot").id), data


def test_a_wall_reads_its_depth_within_half_a_disparity_quantum() -> None:
    spec = StereoCameraSpec(subpixel_px=0.0, mount_xyz_m=MOUNT)
    cam, data = camera(wall(2.0), spec)
    depth = cam.read(data, ORIGIN, np.random.default_rng(0)).depth
    fb = spec.sensor_focal_px * spec.baseline_m
    quantum_m = 2.0**2 * spec.disparity_step_px / fb
    centre = depth[:, 10:]  # the left band is invalid (below)
    assert np.abs(centre - 2.0).max() <= 0.5 * quantum_m + 1e-6
    assert spec.sensor_focal_px == pytest.approx(446.8, abs=0.1)  # D435 at 848 px, 87°


@pytest.mark.parametrize("z_m", [1.0, 2.0, 4.0])
def test_the_depth_error_grows_as_z_squared_times_subpixel_over_f_b(z_m: float) -> None:
    spec = StereoCameraSpec(width=8, height=6, mount_xyz_m=MOUNT)
    cam, data = camera(wall(z_m), spec)
    rng = np.random.default_rng(3)
    samples = []
    for t in range(1500):
        data.time = t  # a new instant: a new draw
        samples.append(cam.read(data, ORIGIN, rng).depth[:, 4:].ravel())
    values = np.concatenate(samples)
    assert np.isfinite(values).all()
    fb = spec.sensor_focal_px * spec.baseline_m
    expected = z_m**2 * math.hypot(spec.subpixel_px, spec.disparity_step_px / 12**0.5) / fb
    assert values.std() == pytest.approx(expected, rel=0.08)
    assert values.mean() == pytest.approx(z_m, abs=0.2 * expected + 1e-3)


def test_pixels_beyond_the_range_and_inside_the_search_limit_are_invalid() -> None:
    spec = StereoCameraSpec(width=8, height=6, subpixel_px=0.0, mount_xyz_m=MOUNT)
    far, data = camera(wall(12.0), spec)
    assert np.isposinf(far.read(data, ORIGIN, np.random.default_rng(0)).depth).all()
    assert spec.min_depth_m == pytest.approx(446.8 * 0.05 / 126, rel=1e-3)
    near, data = camera(wall(0.9 * spec.min_depth_m), spec)
    reading = near.read(data, ORIGIN, np.random.default_rng(0))
    assert np.isneginf(reading.depth).all()
    assert (reading.disparity == INVALID_DISPARITY).all()
    empty, data = camera("", spec)
    assert np.isposinf(empty.read(data, ORIGIN, np.random.default_rng(0)).depth).all()


def test_an_occluding_edge_hides_a_band_from_the_right_camera() -> None:
    spec = StereoCameraSpec(subpixel_px=0.0, mount_xyz_m=MOUNT)
    alone, data = camera(wall(3.0), spec)
    plain = alone.read(data, ORIGIN, np.random.default_rng(0)).depth
    f = spec.width / spec.sensor_width_px * spec.sensor_focal_px
    band = math.ceil(f * spec.baseline_m / 3.0 - 0.5)  # pixel centres left of the disparity
    assert np.isnan(plain[:, :band]).all() and not np.isnan(plain[:, band:]).any()
    post = '<geom type="box" pos="1.05 0 1" size="0.05 0.15 10"/>'  # 0.3 m wide, 1 m ahead
    occluded, data = camera(wall(3.0) + post, spec)
    depth = occluded.read(data, ORIGIN, np.random.default_rng(0)).depth
    row = depth[spec.height // 2]
    on_post = np.flatnonzero(np.abs(row - 1.0) < 0.05)
    hidden = np.flatnonzero(np.isnan(row[band:])) + band
    # the wall just left of the post (in the image; the right camera looks past its other
    # side) is hidden from the right camera: a band as wide as the two disparities' difference
    expected = f * spec.baseline_m * (1 / 1.0 - 1 / 3.0)
    assert len(on_post) > 0 and len(hidden) > 0
    assert hidden.max() == on_post.min() - 1
    assert abs(len(hidden) - expected) <= 1.0


def test_the_disparity_image_gives_the_depth_back() -> None:
    spec = StereoCameraSpec(mount_xyz_m=MOUNT)
    cam, data = camera(wall(2.5), spec)
    reading = cam.read(data, ORIGIN, np.random.default_rng(1))
    valid = np.isfinite(reading.depth)
    assert valid.mean() > 0.9
    np.testing.assert_allclose(cam.focal_px * spec.baseline_m / reading.disparity[valid],
                               reading.depth[valid], rtol=1e-5)
    assert (reading.disparity[~valid] == INVALID_DISPARITY).all()


def test_bad_settings_name_their_key() -> None:
    with pytest.raises(ConfigError, match="stereo.sensor_width_px"):
        StereoCameraSpec(width=100, sensor_width_px=80)
    with pytest.raises(ConfigError, match="stereo.baseline_m"):
        StereoCameraSpec(baseline_m=0.0)


def test_it_is_registered_off_by_default() -> None:
    import pic4rl_bridge  # noqa: F401 - the tables, loaded as a program loads them
    from pic4rl_bridge.readings.sensor_table import BY_NAME
    from pic4rl_sim.engine.robot_specs import JACKAL
    from pic4rl_sim.engine.sensors import KINDS_BY_NAME
    from pic4rl_sim.interfaces import RECORDED, interface

    assert KINDS_BY_NAME["stereo"].optional and JACKAL.sensors["stereo"] is None
    assert interface("stereo/disparity").type == "stereo_msgs/msg/DisparityImage"
    assert not any(name.startswith("stereo") for name in RECORDED)
    assert BY_NAME["stereo_depth"].interface.name == "stereo/depth/image_raw"
