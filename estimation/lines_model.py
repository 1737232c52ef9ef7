"""The two-edge line model shared by the line observers: dynamics, Jacobians, I&I integrals.

System (thesis 3.39 / 4.14 / 4.74, in SPEC frames). The measurement is the pair of runway
edges, ordered ``y = [theta_left, rho_left, theta_right, rho_right]`` (the SPEC ``lines``
array lists the left edge first; the thesis lists the right edge, "d", first), and::

    y'   = g(y, u) + Phi(y, u) eta        (thesis 3.37 per edge, 3.39 stacked)
    eta' = v3 eta^2                       (thesis 4.14, eta = 1/dH, v3 = runway-axes z velocity)

with ``u = (v_C, w_C, n_C)`` the camera velocity and angular velocity in C and the runway down
axis in C (thesis 3.33). ``g`` and ``Phi`` are :func:`visland.features.line_dynamics_terms`
(derived and checked by finite differences in the core; NOTE the sign of Phi is opposite to the
thesis print because the thesis's ``d_p`` equals ``-dH``). :func:`edge_terms` below is the same
formula written on Python floats: the observers evaluate it several times per 50 Hz step and the
cost target (a 100 s approach in under 0.5 s) does not allow a vectorised numpy call each time;
``tests/estimation/test_lines_model.py`` checks it against ``line_dynamics_terms``.

Per edge, with ``c = cos(theta)``, ``s = sin(theta)``::

    g_theta = -rho c w0 - rho s w1 - w2                 g_rho = (1 + rho^2)(s w0 - c w1)
    S = c v0 + s v1 - rho v2     A = n0 s - n1 c        B = rho (n0 c + n1 s) + n2
    Phi_theta = -A S                                    Phi_rho = -B S

Jacobians (derived here, checked by finite differences in the tests), with
``a = n0 c + n1 s = dA/dtheta``, ``S_theta = -s v0 + c v1``, ``S_rho = -v2``,
``dB/dtheta = -rho A``, ``dB/drho = a``::

    dg_theta/dtheta = rho (s w0 - c w1)          dg_theta/drho = -(c w0 + s w1)
    dg_rho/dtheta   = (1 + rho^2)(c w0 + s w1)   dg_rho/drho   = 2 rho (s w0 - c w1)
    dPhi_theta/dtheta = -(a S + A S_theta)       dPhi_theta/drho = A v2
    dPhi_rho/dtheta   = rho A S - B S_theta      dPhi_rho/drho   = -(a S - B v2)

Immersion and invariance integrals (thesis 4.29-4.30, re-derived for the SPEC Phi): with the
filtered measurement ``(theta_hat, rho_hat)`` frozen in the other argument,

    I_theta(theta; rho_hat) = int_0^theta Phi_theta(xi, rho_hat) dxi
        = -[(n0 v0 - n1 v1) s^2/2 + n0 v1 (theta/2 - sin(2 theta)/4) - n1 v0 (theta/2 + sin(2 theta)/4)
            - n0 rho_hat v2 (1 - c) + n1 rho_hat v2 s]
    I_rho(rho; theta_hat) = int_0^rho Phi_rho(theta_hat, xi) dxi
        = -[a_hat S0 rho^2/2 - a_hat v2 rho^3/3 + n2 S0 rho - n2 v2 rho^2/2]

with ``a_hat = n0 cos(theta_hat) + n1 sin(theta_hat)`` and ``S0 = cos(theta_hat) v0 + sin(theta_hat) v1``
(thesis 4.30 prints the same integrals for its sign of Phi, with ``v_v`` where the camera-axes
velocity ``v_c`` of 4.15 is meant).

The chart: each edge follows its line continuously; a measured edge is written in the chart
representative ``(rho, theta)`` or ``(-rho, theta -+ pi)`` nearest to the observer's edge
(:func:`align_to`), so an edge whose theta crosses the SPEC chart boundary never produces a
jump of pi in the innovation. The dynamics above are the same in both representatives.

References
----------
V. Gibert, "Analyse d'observabilite et synthese d'observateurs robustes pour l'atterrissage
base vision d'avions de ligne sur des pistes inconnues", PhD thesis, 2016 (seed 002).
    Eq. 3.34 (the (rho, theta) chart), 3.39-3.40, 4.14 and 4.74 (the two-edge model).
"""
from __future__ import annotations

