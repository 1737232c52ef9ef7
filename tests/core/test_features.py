"""Ideal image features against independent truth.

- corner pixels of hand-computed projections (the arithmetic is written out here, not taken from
  visland.features);
- d_F turned back into the heading deviation within 1e-6 rad over +-15 deg heading and +-10 deg pitch and
  roll, and the closed form of seed 001 eq. 18 (SPEC signs) for a camera along body x;
- finite differences of the simulated measurements against the thesis feature dynamics evaluated with the
  true 1/dH: 3.24/3.29 (points in the virtual frame), 3.37/3.39 (lines). A flipped sign fails these tests.
"""
import math

import numpy as np
import pytest

from visland.camera import CameraModel
from visland.features import (batch_R_camera_from_runway, dF_from_vanishing_point, dpsi_from_dF, horizon_line,
                              ideal_features, line_dynamics_terms, observability_points,
                              point_virtual_dynamics, project_runway_corners, runway_lines, vanishing_point_xy)
from visland.flight import simulate_flight
from visland.runway import Runway
from visland.scenarios import get_scenario

CAM0 = CameraModel.default(mount_rpy_deg=(0.0, 0.0, 0.0))


def _corners(roll_deg, pitch_deg, dpsi_deg, p_runway_m, camera=CAM0, runway=Runway()):
    R_cr = batch_R_camera_from_runway(np.radians([roll_deg]), np.radians([pitch_deg]), np.radians([dpsi_deg]),
                                      camera.mount_rpy_rad)
    uv, _, visible = project_runway_corners(R_cr, np.array([p_runway_m]), runway, camera)
    return uv[0], visible[0]


def test_corner_pixels_level_and_aligned():
    # 1000 m before the threshold, 100 m up, on the centreline: near-left corner is 22.5 m left, 100 m below
    uv, visible = _corners(0, 0, 0, [-1000.0, 0.0, -100.0])
    assert uv[0, 0] == pytest.approx(1023.5 + 2472.0 * (-22.5 / 1000.0), abs=1e-9)
    assert uv[0, 1] == pytest.approx(1023.5 + 2472.0 * (100.0 / 1000.0), abs=1e-9)
    assert uv[3, 0] == pytest.approx(1023.5 + 2472.0 * (22.5 / 4000.0), abs=1e-9)
    assert uv[3, 1] == pytest.approx(1023.5 + 2472.0 * (100.0 / 4000.0), abs=1e-9)
    assert visible.all()


def test_corner_pixels_with_pitch_and_mounting():
    # body pitched up 5 deg, camera mounted 3 deg down: optical axis 2 deg above the horizon
    camera = CameraModel.default(mount_rpy_deg=(0.0, -3.0, 0.0))
    uv, _ = _corners(0, 5, 0, [-1000.0, 0.0, -100.0], camera=camera)
    t = math.radians(2.0)
    forward = math.cos(t) * 1000.0 - math.sin(t) * 100.0
    down = math.sin(t) * 1000.0 + math.cos(t) * 100.0
    assert uv[0, 0] == pytest.approx(1023.5 + 2472.0 * (-22.5 / forward), abs=1e-6)
    assert uv[0, 1] == pytest.approx(1023.5 + 2472.0 * (down / forward), abs=1e-6)


def test_corner_pixels_with_roll_and_heading():
    # roll 10 deg right wing down: the image turns by -10 deg about the optical axis
    uv, _ = _corners(10, 0, 0, [-1000.0, 0.0, -100.0])
    c, s = math.cos(math.radians(10)), math.sin(math.radians(10))
    right, down = c * -22.5 + s * 100.0, -s * -22.5 + c * 100.0
    assert uv[0, 0] == pytest.approx(1023.5 + 2472.0 * right / 1000.0, abs=1e-6)
    assert uv[0, 1] == pytest.approx(1023.5 + 2472.0 * down / 1000.0, abs=1e-6)
    # heading 10 deg right of the runway: the runway appears to the left
    uv, _ = _corners(0, 0, 10, [-1000.0, 0.0, -100.0])
    c, s = math.cos(math.radians(10)), math.sin(math.radians(10))
    forward, right = c * 1000.0 + s * -22.5, -s * 1000.0 + c * -22.5
    assert uv[0, 0] == pytest.approx(1023.5 + 2472.0 * right / forward, abs=1e-6)
    assert uv[0, 1] == pytest.approx(1023.5 + 2472.0 * 100.0 / forward, abs=1e-6)


