"""The two-point observers: model by finite differences, closed forms against numpy, convergence on a flight."""
import numpy as np
import pytest

from tests.helpers.estimation_sims import prepared, simulation, true_height
from visland.estimation.points import (CCPIHG2P, _quaternion_matrix,
                                       output_combination, points_observability, points_phi,
                                       pseudo_inverse_correction)
from visland.estimation.registry import make_observer
from visland.estimation.runner import run_observer
from visland.features import observability_points
from visland.estimation.tuning import omega_for_settling_time


def _true_track(result):
    """Virtual points and eta at every 50 Hz sample, from the flown positions."""
    traj = result.trajectory
    p = traj.p_runway_m
    corners = result.scenario.runway.corners_runway_m()[:2]
    yv = (corners[None, :, :2] - p[:, None, :2]) / (-p[:, None, 2:3])
    return yv.reshape(len(p), 4), 1.0 / (-p[:, 2]), traj.v_runway_mps


def test_model_of_4_1_matches_finite_differences_of_the_flight():
    y, eta, v = _true_track(simulation())
    dt = 0.02
    for k in (100, 1000, 2500):
        fd_y = (y[k + 1] - y[k - 1]) / (2 * dt)
        fd_eta = (eta[k + 1] - eta[k - 1]) / (2 * dt)
        phi = np.array(points_phi(list(y[k]), v[k]))
        assert np.allclose(fd_y, phi * eta[k], rtol=1e-4, atol=1e-8)
        assert fd_eta == pytest.approx(v[k][2] * eta[k] ** 2, rel=1e-3, abs=1e-10)


def test_exact_prediction_between_frames_follows_the_flight():
    """Coasting from a true state reproduces the flown virtual points (the model flow is exact)."""
    result = simulation()
    y, eta, v = _true_track(result)
    prep = prepared()
    observer = CCPIHG2P()
    start = 400
    observer.reset(prep.steps[start], 1.0 / eta[start])
    for j in range(start + 1, start + 101):          # two seconds on the model alone
        observer._predict(*(0.5 * (v[j - 1] + v[j]) * 0.02), 0.02, tuple(v[j - 1]), tuple(v[j]))
    assert np.allclose(observer._y, y[start + 100], rtol=1e-6, atol=1e-9)
    assert observer._eta == pytest.approx(eta[start + 100], rel=1e-6)


def test_output_combination_derivative_is_minus_O_eta_plus_chi():
    """The corrected 4.55-4.58: d y_a/dt = -O eta + chi, checked by finite differences."""
    y, eta, v = _true_track(simulation())
    dt = 0.02
    for k in (300, 1500, 2800):
        ya = [output_combination(list(y[i]), v[i]) for i in (k - 1, k + 1)]
        fd = (ya[1] - ya[0]) / (2 * dt)
        vdot = (v[k + 1] - v[k - 1]) / (2 * dt)
        yk = y[k]
        chi = sum(vdot[0] * yk[i] + vdot[1] * yk[i + 1] - 0.5 * vdot[2] * (yk[i] ** 2 + yk[i + 1] ** 2)
                  for i in (0, 2))
        O = points_observability(list(yk), v[k])
        assert fd == pytest.approx(-O * eta[k] + chi, rel=2e-3, abs=1e-6)
        # README slip: Delta_y = -O = 2 v3 y_a - 2 (v1^2 + v2^2), not eq. 4.58 as printed
        ya_k = output_combination(list(yk), v[k])
        assert -O == pytest.approx(2 * v[k][2] * ya_k - 2 * (v[k][0] ** 2 + v[k][1] ** 2), rel=1e-9)


def test_observability_index_agrees_with_the_core_features_module():
    y, _, v = _true_track(simulation())
    k = 777
    assert points_observability(list(y[k]), v[k]) == pytest.approx(
        float(observability_points(y[k].reshape(2, 2), v[k])), rel=1e-12)


def test_pseudo_inverse_closed_form_equals_numpy_pinv():
    rng = np.random.default_rng(1)
    for m in (3, 4):
        phi = rng.normal(size=m) * 5
        b = 0.03
        kappa_y, kappa_d = rng.normal(size=m), rng.normal(size=m)
        J = np.zeros((2 * m, m + 1))
        J[:m, :m] = np.eye(m)
        J[m:, :m] = b * np.eye(m)
        J[m:, m] = phi
        expected = np.linalg.pinv(J) @ np.concatenate([kappa_y, kappa_d])
        u, s = pseudo_inverse_correction(list(phi), b, list(kappa_y), list(kappa_d))
        assert np.allclose(u, expected[:m], atol=1e-12) and s == pytest.approx(expected[m], abs=1e-12)