import math

__all__ = [
    "edge_terms",
    "edge_terms_and_jacobian",
    "pair_model",
    "pair_observability",
    "align_to",
    "measured_pair",
    "ii_edge_integral",
    "ii_edge_gradient",
    "ii_edge_mismatch",
    "inputs_of",
]

_PI = math.pi


def inputs_of(inp) -> tuple:
    """``(v0, v1, v2, w0, w1, w2, n0, n1, n2, v3)`` as floats from an ObserverInput.

    ``v`` camera velocity in C, ``w`` camera angular velocity in C, ``n`` runway down axis in C
    (thesis 3.33), ``v3`` the velocity along ``n`` that drives ``eta' = v3 eta^2`` (``n . v``: the
    runway-axes z velocity on a level runway, the rate of the distance to a sloped runway's plane).

    Parameters
    ----------
    inp : visland.estimation.base.ObserverInput
        One step's input.

    Returns
    -------
    tuple of 10 floats
    """
    v = inp.v_camera_mps.tolist()
    w = inp.omega_camera_rps.tolist()
    n = inp.n_camera.tolist()
    if inp.slope == 0.0:
        v3 = float(inp.v_runway_mps[2])
    else:
        v3 = n[0] * v[0] + n[1] * v[1] + n[2] * v[2]
    return (v[0], v[1], v[2], w[0], w[1], w[2], n[0], n[1], n[2], v3)


def edge_terms(theta: float, rho: float, u: tuple) -> tuple:
    """``(g_theta, g_rho, Phi_theta, Phi_rho)`` of one edge (thesis 3.37, SPEC sign of Phi).

    Parameters
    ----------
    theta, rho : float
        The edge in the SPEC chart (radians; normalised coordinates).
    u : tuple
        The inputs ``(v0, v1, v2, w0, w1, w2, n0, n1, n2, v3)`` of :func:`inputs_of` (m/s, rad/s, unit normal).

    Returns
    -------
    g_theta, g_rho, Phi_theta, Phi_rho : float
    """
    v0, v1, v2, w0, w1, w2, n0, n1, n2 = u[:9]
    c = math.cos(theta)
    s = math.sin(theta)
    speed = c * v0 + s * v1 - rho * v2
    return (-rho * c * w0 - rho * s * w1 - w2,
            (1.0 + rho * rho) * (s * w0 - c * w1),
            -(n0 * s - n1 * c) * speed,
            -(rho * (n0 * c + n1 * s) + n2) * speed)


def edge_terms_and_jacobian(theta: float, rho: float, u: tuple) -> tuple:
    """Edge terms and their partial derivatives (module docstring).

    Returns ``(g_theta, g_rho, Phi_theta, Phi_rho, Jg, JPhi)`` where ``Jg`` and ``JPhi`` are
    2x2 nested tuples ``((d./dtheta, d./drho) for (theta row, rho row))``.

    Parameters
    ----------
    theta, rho : float
        One edge, SPEC chart.
    u : tuple
        As in :func:`edge_terms`.
    """
    v0, v1, v2, w0, w1, w2, n0, n1, n2 = u[:9]
    c = math.cos(theta)
    s = math.sin(theta)
    speed = c * v0 + s * v1 - rho * v2
    A = n0 * s - n1 * c
    a = n0 * c + n1 * s
    B = rho * a + n2
    S_theta = -s * v0 + c * v1
    sw = s * w0 - c * w1
    cw = c * w0 + s * w1
    Jg = ((rho * sw, -cw),
          ((1.0 + rho * rho) * cw, 2.0 * rho * sw))
    JPhi = ((-(a * speed + A * S_theta), A * v2),
            (rho * A * speed - B * S_theta, -(a * speed - B * v2)))
    # g_theta written as in edge_terms, so that both give the same floats (ekf-2l takes its
    # prediction's first Heun stage from here)
    return (-rho * c * w0 - rho * s * w1 - w2, (1.0 + rho * rho) * sw, -A * speed, -B * speed, Jg, JPhi)


