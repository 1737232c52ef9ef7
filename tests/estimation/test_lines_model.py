"""The two-edge line model: fast terms against the core, Jacobians and I&I integrals by finite differences."""
import math

import numpy as np
import pytest

from visland.camera import wrap_line_chart
from visland.features import line_dynamics_terms
from tests.helpers.estimation_sims import random_line_inputs
from visland.estimation.lines_model import (align_to, edge_terms, edge_terms_and_jacobian, ii_edge_gradient,
                                            ii_edge_integral, ii_edge_mismatch, measured_pair, pair_model,
                                            pair_observability)


@pytest.fixture
def samples():
    rng = np.random.default_rng(20260601)
    out = []
    for _ in range(40):
        u = random_line_inputs(rng)
        out.append((rng.uniform(-1.2, 1.2), rng.uniform(-0.4, 0.4), u))
    return out


def test_edge_terms_match_the_core_line_dynamics(samples):
    for theta, rho, u in samples:
        g, phi = line_dynamics_terms(rho, theta, np.array(u[0:3]), np.array(u[3:6]), np.array(u[6:9]))
        fast = edge_terms(theta, rho, u)
        np.testing.assert_allclose(fast, [g[0], g[1], phi[0], phi[1]], rtol=1e-12, atol=1e-15)


def test_edge_jacobians_match_central_differences(samples):
    h = 1e-6
    for theta, rho, u in samples:
        *_, Jg, JPhi = edge_terms_and_jacobian(theta, rho, u)
        for col, (dt, dr) in enumerate(((h, 0.0), (0.0, h))):
            plus = np.array(edge_terms(theta + dt, rho + dr, u))
            minus = np.array(edge_terms(theta - dt, rho - dr, u))
            fd = (plus - minus) / (2 * h)
            np.testing.assert_allclose([Jg[0][col], Jg[1][col]], fd[:2], rtol=1e-6, atol=1e-9)
            np.testing.assert_allclose([JPhi[0][col], JPhi[1][col]], fd[2:], rtol=1e-6, atol=1e-7)


def test_pair_model_stacks_both_edges_and_eta_dynamics(samples):
    (t1, r1, u), (t2, r2, _) = samples[0], samples[1]
    eta = 1 / 250.0
    ydot, etadot, phi = pair_model([t1, r1, t2, r2], eta, u)
    left = edge_terms(t1, r1, u)
    right = edge_terms(t2, r2, u)
    np.testing.assert_allclose(ydot, [left[0] + left[2] * eta, left[1] + left[3] * eta,
                                      right[0] + right[2] * eta, right[1] + right[3] * eta])
    assert etadot == pytest.approx(u[9] * eta ** 2)   # d(1/dH)/dt = v_z / dH^2 (z down)
    assert pair_observability([t1, r1, t2, r2], u) == pytest.approx(sum(p * p for p in phi))


def test_dynamics_are_the_same_in_both_chart_representatives(samples):
    for theta, rho, u in samples:
        a = edge_terms(theta, rho, u)
        b = edge_terms(theta - math.pi, -rho, u)
        # theta' is the same, rho' flips with rho; Phi likewise
        np.testing.assert_allclose([b[0], -b[1], b[2], -b[3]], a, rtol=1e-12, atol=1e-15)


def test_align_to_picks_the_representative_nearest_the_reference():
    theta, rho = align_to(1.5, 0.2, theta_ref=-1.5)
    assert theta == pytest.approx(1.5 - math.pi) and rho == pytest.approx(-0.2)
    assert align_to(0.1, 0.2, 0.3) == (0.1, 0.2)
    # the same line: a point on the original line lies on the aligned one
    x, y = 0.2 * math.cos(1.5) + 0.7 * -math.sin(1.5), 0.2 * math.sin(1.5) + 0.7 * math.cos(1.5)
    assert x * math.cos(theta) + y * math.sin(theta) == pytest.approx(rho)


def test_measured_pair_reorders_the_spec_lines_array():
    lines = np.array([[0.01, 0.3], [-0.02, -0.4]])      # [[rho_l, theta_l], [rho_r, theta_r]]
    assert measured_pair(lines, [0.3, 0, -0.4, 0]) == [0.3, 0.01, -0.4, -0.02]
    # the same right edge written as (-rho, theta + pi), as a chart near theta = pi/2 would give it
    other = np.array([[0.01, 0.3], [0.02, -0.4 + math.pi]])
    assert np.allclose(wrap_line_chart(other[1, 0], other[1, 1]), (-0.02, -0.4))
    assert np.allclose(measured_pair(other, [0.3, 0, -0.4, 0]), [0.3, 0.01, -0.4, -0.02])


