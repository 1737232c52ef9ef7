"""The coordinate-change observers' inversions (thesis 4.77-4.78 and 4.85-4.93), against finite differences.

The Jacobians here are rebuilt from the immersions themselves by central differences
(``tau = [y, y']`` and ``tau_e = [y, y' - w, psi eta + Phi . w]``), independently of the
hand-derived entries the observers use.
"""
import numpy as np
import pytest

from tests.helpers.estimation_sims import random_line_inputs
from visland.estimation.lines import _edge_blocks, _pair_jacobian, ccpi_correction, cccj_increment, cccj_jacobian
from visland.estimation.lines_model import pair_model


@pytest.fixture
def cases():
    rng = np.random.default_rng(7)
    out = []
    for _ in range(20):
        y = [rng.uniform(-1, 1), rng.uniform(-0.3, 0.3), rng.uniform(-1, 1), rng.uniform(-0.3, 0.3)]
        out.append((y, rng.uniform(1 / 800, 1 / 30), random_line_inputs(rng)))
    return out


def _tau(x, u):
    """Thesis 4.76: ``[y, y']`` at ``x = [y, eta]``."""
    ydot, _, _ = pair_model(x[:4], x[4], u)
    return np.concatenate([x[:4], ydot])


def _tau_e(xw, u, epsilon_sq):
    """Thesis 4.80-4.85 with the completion 4.92: ``[y, y' - w, psi eta + Phi . w]``."""
    y, eta, w = xw[:4], xw[4], xw[5:]
    ydot, _, phi = pair_model(y, eta, u)
    phi = np.array(phi)
    psi = max(epsilon_sq - phi @ phi, 0.0) ** 2
    return np.concatenate([y, np.array(ydot) - w, [psi * eta + phi @ w]])


def _fd_jacobian(fun, x, h):
    cols = []
    for i in range(len(x)):
        dx = np.zeros(len(x))
        dx[i] = h[i]
        cols.append((fun(x + dx) - fun(x - dx)) / (2 * h[i]))
    return np.stack(cols, axis=1)


def test_pair_jacobian_is_the_derivative_of_the_model(cases):
    for y, eta, u in cases:
        x = np.array(y + [eta])
        J = _fd_jacobian(lambda z: _tau(z, u), x, [1e-6] * 4 + [1e-8])
        phi, D, _ = _pair_jacobian(y, eta, u)
        np.testing.assert_allclose(J[:4], np.hstack([np.eye(4), np.zeros((4, 1))]), atol=1e-9)
        np.testing.assert_allclose(J[4:, :4], D, rtol=1e-5, atol=1e-8)
        np.testing.assert_allclose(J[4:, 4], phi, rtol=1e-6)


@pytest.mark.parametrize("floor", [1e-6, 0.5, 50.0])
def test_ccpi_correction_is_the_damped_left_inverse(cases, floor):
    rng = np.random.default_rng(11)
    k1, k2 = 4.0, 6.25
    for y, eta, u in cases:
        x = np.array(y + [eta])
        J = _fd_jacobian(lambda z: _tau(z, u), x, [1e-6] * 4 + [1e-8])      # 8x5, thesis 4.78
        e = rng.normal(0, 1e-3, 4)
        kappa = np.concatenate([k1 * e, k2 * e])                          # thesis 4.44
        # damped least squares: minimise |J dx - kappa|^2 + floor * d_eta^2
        A = np.vstack([J, np.sqrt(floor) * np.eye(5)[4:]])
        b = np.concatenate([kappa, [0.0]])
        expected = np.linalg.lstsq(A, b, rcond=None)[0]
        got = ccpi_correction(_edge_blocks(y, eta, u), list(e), k1, k2, floor)
        np.testing.assert_allclose(got, expected, rtol=1e-5, atol=1e-12)


def test_ccpi_correction_fades_with_observability():
    """The damped inverse: where Phi = 0 (level flight along the runway) eta is left alone."""
    u = (0.0, 0.0, 75.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0)
    y = [0.0, 0.0, 0.5, 0.0]
    eta = 1 / 237.0
    dx = ccpi_correction(_edge_blocks(y, eta, u), [1e-3, -1e-3, 2e-3, 0.0], 4.0, 6.25, 0.5)
    assert np.isfinite(dx).all() and abs(dx[4]) < 1e-15


@pytest.mark.parametrize("epsilon_sq", [1e-3, 2.0, 200.0])   # larger psi eta drowns the differences in rounding
def test_cccj_jacobian_matches_finite_differences_and_never_vanishes(cases, epsilon_sq):
    rng = np.random.default_rng(3)
    for y, eta, u in cases:
        w = rng.normal(0, 1e-4, 4)
        xw = np.concatenate([y, [eta], w])
        J_fd = _fd_jacobian(lambda z: _tau_e(z, u, epsilon_sq), xw, [1e-6] * 4 + [1e-8] + [1e-6] * 4)
        J = cccj_jacobian(y, eta, w, u, epsilon_sq)
        np.testing.assert_allclose(J, J_fd, rtol=1e-5, atol=1e-7)
        _, _, phi = pair_model(y, eta, u)
        phi_sq = float(np.dot(phi, phi))
        psi = max(epsilon_sq - phi_sq, 0.0) ** 2
        assert abs(np.linalg.det(J)) == pytest.approx(psi + phi_sq, rel=1e-8)


def test_cccj_increment_solves_the_completed_system(cases):
    rng = np.random.default_rng(5)
    for epsilon_sq in (1e-3, 2.0, 1e4):
        for y, eta, u in cases:
            w = rng.normal(0, 1e-4, 4)
            r = rng.normal(0, 1e-3, 9)
            expected = np.linalg.solve(cccj_jacobian(y, eta, w, u, epsilon_sq), r)
            got = cccj_increment(_edge_blocks(y, eta, u), eta, list(w), list(r), epsilon_sq)
            np.testing.assert_allclose(got, expected, rtol=1e-8, atol=1e-14)


def test_cccj_increment_is_finite_where_the_lines_are_unobservable():
    """Level flight along the runway (thesis Fig. 3.10, t = 0): Phi = 0, the fictitious output keeps J invertible."""
    u = (0.0, 0.0, 75.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0)   # velocity along the optical axis, n along image y
    y = [0.0, 0.0, 0.5, 0.0]                                   # edges through the vanishing point of the motion
    _, _, phi = pair_model(y, 1 / 237.0, u)
    assert max(abs(p) for p in phi) < 1e-12
    dxw = cccj_increment(_edge_blocks(y, 1 / 237.0, u), 1 / 237.0, [0.0] * 4, [1e-4] * 9, 2.0)
    assert np.isfinite(dxw).all()