def pair_model(y, eta: float, u: tuple) -> tuple:
    """Right-hand side of thesis 3.39 and 4.14 for the state ``(y, eta)``.

    Returns ``(ydot (list of 4), etadot, Phi (list of 4))``.

    Parameters
    ----------
    y : sequence of 4 floats
        ``[theta_l, rho_l, theta_r, rho_r]`` of the two edges.
    eta : float
        ``1/dH``, 1/m.
    u : tuple
        Inputs of :func:`inputs_of`.
    """
    gtl, grl, ptl, prl = edge_terms(y[0], y[1], u)
    gtr, grr, ptr, prr = edge_terms(y[2], y[3], u)
    return ([gtl + ptl * eta, grl + prl * eta, gtr + ptr * eta, grr + prr * eta],
            u[9] * eta * eta, [ptl, prl, ptr, prr])


def pair_observability(y, u: tuple) -> float:
    """Thesis 3.40: ``sum Phi_i^2`` of the two edges, (m/s)^2 (Phi multiplies eta = 1/dH).

    Parameters
    ----------
    y : sequence of 4 floats
        The two edges, ``[theta_l, rho_l, theta_r, rho_r]``.
    u : tuple
        Inputs (:func:`inputs_of`).

    Returns
    -------
    float
    """
    _, _, ptl, prl = edge_terms(y[0], y[1], u)
    _, _, ptr, prr = edge_terms(y[2], y[3], u)
    return ptl * ptl + prl * prl + ptr * ptr + prr * prr


def align_to(theta: float, rho: float, theta_ref: float) -> tuple:
    """The representative of the line ``(rho, theta)`` whose theta is nearest ``theta_ref``.

    ``(rho, theta)`` and ``(-rho, theta +- pi)`` are the same line (SPEC chart,
    :func:`visland.camera.wrap_line_chart`). Returns ``(theta, rho)``.

    Parameters
    ----------
    theta, rho : float
        A line in any chart representative (radians; normalised coordinates).
    theta_ref : float
        The reference angle, radians.
    """
    if not abs(theta - theta_ref) < 8.0 * _PI:
        # far off (a diverging estimate): in one go, not by millions of turns
        if not math.isfinite(theta - theta_ref):
            return theta, rho
        offset = math.remainder(theta - theta_ref, _PI)          # in [-pi/2, pi/2]
        k = round((theta - theta_ref - offset) / _PI)
        return theta_ref + offset, (-rho if k % 2 else rho)
    while theta - theta_ref > 0.5 * _PI:
        theta -= _PI
        rho = -rho
    while theta - theta_ref < -0.5 * _PI:
        theta += _PI
        rho = -rho
    return theta, rho


def measured_pair(lines, y_ref) -> list:
    """``[theta_l, rho_l, theta_r, rho_r]`` from a SPEC ``lines`` array ``[[rho_l, theta_l], [rho_r, theta_r]]``.

    Each edge is written in the chart representative nearest the reference ``y_ref``
    (:func:`align_to`).

    Parameters
    ----------
    lines : array_like, shape (2, 2)
        ``[[rho_l, theta_l], [rho_r, theta_r]]`` as measured.
    y_ref : sequence of 4 floats
        The reference ``[theta_l, rho_l, theta_r, rho_r]`` (the estimate).

    Returns
    -------
    list of 4 floats
    """
    (rho_l, theta_l), (rho_r, theta_r) = lines.tolist()
    theta_l, rho_l = align_to(theta_l, rho_l, y_ref[0])
    theta_r, rho_r = align_to(theta_r, rho_r, y_ref[2])
    return [theta_l, rho_l, theta_r, rho_r]


