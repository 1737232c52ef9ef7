"""The inertial unit and the camera calibration error."""
import math

import numpy as np
import pytest

from visland.camera import CameraModel
from visland.flight import simulate_flight
from visland.scenarios import get_scenario
from visland.sensors import ImuParams, camera_with_calibration_error, measure_imu


@pytest.fixture(scope="module")
def trajectory():
    return simulate_flight(get_scenario("thesis-3"))


def test_perfect_imu_reports_the_truth(trajectory):
    imu = measure_imu(trajectory)
    np.testing.assert_array_equal(imu.v_ned_mps, trajectory.v_ned_mps)
    np.testing.assert_array_equal(imu.roll_rad, trajectory.roll_rad)


def test_velocity_bias_is_a_constant_relative_error(trajectory):
    imu = measure_imu(trajectory, ImuParams(velocity_bias_fraction=0.05))
    np.testing.assert_allclose(imu.v_ned_mps, 1.05 * trajectory.v_ned_mps)


def test_noise_is_seeded_and_sized(trajectory):
    params = ImuParams(attitude_noise_deg=0.1, velocity_noise_mps=0.2, seed=3)
    a, b = measure_imu(trajectory, params), measure_imu(trajectory, params)
    np.testing.assert_array_equal(a.pitch_rad, b.pitch_rad)
    assert np.std(a.v_ned_mps - trajectory.v_ned_mps) == pytest.approx(0.2, rel=0.05)
    assert np.std(np.degrees(a.roll_rad - trajectory.roll_rad)) == pytest.approx(0.1, rel=0.05)


def test_telemetry_columns_are_in_spec_units(trajectory):
    cols = measure_imu(trajectory).as_columns()
    assert list(cols) == ["t_s", "roll_deg", "pitch_deg", "heading_deg", "p_dps", "q_dps", "r_dps",
                          "vn_mps", "ve_mps", "vd_mps", "tas_mps"]
    assert list(measure_imu(trajectory, ImuParams(airspeed=False)).as_columns()) == list(cols)[:-1]
    assert np.all((cols["heading_deg"] >= 0) & (cols["heading_deg"] < 360))


def test_calibration_error_turns_the_image():
    camera = CameraModel.default(mount_rpy_deg=(0.0, 0.0, 0.0))
    mounted = camera_with_calibration_error(camera, [0.0, 0.0, 0.5])
    # yaw is positive to the right (ZYX mounting, z down): a camera yawed 0.5 deg right sees a point
    # straight ahead of the body 0.5 deg left of its axis, u decreases by fx tan(0.5 deg)
    p_body = np.array([1e6, 0.0, 0.0])
    uv_nominal, _ = camera.project(camera.R_body_from_camera.T @ p_body)
    uv_mounted, _ = mounted.project(mounted.R_body_from_camera.T @ p_body)
    assert uv_mounted - uv_nominal == pytest.approx([-camera.fx * math.tan(math.radians(0.5)), 0.0], abs=1e-6)
    # pitch is positive nose up: the same point moves down the image (v grows)
    pitched = camera_with_calibration_error(camera, [0.0, 0.5, 0.0])
    uv_pitched, _ = pitched.project(pitched.R_body_from_camera.T @ p_body)
    assert uv_pitched - uv_nominal == pytest.approx([0.0, camera.fy * math.tan(math.radians(0.5))], abs=1e-6)
    with pytest.raises(ValueError, match="calibration error"):
        camera_with_calibration_error(camera, 45.0)


def test_airspeed_is_the_air_velocity_magnitude_with_seeded_noise():
    trajectory = simulate_flight(get_scenario("dickmanns-wind"))
    air = np.linalg.norm(trajectory.v_ned_mps - trajectory.wind_ned_mps, axis=1)
    # the flight model flies at constant airspeed through the crosswind and the gust
    np.testing.assert_allclose(air, get_scenario("dickmanns-wind").airspeed_mps, rtol=1e-9)
    exact = measure_imu(trajectory, ImuParams(airspeed_noise_mps=0.0))
    np.testing.assert_allclose(exact.tas_mps, air)
    noisy = measure_imu(trajectory, ImuParams(airspeed_noise_mps=0.5, seed=4))
    assert np.std(noisy.tas_mps - air) == pytest.approx(0.5, rel=0.05)
    # switching the airspeed noise on leaves the other streams' realisations unchanged
    other = ImuParams(velocity_noise_mps=0.2, seed=4)
    a = measure_imu(trajectory, other)
    b = measure_imu(trajectory, ImuParams(velocity_noise_mps=0.2, seed=4, airspeed_noise_mps=2.0))
    np.testing.assert_array_equal(a.v_ned_mps, b.v_ned_mps)
    assert measure_imu(trajectory, ImuParams(airspeed=False)).tas_mps is None
    with pytest.raises(ValueError, match="airspeed_noise_mps"):
        ImuParams(airspeed_noise_mps=-1.0)


def _telemetry_table(t_s, heading_deg, tas=None):
    from pathlib import Path

    from visland.contracts import Table
    t_s = np.asarray(t_s, float)
    n = len(t_s)
    columns = {"t_s": t_s, "roll_deg": np.linspace(-2.0, 2.0, n), "pitch_deg": np.full(n, -3.0),
               "heading_deg": np.asarray(heading_deg, float), "p_dps": np.full(n, 1.0), "q_dps": np.zeros(n),
               "r_dps": np.zeros(n), "vn_mps": np.full(n, 70.0), "ve_mps": np.zeros(n), "vd_mps": np.full(n, 3.5)}
    if tas is not None:
        columns["tas_mps"] = np.asarray(tas, float)
    return Table(columns, Path("telemetry.csv"), list(columns))


def test_telemetry_at_frame_times_is_the_one_inertial_record():
    from visland.folder import interpolate_telemetry
    from visland.sensors import InertialSeries
    # heading crosses north between samples: 359 -> 1 deg is +2 deg, halfway is 360 (0), not 180
    table = _telemetry_table([0.0, 1.0, 2.0], [358.0, 359.0, 1.0], tas=[70.0, 71.0, 72.0])
    at_frames = interpolate_telemetry(table, [0.5, 1.5])
    assert isinstance(at_frames, InertialSeries)
    np.testing.assert_allclose(np.degrees(at_frames.heading_rad) % 360.0, [358.5, 0.0], atol=1e-9)
    np.testing.assert_allclose(np.degrees(at_frames.roll_rad), [-1.0, 1.0], atol=1e-12)
    np.testing.assert_allclose(at_frames.omega_body_rps[:, 0], math.radians(1.0))
    np.testing.assert_allclose(at_frames.v_ned_mps, [[70.0, 0.0, 3.5]] * 2)
    np.testing.assert_allclose(at_frames.tas_mps, [70.5, 71.5])


def test_one_frame_at_a_one_row_telemetry_is_accepted():
    from visland.folder import interpolate_telemetry
    at_frames = interpolate_telemetry(_telemetry_table([2.0], [90.0]), [2.0])
    np.testing.assert_allclose(np.degrees(at_frames.heading_rad), [90.0])
    assert at_frames.tas_mps is None


def test_a_frame_outside_the_telemetry_is_named():
    from visland.folder import interpolate_telemetry
    with pytest.raises(ValueError, match=r"^flight.csv: telemetry covers 0..2 s but frame 1 is at t = 2.5 s$"):
        interpolate_telemetry(_telemetry_table([0.0, 1.0, 2.0], [0.0, 0.0, 0.0]), [1.0, 2.5], source="flight.csv")