@pytest.mark.parametrize("mount_deg", [(0.0, 0.0, 0.0), (0.0, -3.0, 0.0), (0.7, -5.0, 1.5)])
def test_dF_gives_back_the_heading_deviation(mount_deg):
    camera = CameraModel.default(mount_rpy_deg=mount_deg)
    grid = np.radians(np.linspace(-15, 15, 7))
    small = np.radians(np.linspace(-10, 10, 5))
    dpsi, pitch, roll = [a.ravel() for a in np.meshgrid(grid, small, small, indexing="ij")]
    R_cr = batch_R_camera_from_runway(roll, pitch, dpsi, camera.mount_rpy_rad)
    h_rho, h_theta = horizon_line(R_cr)
    dF = dF_from_vanishing_point(vanishing_point_xy(R_cr), h_rho, h_theta, camera)
    np.testing.assert_allclose(dpsi_from_dF(dF, roll, pitch, camera), dpsi, atol=1e-6)
    if mount_deg == (0.0, 0.0, 0.0):
        # seed 001 eq. 18 with SPEC signs: d_F = fx (tan(phi) tan(theta) - tan(dpsi) / cos(theta))
        closed = camera.fx * (np.tan(roll) * np.tan(pitch) - np.tan(dpsi) / np.cos(pitch))
        np.testing.assert_allclose(dF, closed, atol=1e-6)


def test_vanishing_point_is_where_far_edges_meet():
    # the image of a point 1e10 m down the runway is (nearly) the vanishing point
    R_cr = batch_R_camera_from_runway(np.radians([4.0]), np.radians([2.0]), np.radians([-7.0]),
                                      CameraModel.default().mount_rpy_rad)
    far = R_cr[0] @ (np.array([1e10, 0.0, 0.0]) - np.array([-2000.0, 150.0, -120.0]))
    np.testing.assert_allclose(vanishing_point_xy(R_cr)[0], far[:2] / far[2], atol=1e-6)


@pytest.fixture(scope="module")
def flown():
    """thesis-8 (a turn back to the centreline) flown at 250 Hz so that finite differences are sharp."""
    scenario = get_scenario("thesis-8")
    trajectory = simulate_flight(scenario, rate_hz=250.0)
    states = trajectory.at(trajectory.t_s)
    return scenario, trajectory, states


def _central_difference(series, dt):
    return (series[2:] - series[:-2]) / (2.0 * dt)


def test_point_dynamics_match_finite_differences(flown):
    scenario, trajectory, states = flown
    features = ideal_features(states, scenario.runway, CameraModel.default())
    dt = 1.0 / trajectory.rate_hz
    eta_true = 1.0 / (-states.p_runway_m[:, 2])
    visible = features.corners_visible[:, :2].all(axis=1)[1:-1]
    y_dot_model, eta_dot_model = point_virtual_dynamics(features.yv_near, eta_true, states.v_runway_mps)  # 3.29
    y_dot_fd = _central_difference(features.yv_near, dt)
    err = np.abs(y_dot_fd - y_dot_model[1:-1])[visible]
    scale = np.abs(y_dot_fd[visible]).max()
    assert err.max() < 1e-4 * scale
    eta_dot_fd = _central_difference(eta_true, dt)
    np.testing.assert_allclose(eta_dot_fd, eta_dot_model[1:-1], rtol=0, atol=1e-4 * np.abs(eta_dot_fd).max())
    # observability (3.30) is |y_v'|^2 / eta^2 summed over both points: independent of the formula's form
    obs_fd = np.sum(y_dot_fd ** 2, axis=(1, 2)) / eta_true[1:-1] ** 2
    obs = observability_points(features.yv_near, states.v_runway_mps)[1:-1]
    np.testing.assert_allclose(obs[visible], obs_fd[visible], rtol=2e-3, atol=1e-6 * obs.max())