# --------------------------------------------------------------------------- I&I (4.29-4.30)
def ii_edge_integral(theta: float, rho: float, theta_hat: float, rho_hat: float, u: tuple) -> float:
    """``I_theta(theta; rho_hat) + I_rho(rho; theta_hat)`` for one edge (thesis 4.29-4.30).

    The I&I function is ``beta = lambda * sum over both edges`` of this value; its gradient in
    the measurement is ``lambda * (Phi_theta(theta, rho_hat), Phi_rho(theta_hat, rho))``
    (:func:`ii_edge_gradient`).

    Parameters
    ----------
    theta, rho : float
        The measured edge (SPEC chart).
    theta_hat, rho_hat : float
        The filter's estimate of it.
    u : tuple
        Inputs (:func:`inputs_of`).

    Returns
    -------
    float
    """
    v0, v1, v2, _, _, _, n0, n1, n2 = u[:9]
    c = math.cos(theta)
    s = math.sin(theta)
    s2t = math.sin(2.0 * theta)
    i_theta = -((n0 * v0 - n1 * v1) * 0.5 * s * s
                + n0 * v1 * (0.5 * theta - 0.25 * s2t)
                - n1 * v0 * (0.5 * theta + 0.25 * s2t)
                - n0 * rho_hat * v2 * (1.0 - c)
                + n1 * rho_hat * v2 * s)
    ch = math.cos(theta_hat)
    sh = math.sin(theta_hat)
    a_hat = n0 * ch + n1 * sh
    S0 = ch * v0 + sh * v1
    i_rho = -(a_hat * S0 * 0.5 * rho * rho - a_hat * v2 * rho ** 3 / 3.0
              + n2 * S0 * rho - n2 * v2 * 0.5 * rho * rho)
    return i_theta + i_rho


def ii_edge_gradient(theta: float, rho: float, theta_hat: float, rho_hat: float, u: tuple) -> tuple:
    """``(d/dtheta, d/drho)`` of :func:`ii_edge_integral`: ``(Phi_theta(theta, rho_hat), Phi_rho(theta_hat, rho))``.

    This is thesis 4.23: ``Phi(y)`` minus a mismatch that vanishes with the filter error
    (:func:`ii_edge_mismatch`).

    Parameters
    ----------
    theta, rho, theta_hat, rho_hat : float
        Measured edge and the filter's estimate, as in :func:`ii_edge_integral`.
    u : tuple
        Inputs.

    Returns
    -------
    d_dtheta, d_drho : float
    """
    _, _, p_theta, _ = edge_terms(theta, rho_hat, u)
    _, _, _, p_rho = edge_terms(theta_hat, rho, u)
    return p_theta, p_rho


def ii_edge_mismatch(theta: float, rho: float, theta_hat: float, rho_hat: float, u: tuple) -> tuple:
    """The factors ``Delta`` of thesis 4.23/4.31/4.35 for one edge.

    ``Phi_theta(theta, rho) - Phi_theta(theta, rho_hat) = Delta_theta * (rho - rho_hat)`` and
    ``Phi_rho(theta, rho) - Phi_rho(theta_hat, rho) = Delta_rho * (theta - theta_hat)``.
    ``Delta_theta = A(theta) v2`` exactly (Phi_theta is affine in rho); ``Delta_rho`` is the divided
    difference in theta (the thesis writes it with a cardinal sine, 4.34-4.35), its limit
    ``dPhi_rho/dtheta`` when the two thetas coincide. Returns ``(Delta_theta, Delta_rho)``.

    Parameters
    ----------
    theta, rho : float
        Measured edge.
    theta_hat, rho_hat : float
        Estimated edge.
    u : tuple
        The step's inputs.
    """
    v0, v1, v2, _, _, _, n0, n1, n2 = u[:9]
    delta_theta = (n0 * math.sin(theta) - n1 * math.cos(theta)) * v2
    d = theta - theta_hat
    if abs(d) > 1e-7:
        _, _, _, p_true = edge_terms(theta, rho, u)
        _, _, _, p_hat = edge_terms(theta_hat, rho, u)
        delta_rho = (p_true - p_hat) / d
    else:
        delta_rho = edge_terms_and_jacobian(theta, rho, u)[5][1][0]
    return delta_theta, delta_rho