def test_completion_matrix_is_orthogonal_with_the_expected_determinant():
    q = (1.5, -0.7, 2.0, 0.3)
    M = np.array(_quaternion_matrix(*q))
    norm2 = sum(c * c for c in q)
    assert np.allclose(M.T @ M, norm2 * np.eye(4))
    assert np.linalg.det(M) == pytest.approx(norm2 ** 2)
    assert np.allclose(M[:, 0], q)


def test_settling_time_helper_reproduces_a_simulated_step_response():
    omega = omega_for_settling_time(6.0, 0.8)
    # simulate s^2 + 2 xi w s + w^2 step response independently (fine Euler)
    dt, x, v = 1e-4, 0.0, 0.0
    last_out = 0.0
    for k in range(int(20 / dt)):
        a = omega ** 2 * (1.0 - x) - 2 * 0.8 * omega * v
        v += a * dt
        x += v * dt
        if abs(1.0 - x) > 0.05:
            last_out = (k + 1) * dt
    assert last_out == pytest.approx(6.0, abs=0.01)


@pytest.mark.parametrize("name", ["oj-2p", "ii-2p", "cccs-2p", "ccpi-hg-2p", "ccpi-hosm-2p", "cccj-2p"])
def test_each_observer_converges_on_ideal_measurements(name):
    result = simulation()
    prep = prepared()
    dh = true_height(result)
    run = run_observer(make_observer(name), prep, 1.2 * dh[0])
    err = np.abs(dh - run.dh_m) / dh
    assert np.isnan(err[0]) and np.isfinite(err[1:]).all()     # started on the second frame
    # within 5 % of the truth for good 5 s after the start (measured: 1.2 s for ii-2p to 3.6 s for ccpi-hg-2p)
    t_s = result.frames.t_s
    assert err[t_s >= t_s[1] + 5.0].max() < 0.05
    i100 = int(np.nonzero(dh <= 30.48)[0][0])
    tolerance = {"ii-2p": 1e-2, "ccpi-hosm-2p": 1e-2}.get(name, 1e-3)
    assert abs(dh[i100] - run.dh_m[i100]) < tolerance
    assert np.nanmax(err[len(err) // 2:]) < 0.01
    # deviations from the estimate and the (filtered) corners
    assert abs(run.dx_m[i100] - (result.frames.p_runway_m[i100, 0] - 320.0)) < 0.1
    assert abs(run.dy_m[i100] - result.frames.p_runway_m[i100, 1]) < 0.05
    assert abs(run.width_m[i100] - result.scenario.runway.width_m) < 0.05


@pytest.mark.parametrize("name", ["ccpi-hg-2p", "cccs-2p"])
def test_change_of_coordinates_observers_are_accurate_to_a_millimetre_at_100_ft(name):
    result = simulation()
    dh = true_height(result)
    run = run_observer(make_observer(name), prepared(), 1.2 * dh[0])
    for h_ft in (400, 200, 100):
        i = int(np.nonzero(dh <= h_ft * 0.3048)[0][0])
        assert abs(dh[i] - run.dh_m[i]) < 1e-3


def test_observers_coast_across_missing_frames_and_recover():
    from dataclasses import replace
    result = simulation()
    prep = prepared()
    dh = true_height(result)
    steps = list(prep.steps)
    gap = range(prep.step_of_frame[800], prep.step_of_frame[850])
    for j in gap:
        steps[j] = replace(steps[j], points_yv=None, lines=None)
    holed = replace(prep, steps=steps)
    run = run_observer(CCPIHG2P(), holed, 1.2 * dh[0])
    frames = np.arange(800, 850)
    assert run.coasting[frames].all() and set(run.reason[frames]) == {"no measurement"}
    assert np.isfinite(run.dh_m[1:]).all()
    # a converged observer coasting on the exact model stays on the truth
    assert np.max(np.abs(dh[frames] - run.dh_m[frames]) / dh[frames]) < 1e-3
    assert not run.coasting[900]


@pytest.mark.slow
def test_one_px_noise_ccpi_error_at_100_ft_within_the_thesis_figures():
    """Thesis Table 5.6: CCPI error at 100 ft, mean 0.10 m and standard deviation 0.05 m over 8 runs.

    Three scenarios here (the full eight are `visland study table-5.6`); each error must stay
    under the thesis's mean plus two of its standard deviations.
    """
    for k, scenario in enumerate(("thesis-1", "thesis-3", "thesis-7")):
        result = simulation(scenario, pixel_noise_px=1.0, seed=k)
        dh = true_height(result)
        run = run_observer(CCPIHG2P(), prepared(scenario, pixel_noise_px=1.0, seed=k), 1.2 * dh[0])
        i100 = int(np.nonzero(dh <= 30.48)[0][0])
        assert abs(dh[i100] - run.dh_m[i100]) < 0.10 + 2 * 0.05


def test_velocity_bias_scales_the_height_as_the_theory_says():
    """A relative bias b on the velocity scales the solution: dH_hat -> (1 + b) dH."""
    result = simulation("thesis-1", velocity_bias=-0.05)
    dh = true_height(result)
    run = run_observer(CCPIHG2P(), prepared("thesis-1", velocity_bias=-0.05), dh[0])
    late = slice(len(dh) - 200, len(dh) - 30)
    assert np.allclose(run.dh_m[late], 0.95 * dh[late], rtol=5e-3)


def test_output_combination_noise_bias_is_minus_v3_half_the_variance():
    """y_a is quadratic in y: Monte Carlo of its mean under seeded Gaussian noise against the
    closed form -v3/2 sum s_i^2 that cccs-2p's noise option adds back."""
    from visland.estimation.points import virtual_noise_sigma
    rng = np.random.default_rng(11)
    y = [-18.0, -0.1, -18.0, 0.1]
    v = (70.0, 1.0, 3.7)
    sigma = virtual_noise_sigma(y, 5.0 / 2472.0)
    assert sigma[0] == pytest.approx((1 + 18.0 ** 2) * 5.0 / 2472.0)
    n = 1000000
    noisy = np.array(y)[None, :] + rng.standard_normal((n, 4)) * np.array(sigma)[None, :]
    v1, v2, v3 = v
    ya = sum(v1 * noisy[:, k] + v2 * noisy[:, k + 1] - 0.5 * v3 * (noisy[:, k] ** 2 + noisy[:, k + 1] ** 2)
             for k in (0, 2))
    bias = ya.mean() - output_combination(y, v)
    expected = -0.5 * v3 * sum(s * s for s in sigma)
    standard_error = ya.std() / np.sqrt(n)
    assert abs(bias - expected) < 4 * standard_error
    assert abs(expected) > 5 * standard_error          # the bias is real, not lost in the noise


def test_ii_observer_does_not_rectify_the_image_noise_at_its_domain_bound():
    """5 px far out: ii-2p's eta_hat carries noise larger than eta; projecting its state onto the
    domain each step kept the upward half and took it to the 0.5 m bound (dH error 29.98 m at 100 ft
    on thesis-1, now withheld by the runner's divergence cut-off); projecting only the reported
    height, it ends within 5 m (measured 3.6 m)."""
    result = simulation("thesis-1", pixel_noise_px=5.0, seed=0)
    dh = true_height(result)
    prep = prepared("thesis-1", pixel_noise_px=5.0, seed=0)
    start = prep.frame_of_step[prep.first_step_with("points")]
    i100 = int(np.nonzero(dh <= 30.48)[0][0])
    errors = {}
    for project in (True, False):
        observer = make_observer("ii-2p")
        observer.project_state = project
        run = run_observer(observer, prep, 1.2 * dh[start])
        errors[project] = abs(dh[i100] - run.dh_m[i100])
    assert not errors[True] < 20.0                   # NaN: cut off as diverged
    assert errors[False] < 5.0


@pytest.mark.slow
@pytest.mark.parametrize("scenario,seed", [("thesis-1", 0), ("thesis-5", 4), ("thesis-7", 6)])
def test_no_point_observer_diverges_with_5_px_of_noise(scenario, seed):
    """Issue 12: with 5 px of corner noise and the 5 px settings of `visland study table-5.7`,
    every point observer is within 6 m of the truth at 100 ft (was: kf-2p -17 m on thesis-7,
    ii-2p 30 m on thesis-1, ccpi-hosm-2p 30 m on thesis-5, cccs-2p no estimate on thesis-5 and -7)."""
    from visland.estimation.study import SLOW_5PX_PARAMS
    result = simulation(scenario, pixel_noise_px=5.0, seed=seed)
    dh = true_height(result)
    prep = prepared(scenario, pixel_noise_px=5.0, seed=seed)
    start = prep.frame_of_step[prep.first_step_with("points")]
    i100 = int(np.nonzero(dh <= 30.48)[0][0])
    for name in ("oj-2p", "ii-2p", "cccs-2p", "ccpi-hg-2p", "ccpi-hosm-2p", "cccj-2p", "kf-2p"):
        run = run_observer(make_observer(name, SLOW_5PX_PARAMS.get(name)), prep, 1.2 * dh[start])
        assert abs(dh[i100] - run.dh_m[i100]) < 6.0, name
