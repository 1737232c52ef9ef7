"""Flight simulation: the issue's approach criteria, the thesis 1.3.2 limits, kinematic consistency."""
import math

import numpy as np
import pytest

from visland.camera import CameraModel
from visland.features import batch_R_camera_from_runway, project_runway_corners
from visland.flight import G_MPS2, FT_TO_M, simulate_flight
from visland.frames import R_ned_from_body
from visland.scenarios import BUILTIN_SCENARIOS, Scenario

ELEVEN = [f"thesis-{k}" for k in range(1, 9)] + ["ecc-1", "ecc-2", "ecc-3"]


@pytest.fixture(scope="module")
def flights():
    return {name: simulate_flight(BUILTIN_SCENARIOS[name]) for name in ELEVEN}


@pytest.mark.parametrize("name", ELEVEN)
def test_aligned_before_400_ft_and_within_limits(flights, name):
    trajectory = flights[name]
    assert trajectory.end_reason == "threshold"
    i400 = trajectory.index_at_height(400 * FT_TO_M)
    assert np.abs(trajectory.dy_m[i400:]).max() < 5.0
    report = trajectory.limits_report()
    assert all(item["ok"] for item in report.values()), report
    if name == "ecc-3":
        # ECC'15 landing 3 starts 100 m above the path at 4 km: reaching the path by 400 ft needs a mean
        # slope of 6.2 deg, beyond the -6 deg limit (the paper notes its saturated, poorer glide tracking);
        # the path is captured by 200 ft
        i200 = trajectory.index_at_height(200 * FT_TO_M)
        assert np.abs(trajectory.dgs_m[i200:]).max() < 3.0
        assert trajectory.gamma_rad.min() < math.radians(-5.5)
    else:
        assert np.abs(trajectory.dgs_m[i400:]).max() < 3.0


def test_ecc3_glide_path_is_out_of_reach_within_the_flight_path_limit():
    scenario = BUILTIN_SCENARIOS["ecc-3"]
    # straight-line bound: from the start to the point 3 m above the path at 400 ft
    height_to_lose = scenario.initial_height_m - 400 * FT_TO_M
    dx_at_400ft = -(400 * FT_TO_M - 3.0) / math.tan(math.radians(3.0))
    slope = math.degrees(math.atan(height_to_lose / (dx_at_400ft - scenario.dx_m)))
    assert slope > 6.0


@pytest.mark.parametrize("name", ELEVEN)
def test_corners_stay_in_the_image_down_to_100_ft(flights, name):
    trajectory = flights[name]
    camera = CameraModel.default()
    keep = trajectory.dh_m >= 100 * FT_TO_M
    R_cr = batch_R_camera_from_runway(trajectory.roll_rad[keep], trajectory.pitch_rad[keep],
                                      trajectory.dpsi_rad[keep], camera.mount_rpy_rad)
    _, _, visible = project_runway_corners(R_cr, trajectory.p_runway_m[keep], trajectory.runway, camera)
    assert visible.all()


def test_initial_conditions_follow_the_scenario(flights):
    trajectory = flights["thesis-6"]
    scenario = BUILTIN_SCENARIOS["thesis-6"]
    assert trajectory.dx_m[0] == pytest.approx(scenario.dx_m)
    assert trajectory.dy_m[0] == pytest.approx(scenario.dy_m)
    assert trajectory.dgs_m[0] == pytest.approx(scenario.dgs_m)
    assert math.degrees(trajectory.gamma_rad[0]) == pytest.approx(0.0)
    speed = np.linalg.norm(trajectory.v_ned_mps, axis=1)
    np.testing.assert_allclose(speed, 140 * 1852 / 3600, rtol=1e-12)      # constant airspeed, calm air
    ecc = flights["ecc-1"]
    assert math.degrees(ecc.gamma_rad[0]) == pytest.approx(-3.0)
    assert math.degrees(ecc.dpsi_rad[0]) == pytest.approx(15.0)


@pytest.mark.slow
def test_body_rates_are_the_derivative_of_the_attitude():
    # at 250 Hz: the orders are held over each step, so finite differences are only as sharp as the step
    trajectory = simulate_flight(BUILTIN_SCENARIOS["thesis-8"], rate_hz=250.0)
    dt = 1.0 / trajectory.rate_hz
    R = np.array([R_ned_from_body(r, p, h) for r, p, h in
                  zip(trajectory.roll_rad, trajectory.pitch_rad, trajectory.heading_rad)])
    skew = np.einsum("nji,njk->nik", R[1:-1], (R[2:] - R[:-2]) / (2 * dt))   # R^T R' = [w]x
    omega_fd = np.stack([skew[:, 2, 1], skew[:, 0, 2], skew[:, 1, 0]], axis=1)
    err = np.abs(omega_fd - trajectory.omega_body_rps[1:-1])
    assert np.percentile(err, 99) < 2e-3 * np.abs(trajectory.omega_body_rps).max()


def test_turns_are_coordinated(flights):
    # heading rate of a coordinated turn: g tan(phi) / V (small flight path angles)
    trajectory = flights["thesis-4"]
    heading_rate = np.gradient(np.unwrap(trajectory.heading_rad), trajectory.t_s)
    expected = G_MPS2 * np.tan(trajectory.roll_rad) / np.linalg.norm(trajectory.v_ned_mps[:, :2], axis=1)
    # steady part of the turns: while rolling, the nose swings about the velocity vector (body pitched by alpha)
    banked = (np.abs(trajectory.roll_rad) > math.radians(10)) & (np.abs(trajectory.roll_rate_rps) < math.radians(0.5))
    assert banked.sum() > 50
    np.testing.assert_allclose(heading_rate[banked], expected[banked], rtol=0.08)


def test_ground_track_includes_the_wind():
    scenario = BUILTIN_SCENARIOS["dickmanns-wind"]
    trajectory = simulate_flight(scenario)
    i400 = trajectory.index_at_height(400 * FT_TO_M)
    assert np.abs(trajectory.dy_m[i400:]).max() < 5.0
    # after the crosswind onset the aircraft crabs: heading and ground track differ
    v_runway = trajectory.v_runway_mps
    track = np.arctan2(v_runway[:, 1], v_runway[:, 0])
    crab = np.degrees(trajectory.dpsi_rad - track)
    assert np.abs(crab[-50:]).max() > 0.5
    assert trajectory.wind_ned_mps[0].any() == False  # noqa: E712 (calm before the onset)


def test_a_100_s_approach_flies_to_the_threshold_crossing():
    """The long approach of ``visland bench`` and the README (its speed is measured there, not here)."""
    scenario = Scenario("long", -7500.0, 150.0, -20.0, 5.0)
    trajectory = simulate_flight(scenario)
    assert trajectory.end_reason == "threshold" and trajectory.duration_s > 95.0
    assert len(trajectory.t_s) == round(trajectory.duration_s * 50.0) + 1
    # one 50 Hz step past the threshold, on the centre line, at the 3 deg glide path's crossing height
    assert 0.0 <= trajectory.p_runway_m[-1, 0] < trajectory.v_runway_mps[-1, 0] / 50.0
    assert abs(trajectory.dy_m[-1]) < 0.1
    assert trajectory.dh_m[-1] == pytest.approx(320.0 * math.tan(math.radians(3.0)), abs=0.5)