def test_line_dynamics_match_finite_differences(flown):
    scenario, trajectory, states = flown
    camera = CameraModel.default()
    R_cr = batch_R_camera_from_runway(states.roll_rad, states.pitch_rad, states.dpsi_rad, camera.mount_rpy_rad)
    lines = runway_lines(R_cr, states.p_runway_m, scenario.runway)
    v_C = np.einsum("nij,nj->ni", R_cr, states.v_runway_mps)
    w_C = states.omega_body_rps @ camera.R_body_from_camera   # R_camera_from_body @ w_B
    n_C = R_cr[:, :, 2]
    eta = 1.0 / (-states.p_runway_m[:, 2])
    dt = 1.0 / trajectory.rate_hz
    for name in ("left", "right", "center"):
        rho, theta = lines[name]
        g, phi = line_dynamics_terms(rho, theta, v_C, w_C, n_C)          # 3.37
        model = (g + phi * eta[:, None])[1:-1]
        fd = np.stack([_central_difference(theta, dt), _central_difference(rho, dt)], axis=1)
        err = np.abs(fd - model)
        scale = np.abs(fd).max(axis=0)
        assert np.percentile(err, 99.5, axis=0).max() < 2e-3 * scale.max(), name
        late = states.t_s[1:-1] > 45.0
        assert np.abs(fd - model)[late].max() < 1e-3 * scale.max(), name
        if name != "center":
            # on the edges the eta term is most of the late motion, so dropping or flipping it would
            # break the agreement (the centre line barely moves once aligned)
            assert np.abs(phi[1:-1] * eta[1:-1, None])[late].max() > 0.5 * np.abs(fd[late]).max()
            assert np.abs(fd - model)[late].max() < 1e-3 * np.abs(fd[late]).max()


def test_line_observability_is_zero_in_level_flight_parallel_to_the_runway(flown):
    # thesis Fig. 3.10: at the start (level, along the runway direction) the edges do not move
    scenario = get_scenario("thesis-1")
    trajectory = simulate_flight(scenario)
    states = trajectory.at(trajectory.t_s[:5])
    features = ideal_features(states, scenario.runway, CameraModel.default())
    assert features.obs_lines[0] < 1e-20
    later = trajectory.at([30.0])
    assert ideal_features(later, scenario.runway, CameraModel.default()).obs_lines[0] > 1e-6


def test_noise_is_seeded_and_has_the_requested_size(flown):
    scenario, _, states = flown
    camera = CameraModel.default()
    clean = ideal_features(states, scenario.runway, camera)
    noisy_a = ideal_features(states, scenario.runway, camera, pixel_noise_px=5.0, rng=np.random.default_rng(7))
    noisy_b = ideal_features(states, scenario.runway, camera, pixel_noise_px=5.0, rng=np.random.default_rng(7))
    np.testing.assert_array_equal(noisy_a.corners_uv, noisy_b.corners_uv)
    diff = (noisy_a.corners_uv - clean.corners_uv)[np.isfinite(clean.corners_uv)]
    assert np.std(diff) == pytest.approx(5.0, rel=0.03)
    with pytest.raises(ValueError, match="rng"):
        ideal_features(states, scenario.runway, camera, pixel_noise_px=1.0)


