"""Seed 001: the single-point observer, its Jacobian and its academic example (eq. 14-16)."""
import numpy as np
import pytest

from visland.estimation.single_point import (ACADEMIC_A, ACADEMIC_B, SinglePointObserver, SinglePointParams,
                                             academic_example, psi_jacobian)


def _psi(x, A, B):
    xdot = A @ x + B
    y1, y2 = x[0] / x[2], x[1] / x[2]
    y1dot = (xdot[0] * x[2] - x[0] * xdot[2]) / x[2] ** 2
    return np.array([y1, y1dot, y2])


def test_jacobian_of_psi_matches_finite_differences():
    x = np.array([0.7, -1.2, 3.1])
    J = psi_jacobian(x, ACADEMIC_A, ACADEMIC_B)
    h = 1e-6
    fd = np.column_stack([(_psi(x + h * e, ACADEMIC_A, ACADEMIC_B) - _psi(x - h * e, ACADEMIC_A, ACADEMIC_B)) / (2 * h)
                          for e in np.eye(3)])
    assert np.allclose(J, fd, atol=1e-7)


def test_academic_example_truth_is_the_linear_system():
    result = academic_example(duration_s=1.0, dt_s=1e-3)
    from scipy.integrate import solve_ivp
    sol = solve_ivp(lambda t, x: ACADEMIC_A @ x + ACADEMIC_B, (0, 1.0), [1.0, 1.5, 2.5], rtol=1e-10, atol=1e-12)
    assert np.allclose(result.x[-1], sol.y[:, -1], atol=1e-8)


@pytest.mark.slow
def test_depth_within_one_percent_two_seconds_after_the_start():
    result = academic_example()
    assert result.relative_depth_error_at(2.0) < 0.01
    assert result.relative_depth_error_at(0.0) == pytest.approx(1.5 / 2.5)     # the seed's initial error


@pytest.mark.slow
def test_noisy_measurements_still_converge():
    result = academic_example(noise_fraction=0.01, seed=2)
    assert result.relative_depth_error_at(3.0) < 0.03


def test_missing_measurement_coasts_and_bad_input_is_refused():
    observer = SinglePointObserver(SinglePointParams())
    observer.reset(0.0, [0.4, 0.6, 1.0])
    est = observer.step(0.01, [np.nan, 0.5], ACADEMIC_A, ACADEMIC_B)
    assert np.isfinite(est.x_hat).all()
    with pytest.raises(ValueError, match="time must increase"):
        observer.step(0.01, [0.4, 0.6], ACADEMIC_A, ACADEMIC_B)
    with pytest.raises(ValueError, match="shape"):
        observer.step(0.02, [0.4, 0.6, 0.1], ACADEMIC_A, ACADEMIC_B)
    with pytest.raises(ValueError, match="depth guess"):
        observer.reset(0.0, [0.4, 0.6, -1.0])