def test_ii_integral_is_zero_at_the_origin_and_its_gradient_is_phi_at_mixed_arguments(samples):
    h = 1e-6
    for theta, rho, u in samples:
        theta_hat, rho_hat = theta + 0.01, rho - 0.003
        assert ii_edge_integral(0.0, 0.0, theta_hat, rho_hat, u) == 0.0
        fd_theta = (ii_edge_integral(theta + h, rho, theta_hat, rho_hat, u)
                    - ii_edge_integral(theta - h, rho, theta_hat, rho_hat, u)) / (2 * h)
        fd_rho = (ii_edge_integral(theta, rho + h, theta_hat, rho_hat, u)
                  - ii_edge_integral(theta, rho - h, theta_hat, rho_hat, u)) / (2 * h)
        g_theta, g_rho = ii_edge_gradient(theta, rho, theta_hat, rho_hat, u)
        assert fd_theta == pytest.approx(g_theta, rel=1e-6, abs=1e-8)
        assert fd_rho == pytest.approx(g_rho, rel=1e-6, abs=1e-8)
        # thesis 4.23: with y_hat = y the gradient is Phi(y) itself
        _, _, p_theta, p_rho = edge_terms(theta, rho, u)
        assert ii_edge_gradient(theta, rho, theta, rho, u) == pytest.approx((p_theta, p_rho))


def test_ii_integral_matches_quadrature(samples):
    theta, rho, u = samples[3]
    theta_hat, rho_hat = theta - 0.02, rho + 0.01
    xs = np.linspace(0.0, theta, 2001)
    i_theta = np.trapezoid([edge_terms(x, rho_hat, u)[2] for x in xs], xs)
    rs = np.linspace(0.0, rho, 2001)
    i_rho = np.trapezoid([edge_terms(theta_hat, r, u)[3] for r in rs], rs)
    assert ii_edge_integral(theta, rho, theta_hat, rho_hat, u) == pytest.approx(i_theta + i_rho, rel=1e-6)


def test_ii_mismatch_factors_reproduce_the_gradient_defect(samples):
    for theta, rho, u in samples:
        theta_hat, rho_hat = theta + 0.02, rho - 0.01
        d_theta, d_rho = ii_edge_mismatch(theta, rho, theta_hat, rho_hat, u)
        _, _, p_theta, p_rho = edge_terms(theta, rho, u)
        g_theta, g_rho = ii_edge_gradient(theta, rho, theta_hat, rho_hat, u)
        assert p_theta - g_theta == pytest.approx(d_theta * (rho - rho_hat), rel=1e-9, abs=1e-12)
        assert p_rho - g_rho == pytest.approx(d_rho * (theta - theta_hat), rel=1e-9, abs=1e-12)
        # coinciding thetas: the limit dPhi_rho/dtheta
        _, d_rho0 = ii_edge_mismatch(theta, rho, theta, rho_hat, u)
        h = 1e-6
        fd = (edge_terms(theta + h, rho, u)[3] - edge_terms(theta - h, rho, u)[3]) / (2 * h)
        assert d_rho0 == pytest.approx(fd, rel=1e-6, abs=1e-8)


def test_align_to_returns_at_once_for_a_reference_far_off():
    """A diverging estimate can carry theta 1e17 rad away: the chart is found in one go (it looped
    for ever, one turn of pi at a time, which a float that large does not even change)."""
    import threading
    out = {}
    worker = threading.Thread(target=lambda: out.update(r=align_to(0.1, 0.2, 1e17)), daemon=True)
    worker.start()
    worker.join(timeout=5.0)
    assert "r" in out, "align_to did not return"
    theta, rho = out["r"]
    assert abs(theta - 1e17) <= 0.5 * math.pi + 16.0 and abs(rho) == 0.2
    # a few turns away: the same line, theta within pi/2 of the reference, rho's sign by the parity
    theta, rho = align_to(0.1, 0.2, 0.1 + 5 * math.pi + 0.3)
    assert theta == pytest.approx(0.1 + 5 * math.pi) and rho == -0.2
    theta, rho = align_to(0.1, 0.2, 0.1 - 40 * math.pi)
    assert theta == pytest.approx(0.1 - 40 * math.pi) and rho == 0.2