# --------------------------------------------------------------------------- sloped runway
def test_sloped_runway_corners_and_edges_by_hand():
    # 1 % uphill, 3000 m long: the far end is 30 m above the threshold (z = -30 in R, z down).
    # Camera level and aligned, 1000 m before the threshold, 100 m up: the far corners are
    # 130 m below the camera at 4000 m ahead, the near ones 100 m below at 1000 m.
    runway = Runway(slope_pct=1.0)
    uv, visible = _corners(0, 0, 0, [-1000.0, 0.0, -100.0], runway=runway)
    assert uv[0, 1] == pytest.approx(1023.5 + 2472.0 * 100.0 / 1000.0, abs=1e-9)
    assert uv[2, 0] == pytest.approx(1023.5 + 2472.0 * (-22.5 / 4000.0), abs=1e-9)
    assert uv[2, 1] == pytest.approx(1023.5 + 2472.0 * (70.0 / 4000.0), abs=1e-9)
    assert visible.all()
    # the edge lines pass through both corners of their side and through a mid-runway point
    R_cr = batch_R_camera_from_runway(np.zeros(1), np.zeros(1), np.zeros(1), CAM0.mount_rpy_rad)
    lines = runway_lines(R_cr, np.array([[-1000.0, 0.0, -100.0]]), runway)
    mid = np.array([1500.0 + 1000.0, -22.5, 100.0 - 15.0])        # x = 1500 m on the left edge, 15 m up
    for name, pts in (("left", [uv[0], uv[2], CAM0.fx * mid[1:] / mid[0] + 1023.5]),):
        rho, theta = lines[name]
        for u, v in pts:
            x, y = (u - 1023.5) / 2472.0, (v - 1023.5) / 2472.0
            assert x * math.cos(theta[0]) + y * math.sin(theta[0]) == pytest.approx(rho[0], abs=1e-12)


def test_sloped_runway_vanishing_point_is_above_the_horizon_by_the_slope():
    runway = Runway(slope_pct=1.5)
    R_cr = batch_R_camera_from_runway(np.zeros(1), np.zeros(1), np.zeros(1), CAM0.mount_rpy_rad)
    vp = vanishing_point_xy(R_cr, runway.direction_runway())[0]
    assert vp[0] == pytest.approx(0.0, abs=1e-15)
    assert vp[1] == pytest.approx(-0.015, abs=1e-12)           # y down: 1.5 % above the level horizon
    # the surface holds all four corners and the normal is orthogonal to the centreline and to y
    corners = runway.corners_runway_m()
    np.testing.assert_allclose(corners[:, 2], runway.surface_z_m(corners[:, 0]))
    assert runway.normal_runway() @ runway.direction_runway() == pytest.approx(0.0, abs=1e-15)
    assert runway.normal_runway() @ (corners[2] - corners[1]) == pytest.approx(0.0, abs=1e-9)


def test_sloped_runway_labels_follow_the_flown_corners(flown):
    # labels on a sloped runway: the far corners' pixels are those of points on z = -x s (checked
    # against a projection written here), the near ones are unchanged by the slope
    scenario, _, states = flown
    camera = CameraModel.default()
    sloped = Runway(slope_pct=-1.2)
    a = ideal_features(states, scenario.runway, camera)
    b = ideal_features(states, sloped, camera)
    np.testing.assert_allclose(a.corners_uv[:, :2], b.corners_uv[:, :2], atol=1e-9)
    i = len(states.t_s) // 2
    R_cr = batch_R_camera_from_runway(states.roll_rad[i:i + 1], states.pitch_rad[i:i + 1], states.dpsi_rad[i:i + 1],
                                      camera.mount_rpy_rad)[0]
    far_left = np.array([sloped.length_m, -sloped.width_m / 2, 0.012 * sloped.length_m])   # downhill: lower
    p_C = R_cr @ (far_left - states.p_runway_m[i])
    expected = np.array([camera.fx * p_C[0] / p_C[2] + camera.cx, camera.fy * p_C[1] / p_C[2] + camera.cy])
    np.testing.assert_allclose(b.corners_uv[i, 2], expected, atol=1e-6)
