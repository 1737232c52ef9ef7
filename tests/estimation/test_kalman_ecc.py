"""The pseudo-measurement Kalman filter (thesis annex) and the ECC'15 observers on simulated flights."""
import numpy as np
import pytest

from tests.helpers.estimation_sims import prepared, simulation, true_height
from visland.estimation.ecc import EccHG, EccHOSM
from visland.estimation.kalman import KF2P, KFParams
from visland.estimation.runner import run_observer


def _error_at(dh, est, height_m):
    i = int(np.nonzero(dh <= height_m)[0][0])
    return dh[i] - est[i]


def test_kalman_filter_converges_on_ideal_measurements():
    result = simulation()
    dh = true_height(result)
    run = run_observer(KF2P(), prepared(), 1.2 * dh[0])
    assert abs(_error_at(dh, run.dh_m, 30.48)) < 1e-2
    assert np.max(np.abs(dh - run.dh_m)[len(dh) // 4:] / dh[len(dh) // 4:]) < 0.01


def test_kalman_state_is_the_virtual_frame_positions_of_the_corners():
    result = simulation()
    dh = true_height(result)
    observer = KF2P()
    prep = prepared()
    run_observer(observer, prep, 1.2 * dh[0])
    x = observer._get_state()          # [X, Y', Y'', Z] at the last step
    p = result.trajectory.p_runway_m[len(prep) - 1]
    half = result.scenario.runway.width_m / 2
    assert np.allclose(x, [-p[0], -half - p[1], half - p[1], -p[2]], atol=0.05)
    assert np.all(np.linalg.eigvalsh(observer.covariance) > 0)


def test_kalman_filter_does_not_collapse_under_pixel_noise():
    """With the measured ratios inside H, noise drags the filter to x = 0 (see kalman.py)."""
    result = simulation("thesis-1", pixel_noise_px=1.0, seed=1)
    dh = true_height(result)
    run = run_observer(KF2P(), prepared("thesis-1", pixel_noise_px=1.0, seed=1), 1.2 * dh[0])
    assert np.nanmin(run.dh_m / dh) > 0.5
    assert abs(_error_at(dh, run.dh_m, 30.48)) < 0.3


def test_kalman_params_are_validated():
    with pytest.raises(ValueError, match="image_sigma_rad"):
        KFParams(image_sigma_rad=0.0)


@pytest.mark.slow
@pytest.mark.parametrize("cls", [EccHG, EccHOSM])
def test_ecc_observers_converge_on_ideal_measurements_of_the_ecc_landings(cls):
    for scenario in ("ecc-1", "ecc-2"):
        result = simulation(scenario)
        dh = true_height(result)
        run = run_observer(cls(), prepared(scenario), 1.2 * dh[0])
        assert abs(_error_at(dh, run.dh_m, 30.48)) < 0.05
        assert abs(_error_at(dh, run.dh_m, 121.92)) / 121.92 < 0.05
        i = int(np.nonzero(dh <= 30.48)[0][0])
        assert abs(run.dy_m[i] - result.frames.p_runway_m[i, 1]) < 0.1


def test_kalman_huber_update_bounds_a_wild_measurement():
    """One frame's corners 5 units of X/Z off (an outlier thousands of sigma large) after
    convergence: with the annex's update dH is then up to 0.58 m off, with the Huber-weighted one
    0.06 m (measured)."""
    from dataclasses import replace
    result = simulation()
    dh = true_height(result)
    prep = prepared()
    f = 1200
    j = prep.step_of_frame[f]
    steps = list(prep.steps)
    steps[j] = replace(steps[j], points_yv=steps[j].points_yv + 5.0)
    wild = replace(prep, steps=steps)
    worst = {}
    for c in (0.0, 3.64):
        run = run_observer(KF2P(KFParams(huber_threshold=c)), wild, 1.2 * dh[0])
        worst[c] = np.nanmax(np.abs(dh[f:] - run.dh_m[f:]))
    assert worst[0.0] > 0.3
    assert worst[3.64] < 0.2 * worst[0.0]
