"""Observers of the height above the runway from the two runway edge lines (thesis chapter 4).

Five observers of ``eta = 1/dH`` share the model of :mod:`visland.estimation.lines_model`
(thesis 3.39 / 4.14, SPEC frames and signs): the measurement ``y = [theta_l, rho_l, theta_r, rho_r]``
(left edge first, SPEC ``lines`` chart) obeys ``y' = g(y, u) + Phi(y, u) eta`` and
``eta' = v3 eta^2``.

================  ==================================================================  ===========
SPEC name         method                                                              thesis
================  ==================================================================  ===========
``ccpi-2l``       coordinate change ``zeta = (y, y')`` and Moore-Penrose left inverse   4.3.2 (4.76-4.78)
``cccj-2l``       coordinate change completed into a diffeomorphism (Jacobian          4.4.1, 4.4.3
                  completion, fictitious output)                                      (4.80-4.86, 4.92-4.93)
``ii-2l``         immersion and invariance, filtered measurements, dynamic scaling    4.2.2 (4.18-4.30)
``ekf-2l``        extended Kalman filter (filterpy), discrete at the 50 Hz rate       annex (5.7-5.9)
``oj-2l``         identifier-based observer of [Jankovic 95]                          4.1, [Jankovic 95]
================  ==================================================================  ===========

Time discretisation (common to all five). ``step`` first propagates the observer's model from the
previous input to the current one with Heun's method (trapezoid, inputs taken at both ends: the
50 Hz inertial samples), then, when the input carries a camera measurement, applies the
observer's correction integrated over the time since the previous correction (at most
``max_correction_interval_s``, so a long gap in the measurements never turns into one huge
correction). With a camera at 25 Hz every other step is a prediction only: the estimate is then
flagged ``coasting`` (the base class adds the reason). This splitting converges to the
thesis's continuous-time observers as the step shrinks; the second-order prediction keeps the
discretisation bias of the height far below the errors of thesis Table 5.4: on thesis-1 with
ideal inputs the errors at 400/200/100 ft stay under 3 mm, where a first-order (Euler)
prediction leaves 0.05 to 1.1 m.

Every observer projects its eta onto ``[ETA_MIN, ETA_MAX]`` (:func:`visland.estimation.base.clip_eta`):
the thesis's observers assume dH > 0 (hypothesis 1.3.1) and the projection keeps 1/eta finite
during the first transients, when the lines are nearly unobservable (level flight parallel to
the runway, thesis Fig. 3.10).

Tuning (thesis 5.2.1): the coordinate-change observers fix their error dynamics in the zeta
coordinates (second order, damping 0.8, natural frequency ``omega_rps``); the others need
iterations. Near the singularity ``sum Phi_i^2 = 0`` (first seconds of every thesis scenario)
the two coordinate-change observers regularise the inversion of the Jacobian: a damped left
inverse (ccpi-2l, ``observability_floor``) and the fictitious output of thesis 4.81-4.82
(cccj-2l, ``epsilon_sq``). The defaults are tuned for ideal measurements (thesis 5.2.1,
Table 5.4): started 20 % off on the eight thesis scenarios with ideal inertial data, they
enter the 5 % band for good within 0.2-5.5 s (trajectory 1: ccpi 2.0 s, cccj 1.8 s, ekf 1.6 s,
oj and ii 3.5 s; thesis 2.04, 2.04, 3.4, 5.52, 6 s) and err by less than 1 mm at 100 ft
(``tests/estimation/test_lines.py``).

Noisy lines need slower dynamics, as the thesis found with its detector (5.3.3). Measured on
thesis-1 with the edges drawn through corners carrying 1 px of white noise
(``SimulationOptions(pixel_noise_px=1)``): the default ccpi-2l, cccj-2l, oj-2l and ii-2l are
driven to the edge of the eta domain (dH 20 km) in the weakly observable middle of the
approach; ekf-2l stays within 2.7 m rms after 10 s. Retuned, rms errors after 10 s were:
ccpi-2l ``omega_rps=1, observability_floor=500`` 1.9 m; ekf-2l ``sigma_line=3e-3`` 1.4 m;
oj-2l ``gain_alpha=0.002`` 3.4 m; ii-2l ``gain_lambda=5e-4`` 5.3 m; cccj-2l ``omega_rps=1,
epsilon_sq=500`` 6.3 m (the last three biased by a few metres).

Image noise (issue 12). With 5 px of corner noise the edges' theta errs by 0.06-0.08 rad (median)
over most of an approach (the lines through two noisy corners; thesis-1, seed 0) and rho by
0.002-0.005, strongly correlated. With the defaults, oj-2l, ii-2l and ccpi-2l were thrown onto the
domain bound and cut off as diverged on all eight thesis scenarios, cccj-2l on thesis-6
(``visland study lines-5px``, seeds as the table studies). The causes and what the 5 px settings
(``SLOW_5PX_PARAMS`` of :mod:`visland.estimation.study`; the defaults stay the thesis's) change:

- the correction injects each frame's noise: oj-2l's identifier moves eta by
  ``alpha dt Phi . n`` per frame, which during the thesis scenarios' alignment turn (observability
  3.40 of 300-600) exceeded eta itself; the thesis's remedy for 5 px (5.2.2.1, "réduire la
  dynamique de correction") is taken: slower high-gain dynamics for ccpi-2l (omega 0.7 rad/s) and
  cccj-2l (1 rad/s) in 4.44-4.46, a slow output injection and a smaller gain for oj-2l;
- oj-2l's regressor ``Phi(y)`` taken at the *measured* edges is correlated with the innovation's
  noise (``E[Phi(y + n) . n] != 0``): a bias in eta that sent it to a bound on thesis-2, -5 and -6
  even with the slow gains; at the prediction (``regressor_at_measurement=False``) it is not;
- ii-2l's sampled I&I increment ``beta(y_meas; y_hat) - beta(y_model; y_hat)`` (4.18, 4.29) has a
  non-zero mean with noise: ``y_hat`` (4.19, gain 20/s, and the dynamic scaling 4.27-4.28 raising
  it with the noise) carries the previous frame's noisy rho into ``I_theta``, where it multiplies
  that frame's theta noise, correlated with it. At the true eta on thesis-1 the increment averaged
  +0.5 to +0.75 per second over 20-40 s at 5 px (1e-6 at 0 px): eta rose by more than itself per
  second. With a slow filter (``k_filter=0.1``, ``c_scaling=0``) the mean is -0.01 +- 0.4; the
  noise then left in eta cancels from frame to frame unless it is projected
  (``project_state=False``, as ii-2p), and a smaller lambda keeps it small.

References
----------
V. Gibert, "Analyse d'observabilite et synthese d'observateurs robustes pour l'atterrissage
base vision d'avions de ligne sur des pistes inconnues", PhD thesis, 2016 (seed 002).
    Eq. 3.34-3.40 (lines, their observability), ch. 4.4-4.5 (the line observers) and annex
    5.7-5.9 (the EKF on two lines).
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from visland.estimation.base import Estimate, Observer, ObserverInput, ObserverParams, clip_eta
from visland.estimation.lines_model import (edge_terms, edge_terms_and_jacobian, ii_edge_gradient,
                                            ii_edge_integral, ii_edge_mismatch, inputs_of, measured_pair, pair_model)

__all__ = [
    "CCPI2L", "CCCJ2L", "II2L", "EKF2L", "OJ2L",
    "CCPI2LParams", "CCCJ2LParams", "II2LParams", "EKF2LParams", "OJ2LParams",
    "LINE_OBSERVERS", "ccpi_correction", "cccj_increment", "cccj_jacobian",
]


# --------------------------------------------------------------------------- shared machinery
def _heun(y, eta: float, u0: tuple, u1: tuple, dt: float, first=None) -> tuple:
    """One Heun (trapezoid) step of ``y' = g + Phi eta``, ``eta' = v3 eta^2`` from inputs u0 to u1.

    ``first``: the model's ``(y', eta')`` at ``(y, eta, u0)`` when the caller has it already
    (:func:`pair_model`'s first two outputs); computed here otherwise.
    """
    d1, e1 = first if first is not None else pair_model(y, eta, u0)[:2]
    yp = [y[0] + dt * d1[0], y[1] + dt * d1[1], y[2] + dt * d1[2], y[3] + dt * d1[3]]
    d2, e2, _ = pair_model(yp, eta + dt * e1, u1)
    h = 0.5 * dt
    return ([y[0] + h * (d1[0] + d2[0]), y[1] + h * (d1[1] + d2[1]),
             y[2] + h * (d1[2] + d2[2]), y[3] + h * (d1[3] + d2[3])],
            eta + h * (e1 + e2))


def _pair_jacobian(y, eta: float, u: tuple) -> tuple:
    """``Phi`` (4,), ``D = d(y')/dy`` (4, 4) and ``dPhi/dy`` (4, 4) at ``(y, eta)`` as numpy arrays.

    Both matrices are block diagonal (one 2x2 block per edge). Used by :func:`cccj_jacobian`
    and the tests; the observers, EKF included, work on the blocks directly (:func:`_edge_blocks`).
    """
    phi = np.empty(4)
    D = np.zeros((4, 4))
    dPhi = np.zeros((4, 4))
    for k, (p_t, p_r, Dk, Pk) in zip((0, 2), _edge_blocks(y, eta, u)):
        phi[k] = p_t
        phi[k + 1] = p_r
        D[k:k + 2, k:k + 2] = Dk
        dPhi[k:k + 2, k:k + 2] = Pk
    return phi, D, dPhi


def _edge_blocks(y, eta: float, u: tuple) -> list:
    """Per edge: ``(Phi_theta, Phi_rho, D_k, dPhi_k)`` with the 2x2 blocks as nested tuples."""
    out = []
    for k in (0, 2):
        _, _, p_t, p_r, Jg, JP = edge_terms_and_jacobian(y[k], y[k + 1], u)
        Dk = ((Jg[0][0] + eta * JP[0][0], Jg[0][1] + eta * JP[0][1]),
              (Jg[1][0] + eta * JP[1][0], Jg[1][1] + eta * JP[1][1]))
        out.append((p_t, p_r, Dk, JP))
    return out


def ccpi_correction(blocks: list, e, k1: float, k2: float, floor: float) -> list:
    """``[dtau/dx]^+ kappa`` of thesis 4.77-4.78 with the damped left inverse (per unit time).

    ``J = [[I4, 0], [D, Phi]]`` (8x5), ``kappa = [k1 e, k2 e]``; solves
    ``(J^T J + floor e5 e5^T) dx = J^T kappa`` by the Schur complement on the eta entry, using
    the block-diagonal structure of ``D`` (one 2x2 block per edge). ``blocks`` is
    :func:`_edge_blocks` at the estimate. Returns ``dx`` (5 floats).

    Parameters
    ----------
    blocks : list
        :func:`_edge_blocks` at the estimate: per edge ``(Phi_theta, Phi_rho, D_k, dPhi_k)``.
    e : sequence of 4 floats
        Output error ``y - y_hat`` (theta, rho of each edge).
    k1, k2 : float
        High-gain coefficients of the output and derivative rows.
    floor : float
        Damping of the left inverse on the eta entry, (m/s)^2.
    """
    # A = I + D^T D (block diagonal), b = D^T Phi, r_y = k1 e + k2 D^T e, r_eta = k2 Phi . e
    Ainv_r = []
    Ainv_b = []
    b_dot_Ainv_r = 0.0
    b_dot_Ainv_b = 0.0
    phi_sq = 0.0
    r_eta = 0.0
    for (p_t, p_r, Dk, _), k in zip(blocks, (0, 2)):
        e0, e1 = e[k], e[k + 1]
        (d00, d01), (d10, d11) = Dk
        a00 = 1.0 + d00 * d00 + d10 * d10
        a01 = d00 * d01 + d10 * d11
        a11 = 1.0 + d01 * d01 + d11 * d11
        det = a00 * a11 - a01 * a01                        # >= 1: A is I plus a Gram matrix
        b0 = d00 * p_t + d10 * p_r
        b1 = d01 * p_t + d11 * p_r
        r0 = k1 * e0 + k2 * (d00 * e0 + d10 * e1)
        r1 = k1 * e1 + k2 * (d01 * e0 + d11 * e1)
        ar0 = (a11 * r0 - a01 * r1) / det
        ar1 = (a00 * r1 - a01 * r0) / det
        ab0 = (a11 * b0 - a01 * b1) / det
        ab1 = (a00 * b1 - a01 * b0) / det
        Ainv_r += [ar0, ar1]
        Ainv_b += [ab0, ab1]
        b_dot_Ainv_r += b0 * ar0 + b1 * ar1
        b_dot_Ainv_b += b0 * ab0 + b1 * ab1
        phi_sq += p_t * p_t + p_r * p_r
        r_eta += k2 * (p_t * e0 + p_r * e1)
    # Schur complement: positive (>= floor) since D (I + D^T D)^-1 D^T <= I
    d_eta = (r_eta - b_dot_Ainv_r) / (phi_sq + floor - b_dot_Ainv_b)
    return [Ainv_r[i] - Ainv_b[i] * d_eta for i in range(4)] + [d_eta]


def cccj_increment(blocks: list, eta: float, w, r, epsilon_sq: float) -> list:
    """``J^-1 r`` for the completed Jacobian of thesis 4.93 (9x9), in closed form.

    ``J = [[I4, 0, 0], [D, Phi, -I4], [eta dpsi/dy + w^T dPhi/dy, psi, Phi^T]]`` with
    ``psi = max(epsilon_sq - |Phi|^2, 0)^2`` (4.82). Eliminating ``dy = r1`` and
    ``dw = Phi d_eta - q`` (``q = r2 - D dy``) leaves
    ``d_eta = (r3 - c . dy + Phi . q) / (psi + |Phi|^2)``, ``c`` the first four entries of the
    last row: the determinant ``psi + |Phi|^2`` never vanishes. ``blocks`` is :func:`_edge_blocks`
    at the estimate. Returns ``[dy (4), d_eta, dw (4)]``.

    Parameters
    ----------
    blocks : list
        The edge blocks at the estimate.
    eta : float
        ``1/dH`` estimate, 1/m.
    w : sequence of 4 floats
        The completion state ``w``.
    r : sequence of 9 floats
        Right-hand side.
    epsilon_sq : float
        ``epsilon^2`` of 4.82, (m/s)^2.
    """
    phi = [blocks[0][0], blocks[0][1], blocks[1][0], blocks[1][1]]
    phi_sq = phi[0] ** 2 + phi[1] ** 2 + phi[2] ** 2 + phi[3] ** 2
    m = epsilon_sq - phi_sq
    m = m if m > 0.0 else 0.0
    psi = m * m
    dy = list(r[:4])
    q = [0.0] * 4
    c_dot_dy = 0.0
    for (p_t, p_r, Dk, Pk), k in zip(blocks, (0, 2)):
        (d00, d01), (d10, d11) = Dk
        q[k] = r[4 + k] - (d00 * dy[k] + d01 * dy[k + 1])
        q[k + 1] = r[5 + k] - (d10 * dy[k] + d11 * dy[k + 1])
        # last row: sum_i (w_i - 4 m eta Phi_i) dPhi_i/dy_j   (d psi/dy = -4 m Phi^T dPhi/dy)
        s_t = w[k] - 4.0 * m * eta * p_t
        s_r = w[k + 1] - 4.0 * m * eta * p_r
        c0 = s_t * Pk[0][0] + s_r * Pk[1][0]
        c1 = s_t * Pk[0][1] + s_r * Pk[1][1]
        c_dot_dy += c0 * dy[k] + c1 * dy[k + 1]
    phi_q = phi[0] * q[0] + phi[1] * q[1] + phi[2] * q[2] + phi[3] * q[3]
    d_eta = (r[8] - c_dot_dy + phi_q) / (psi + phi_sq)
    return dy + [d_eta] + [phi[i] * d_eta - q[i] for i in range(4)]


def cccj_jacobian(y, eta: float, w, u: tuple, epsilon_sq: float) -> np.ndarray:
    """The full 9x9 completed Jacobian of thesis 4.93 (for the tests and for readers).

    Parameters
    ----------
    y : sequence of 4 floats
        The two edges ``[theta_l, rho_l, theta_r, rho_r]``.
    eta : float
        ``1/dH``, 1/m.
    w : sequence of 4 floats
        The completion state.
    u : tuple
        Inputs (:func:`visland.estimation.lines_model.inputs_of`).
    epsilon_sq : float
        ``epsilon^2`` of 4.82.

    Returns
    -------
    ndarray, shape (9, 9)
    """
    phi, D, dPhi = _pair_jacobian(y, eta, u)
    phi_sq = float(phi @ phi)
    m = max(epsilon_sq - phi_sq, 0.0)
    J = np.zeros((9, 9))
    J[:4, :4] = np.eye(4)
    J[4:8, :4] = D
    J[4:8, 4] = phi
    J[4:8, 5:] = -np.eye(4)
    J[8, :4] = eta * (-4.0 * m * (phi @ dPhi)) + np.asarray(w) @ dPhi
    J[8, 4] = m * m
    J[8, 5:] = phi
    return J


class _LineObserver(Observer):
    """Bookkeeping shared by the line observers: inputs at the previous step, correction clock."""

    features: ClassVar[str] = "lines"

    def __init__(self, params=None):
        super().__init__(params)
        self._u_prev: tuple | None = None
        self._t_corrected: float = 0.0

    def _start(self, first: ObserverInput, measurement: np.ndarray) -> list:
        """Remember the first input; return the first measured edges ``y``."""
        self._u_prev = inputs_of(first)
        self._t_corrected = float(first.t_s)
        (_, theta_l), (_, theta_r) = measurement.tolist()
        return measured_pair(measurement, [theta_l, 0.0, theta_r, 0.0])

    # the state (y, eta) of the edge observers without extra states (ccpi-2l, oj-2l); the others
    # override these three
    def _reset(self, first, dh0_m, measurement):
        self._y = self._start(first, measurement)
        self._eta = 1.0 / dh0_m

    def _get_state(self):
        return np.array(self._y + [self._eta])

    def _set_state(self, state):
        self._y = state[:4].tolist()
        self._eta = float(state[4])

    def _correction_interval(self, t_s: float) -> float:
        """Time over which to integrate the correction at a measurement, and restart the clock."""
        dtc = min(t_s - self._t_corrected, self.params.max_correction_interval_s)
        self._t_corrected = t_s
        return dtc


def _observability(y, u: tuple) -> float:
    """Thesis 3.40 on the given edges: ``sum Phi_i^2``."""
    _, _, a, b = edge_terms(y[0], y[1], u)
    _, _, c, d = edge_terms(y[2], y[3], u)
    return a * a + b * b + c * c + d * d


def _check_correction_interval(params) -> None:
    params._check_range("max_correction_interval_s", 0.005, 1.0)


def _check_bool(params, name: str) -> None:
    value = getattr(params, name)
    if not isinstance(value, bool):
        raise ValueError(f"{type(params).__name__}.{name} must be true or false, got {value!r}")


# --------------------------------------------------------------------------- ccpi-2l
@dataclass(frozen=True)
class CCPI2LParams(ObserverParams):
    """Parameters of :class:`CCPI2L`.

    Attributes
    ----------
    omega_rps : float
        Natural frequency of the high-gain error dynamics in the zeta coordinates, rad/s
        (thesis 4.44-4.46 footnote 4: ``k1 = 2 xi omega``, ``k2 = omega^2``).
    damping : float
        Damping ``xi`` of those dynamics (thesis 5.2.1: 0.8).
    observability_floor : float
        Damping of the left inverse, (m/s)^2: the eta correction is scaled by about
        ``O / (O + floor)`` where ``O = sum Phi_i^2`` (thesis 3.40), so it fades out near the
        unobservable start instead of dividing by zero.
    max_correction_interval_s : float
        Longest time a single correction integrates (see module docstring).
    """

    omega_rps: float = 2.5
    damping: float = 0.8
    observability_floor: float = 0.5
    max_correction_interval_s: float = 0.1

    def __post_init__(self):
        self._check_range("omega_rps", 0.01, 100.0)
        self._check_range("damping", 0.05, 5.0)
        self._check_range("observability_floor", 1e-9, 1e4)
        _check_correction_interval(self)


class CCPI2L(_LineObserver):
    """Coordinate change with pseudo-inverse on the two edges (thesis 4.3.2, Conjecture 4.3.2).

    State ``x = [theta_l, rho_l, theta_r, rho_r, eta]`` (``Estimate.state``). The immersion
    ``zeta = tau(x) = [y, y']`` (4.76) puts the system in the chain-of-integrators form 4.41,
    observed with the high-gain correction ``kappa = [k1 (y - y_hat), k2 (y - y_hat)]`` (4.44);
    the observer in the original coordinates is (4.73/4.77)::

        x_hat' = f(x_hat) + [d tau / dx (x_hat)]^+ kappa

    with ``f`` the model (evaluated at the estimate, as in the general form 4.73) and the 8x5
    Jacobian ``d tau/dx = [[I4, 0], [D, Phi]]`` (4.78; ``D = dg/dy + eta dPhi/dy``, the "*"
    entries). The left inverse ``(J^T J)^-1 J^T`` (thesis footnote 7) is damped on the eta
    diagonal by ``observability_floor`` (``J^T J`` is singular where ``Phi = 0``).
    """

    name: ClassVar[str] = "ccpi-2l"
    params_type: ClassVar[type] = CCPI2LParams

    def _step(self, inp, dt_s, measurement):
        p = self.params
        u1 = inputs_of(inp)
        y, eta = _heun(self._y, self._eta, self._u_prev, u1, dt_s)     # x_hat' = f(x_hat)
        self._u_prev = u1
        if measurement is not None:
            ym = measured_pair(measurement, y)
            dtc = self._correction_interval(inp.t_s)
            e = [ym[0] - y[0], ym[1] - y[1], ym[2] - y[2], ym[3] - y[3]]
            k1 = 2.0 * p.damping * p.omega_rps                           # 4.46, footnote 4
            k2 = p.omega_rps ** 2
            dx = ccpi_correction(_edge_blocks(y, eta, u1), e, k1, k2, p.observability_floor)  # 4.77
            y = [y[0] + dtc * dx[0], y[1] + dtc * dx[1], y[2] + dtc * dx[2], y[3] + dtc * dx[3]]
            eta = eta + dtc * dx[4]
        self._y = y
        self._eta = clip_eta(eta)
        return Estimate(t_s=float(inp.t_s), dh_m=1.0 / self._eta, observability=_observability(y, u1),
                        coasting=measurement is None, state=self._get_state())


# --------------------------------------------------------------------------- cccj-2l
@dataclass(frozen=True)
class CCCJ2LParams(ObserverParams):
    """Parameters of :class:`CCCJ2L`.

    Attributes
    ----------
    omega_rps, damping : float
        High-gain error dynamics of the measured part of zeta (as :class:`CCPI2LParams`).
    k_fictitious : float
        Gain (1/s) on the fictitious output ``y_f = psi eta`` (thesis 4.89, ``K3``): the observer
        compares its ``zeta_9 = psi(y_hat) eta_hat + Phi . w_hat`` with ``psi(y) eta_hat``, which
        drives the completion states ``w`` back to zero.
    epsilon_sq : float
        ``epsilon^2`` of thesis 4.82, (m/s)^2: ``psi = max(epsilon^2 - sum Phi_i^2, 0)^2`` is non-zero
        only where the observability index 3.40 is below ``epsilon^2``.
    max_correction_interval_s : float
        Longest time a single correction integrates.
    """

    omega_rps: float = 2.5
    damping: float = 0.8
    k_fictitious: float = 5.0
    epsilon_sq: float = 2.0
    max_correction_interval_s: float = 0.1

    def __post_init__(self):
        self._check_range("omega_rps", 0.01, 100.0)
        self._check_range("damping", 0.05, 5.0)
        self._check_range("k_fictitious", 0.0, 1000.0)
        self._check_range("epsilon_sq", 1e-9, 1e4)
        _check_correction_interval(self)


class CCCJ2L(_LineObserver):
    """Coordinate change with Jacobian completion on the two edges (thesis 4.4.1 and 4.4.3).

    State ``[theta_l, rho_l, theta_r, rho_r, eta, w1, w2, w3, w4]`` (``Estimate.state``), the
    four ``w`` being the completion states (zero on the true system).

    Immersion (4.80-4.82): ``tau = [y, y', y_f]`` with the fictitious output ``y_f = psi(y, u) eta``,
    ``psi = max(epsilon^2 - sum Phi_i^2, 0)^2``. Completion (4.85, 4.92)::

        tau_e(x, w) = tau(x) + gamma w = [y, y' - w, psi eta + Phi . w]

    whose 9x9 Jacobian (4.93, here with every entry)::

        [[I4,                            0,   0   ],
         [D,                             Phi, -I4 ],
         [eta dpsi/dy + w^T dPhi/dy,     psi, Phi^T]]

    has determinant ``+-(psi + sum Phi_i^2) > 0``: invertible everywhere, also where the lines are
    unobservable (:func:`cccj_increment` solves it in closed form).

    The observer is 4.86, ``J [x_hat; w_hat]' = A tau_e + Omega(tau_e) + kappa - d tau_e/dt``, with
    the zeta dynamics taken at the x-part of ``tau_e^-1(zeta)`` (a smooth extension of Omega off
    ``w = 0``): ``A tau_e = [y' - w, 0, 0]``, ``Omega = [0, y'', d(psi eta)/dt]`` evaluated at
    ``x_hat``. Subtracting ``J [f(x_hat); 0]`` (which holds ``[y', y'', d(psi eta)/dt]`` at ``x_hat``
    minus the explicit time derivatives, and ``w^T dPhi/dy y'`` in the last row) leaves::

        [x_hat; w_hat]' = [f(x_hat); 0] + J^-1 ([-w_hat; 0; -Phi' . w_hat] + kappa)
        kappa = [k1 e; k2 e; k3 (psi(y) eta_hat - zeta_9)],   e = y - y_hat,
        zeta_9 = psi(y_hat) eta_hat + Phi(y_hat) . w_hat

    with ``Phi'`` the total derivative of Phi along the estimate (a difference over the step).
    With ``w_hat = 0`` and ``kappa = 0`` this is the model itself. ``f(x_hat)`` is integrated with
    Heun's method, the ``J^-1`` term with one step at the predicted state. The gain on the
    fictitious output (4.89, ``K3``) is what brings ``w_hat`` back to zero: where ``psi(y) = 0``
    (observable), the measured value of ``y_f`` is exactly 0.
    """

    name: ClassVar[str] = "cccj-2l"
    params_type: ClassVar[type] = CCCJ2LParams

    def _reset(self, first, dh0_m, measurement):
        self._y = self._start(first, measurement)
        self._eta = 1.0 / dh0_m
        self._w = [0.0, 0.0, 0.0, 0.0]
        self._phi_prev = pair_model(self._y, self._eta, self._u_prev)[2]

    def _get_state(self):
        return np.array(self._y + [self._eta] + self._w)

    def _set_state(self, state):
        self._y = state[:4].tolist()
        self._eta = float(state[4])
        self._w = state[5:9].tolist()

    def _dh_from_state(self, state):
        return 1.0 / clip_eta(float(state[4]))

    def _psi(self, phi) -> float:
        """``psi = max(epsilon^2 - |Phi|^2, 0)^2`` (4.82)."""
        m = self.params.epsilon_sq - (phi[0] ** 2 + phi[1] ** 2 + phi[2] ** 2 + phi[3] ** 2)
        return m * m if m > 0.0 else 0.0

    def _step(self, inp, dt_s, measurement):
        p = self.params
        u1 = inputs_of(inp)
        y, eta = _heun(self._y, self._eta, self._u_prev, u1, dt_s)     # [f(x_hat); 0]
        self._u_prev = u1
        w = self._w
        blocks = _edge_blocks(y, eta, u1)
        phi = [blocks[0][0], blocks[0][1], blocks[1][0], blocks[1][1]]
        # total derivative of Phi along the estimate, for the Omega_9 - dtau_e/dt term
        phi_dot_w = sum((phi[i] - self._phi_prev[i]) * w[i] for i in range(4)) / dt_s
        r = [-w[0] * dt_s, -w[1] * dt_s, -w[2] * dt_s, -w[3] * dt_s,     # A tau_e: zeta_1' = y' - w
             0.0, 0.0, 0.0, 0.0, -phi_dot_w * dt_s]
        if measurement is not None:
            ym = measured_pair(measurement, y)
            dtc = self._correction_interval(inp.t_s)
            e = [ym[0] - y[0], ym[1] - y[1], ym[2] - y[2], ym[3] - y[3]]
            k1 = 2.0 * p.damping * p.omega_rps                           # 4.44-4.46
            k2 = p.omega_rps ** 2
            zeta_9 = self._psi(phi) * eta + sum(phi[i] * w[i] for i in range(4))
            psi_meas = self._psi(pair_model(ym, eta, u1)[2])
            for i in range(4):
                r[i] += k1 * e[i] * dtc
                r[4 + i] += k2 * e[i] * dtc
            r[8] += p.k_fictitious * (psi_meas * eta - zeta_9) * dtc      # 4.89, K3
        dxw = cccj_increment(blocks, eta, w, r, p.epsilon_sq)            # 4.86: J^-1 (...)
        y = [y[0] + dxw[0], y[1] + dxw[1], y[2] + dxw[2], y[3] + dxw[3]]
        self._y = y
        self._eta = clip_eta(eta + dxw[4])
        self._w = [w[i] + dxw[5 + i] for i in range(4)]
        self._phi_prev = phi                                             # at the prediction of this step
        obs = phi[0] ** 2 + phi[1] ** 2 + phi[2] ** 2 + phi[3] ** 2
        return Estimate(t_s=float(inp.t_s), dh_m=1.0 / self._eta, observability=obs,
                        coasting=measurement is None, state=self._get_state())


# --------------------------------------------------------------------------- ii-2l
@dataclass(frozen=True)
class II2LParams(ObserverParams):
    """Parameters of :class:`II2L`.

    Attributes
    ----------
    gain_lambda : float
        ``lambda`` of thesis 4.23, s/m^2: the height error decays at about
        ``lambda * sum Phi_i^2`` (per second).
    k_filter : float
        ``k`` of thesis 4.27, 1/s: bandwidth of the measurement filter ``y_hat``.
    c_scaling, eps_scaling : float
        ``c`` and ``epsilon`` of thesis 4.27-4.28 (dynamic scaling: the filter gain grows as
        ``r^2`` and with the mismatch factors ``Delta`` when the filter lags).
    r_decay : float
        ``rho(y)`` of thesis 4.28 (a constant here), 1/s: how fast ``r`` returns to 1.
    max_correction_interval_s : float
        Longest interval used to damp the sampled I&I correction (see :class:`II2L`).
    project_state : bool
        Project the state's eta onto ``[ETA_MIN, ETA_MAX]`` after every step (True, default), or
        only the reported height (False: the 5 px settings; module docstring, "Image noise").
    """

    gain_lambda: float = 0.03
    k_filter: float = 20.0
    c_scaling: float = 1.0
    eps_scaling: float = 1.0
    r_decay: float = 1.0
    max_correction_interval_s: float = 0.1
    project_state: bool = True

    def __post_init__(self):
        self._check_range("gain_lambda", 1e-9, 100.0)
        self._check_range("k_filter", 0.01, 1000.0)
        self._check_range("c_scaling", 0.0, 1e6)
        self._check_range("eps_scaling", 0.0, 1e6)
        self._check_range("r_decay", 0.0, 100.0)
        _check_correction_interval(self)
        _check_bool(self, "project_state")


class II2L(_LineObserver):
    """Immersion and invariance with filtered measurements and dynamic scaling (thesis 4.2.2, [Karagiannis 09]).

    State (``Estimate.state``, 10 values): ``[y_hat (4), y_model (4), r, eta_hat]`` where
    ``y_hat`` is the filtered measurement of 4.19, ``y_model`` the last measured edges carried
    forward by the model (the sampled stand-in for ``y`` between camera frames), ``r`` the
    scaling factor of 4.28 and ``eta_hat = eta_bar + beta(y, y_hat)`` (4.18).

    With ``beta = lambda sum_edges [I_theta(theta; rho_hat) + I_rho(rho; theta_hat)]`` (4.29,
    :func:`~visland.estimation.lines_model.ii_edge_integral`) and ``eta_bar`` following 4.21
    (plus the ``-d beta/dt`` term that 4.21 omits: ``beta`` depends on time through ``v_C`` and
    ``n_C``), the estimate obeys ``eta_hat' = v3 eta_hat^2 + d beta/dy (y' - g(y) - Phi(y) eta_hat)``.
    Between two camera frames, ``y'`` is unknown and the last term is zero; at a frame the
    accumulated term is exactly ``beta(y_meas) - beta(y_model)`` (``y_hat`` and the inputs held),
    which is what ``step`` adds. Its gradient ``lambda Phi(mixed)`` (4.23) makes the error decay
    at ``lambda Phi(mixed) . Phi(y)``, about ``lambda sum Phi_i^2`` once ``y_hat`` tracks ``y``.

    Filter (4.19, 4.27): ``y_hat' = g(y) + Phi(y) eta_hat - K (y_hat - y)`` with the diagonal gain
    ``K_j = r^2 (k + eps c Delta_j^2)``, ``Delta_j`` the mismatch factor that multiplies ``e_j``
    in ``d beta/dy`` (4.31, 4.35); scaling (4.28):
    ``r' = -rho/2 (r - 1) + c r sum_j e_j^2 Delta_j^2``, ``e = y - y_hat``.
    """

    name: ClassVar[str] = "ii-2l"
    params_type: ClassVar[type] = II2LParams

    def _reset(self, first, dh0_m, measurement):
        y0 = self._start(first, measurement)
        self._y_hat = list(y0)
        self._y_model = list(y0)
        self._r = 1.0
        self._eta = 1.0 / dh0_m

    def _get_state(self):
        return np.array(self._y_hat + self._y_model + [self._r, self._eta])

    def _set_state(self, state):
        self._y_hat = state[:4].tolist()
        self._y_model = state[4:8].tolist()
        self._r = float(state[8])
        self._eta = float(state[9])

    def _step(self, inp, dt_s, measurement):
        p = self.params
        u1 = inputs_of(inp)
        y_old = self._y_model
        y_model, eta = _heun(y_old, self._eta, self._u_prev, u1, dt_s)
        self._u_prev = u1
        # the filter follows y with the same model increment (4.19 uses g(y) + Phi(y) eta_hat)
        y_hat = [self._y_hat[i] + (y_model[i] - y_old[i]) for i in range(4)]
        if measurement is not None:
            ym = measured_pair(measurement, y_model)
            dtc = self._correction_interval(inp.t_s)
            # eta_hat += beta(y_meas, y_hat) - beta(y_model, y_hat): the integral of 4.21 + 4.18
            d_beta = 0.0
            rate = 0.0                                   # lambda Phi(mixed) . Phi(y): decay rate of the error
            for k in (0, 2):
                d_beta += (ii_edge_integral(ym[k], ym[k + 1], y_hat[k], y_hat[k + 1], u1)
                           - ii_edge_integral(y_model[k], y_model[k + 1], y_hat[k], y_hat[k + 1], u1))
                g_t, g_r = ii_edge_gradient(ym[k], ym[k + 1], y_hat[k], y_hat[k + 1], u1)
                _, _, p_t, p_r = edge_terms(ym[k], ym[k + 1], u1)
                rate += g_t * p_t + g_r * p_r
            # the sampled correction is that of an implicit step (error / (1 + rate dt) rather than
            # error (1 - rate dt)): same first-order behaviour, stable for any gain and frame rate
            eta = eta + p.gain_lambda * d_beta / (1.0 + max(p.gain_lambda * rate, 0.0) * dtc)
            y_model = ym
        # filter pull and dynamic scaling (4.19, 4.27, 4.28), y_model standing in for y
        growth = 0.0
        r2 = self._r * self._r
        for k in (0, 2):
            delta_theta, delta_rho = ii_edge_mismatch(y_model[k], y_model[k + 1], y_hat[k], y_hat[k + 1], u1)
            delta_theta *= p.gain_lambda
            delta_rho *= p.gain_lambda
            # e_rho multiplies Delta_theta in d beta/d theta, e_theta multiplies Delta_rho in d beta/d rho
            for j, delta in ((k, delta_rho), (k + 1, delta_theta)):
                e_j = y_model[j] - y_hat[j]
                gain = r2 * (p.k_filter + p.eps_scaling * p.c_scaling * delta * delta)
                y_hat[j] = y_model[j] - math.exp(-gain * dt_s) * e_j
                growth += e_j * e_j * delta * delta
        r = 1.0 + (self._r - 1.0) * math.exp(-0.5 * p.r_decay * dt_s)
        self._r = r * math.exp(min(p.c_scaling * growth * dt_s, 1.0))
        self._y_hat = y_hat
        self._y_model = y_model
        self._eta = clip_eta(eta) if p.project_state else eta     # the reported height always is
        return Estimate(t_s=float(inp.t_s), dh_m=1.0 / clip_eta(eta), observability=_observability(y_model, u1),
                        coasting=measurement is None, state=self._get_state())


# --------------------------------------------------------------------------- oj-2l
@dataclass(frozen=True)
class OJ2LParams(ObserverParams):
    """Parameters of :class:`OJ2L`.

    Attributes
    ----------
    k_filter : float
        Output-injection gain ``h`` on the edges, 1/s.
    gain_alpha : float
        Identifier gain ``alpha`` on eta, s/m^2 (eta' gets ``alpha Phi^T (y - y_hat)``): once the
        edges are tracked the height error decays at about ``alpha sum Phi_i^2 / h`` per second.
    max_correction_interval_s : float
        Longest time a single correction integrates.
    regressor_at_measurement : bool
        Take the regressor ``Phi`` at the measured edges (True, default, as [Jankovic 95]) or at the
        observer's prediction (False: the 5 px settings; with noisy edges the measured regressor
        is correlated with the innovation, module docstring "Image noise").
    """

    k_filter: float = 6.0
    gain_alpha: float = 0.15
    max_correction_interval_s: float = 0.1
    regressor_at_measurement: bool = True

    def __post_init__(self):
        self._check_range("k_filter", 0.01, 1000.0)
        self._check_range("gain_alpha", 1e-9, 1e4)
        _check_correction_interval(self)
        _check_bool(self, "regressor_at_measurement")


class OJ2L(_LineObserver):
    """Identifier-based observer of [Jankovic 95] on the two edges (the thesis's OJ_2D).

    State ``x = [theta_l, rho_l, theta_r, rho_r, eta]`` (``Estimate.state``). Jankovic and Ghosh
    treat the unknown range as the parameter of an identifier (the adaptive-observer structure
    of [Marino 95]): a copy of the model with output injection on the measured part and a
    gradient update of the unmeasured part along the regressor ``Phi``::

        y_hat'   = g(y_hat) + Phi(y_hat) eta_hat + h (y - y_hat)
        eta_hat' = v3 eta_hat^2 + alpha Phi(y)^T (y - y_hat)      (Phi(y_hat) if not regressor_at_measurement)

    With ``e = y - y_hat`` and ``z = eta - eta_hat`` the error obeys ``e' ~ Phi z - h e``,
    ``z' ~ -alpha Phi^T e`` (up to terms of second order); ``V = |e|^2/2 + z^2/(2 alpha)``
    decreases as ``-h |e|^2`` and persistent excitation of ``Phi`` (observability, thesis 3.40)
    makes z converge.
    """

    name: ClassVar[str] = "oj-2l"
    params_type: ClassVar[type] = OJ2LParams

    def _step(self, inp, dt_s, measurement):
        p = self.params
        u1 = inputs_of(inp)
        y, eta = _heun(self._y, self._eta, self._u_prev, u1, dt_s)
        self._u_prev = u1
        if measurement is not None:
            ym = measured_pair(measurement, y)
            dtc = self._correction_interval(inp.t_s)
            e = [ym[0] - y[0], ym[1] - y[1], ym[2] - y[2], ym[3] - y[3]]
            # the regressor Phi at the measured output (Jankovic), or at the prediction (noise)
            phi = pair_model(ym if p.regressor_at_measurement else y, eta, u1)[2]
            eta = eta + p.gain_alpha * dtc * (phi[0] * e[0] + phi[1] * e[1] + phi[2] * e[2] + phi[3] * e[3])
            pull = 1.0 - math.exp(-p.k_filter * dtc)                      # exact for the linear injection
            y = [y[i] + pull * e[i] for i in range(4)]
        self._y = y
        self._eta = clip_eta(eta)
        return Estimate(t_s=float(inp.t_s), dh_m=1.0 / self._eta, observability=_observability(y, u1),
                        coasting=measurement is None, state=self._get_state())


# --------------------------------------------------------------------------- ekf-2l
@dataclass(frozen=True)
class EKF2LParams(ObserverParams):
    """Parameters of :class:`EKF2L` (the Q, R and P(0) of thesis annex 5.8).

    Attributes
    ----------
    sigma_line : float
        Standard deviation of each measured theta (rad) and rho (normalised units): ``R``.
        1e-3 is about 2.5 pixels at the SPEC focal length (a tuning value: the thesis's ideal
        measurements have no noise).
    q_line : float
        Process noise density on each edge coordinate, per sqrt(s): ``Q`` for y.
    q_eta_rel : float
        Process noise density on eta relative to eta, per sqrt(s): ``Q`` for eta is
        ``(q_eta_rel eta_hat)^2`` per second.
    p0_line : float
        Initial standard deviation of the edges (they start at the first measurement).
    p0_eta_rel : float
        Initial standard deviation of eta relative to the guess (the seeds start 20 % off).
    """

    sigma_line: float = 1e-3
    q_line: float = 1e-5
    q_eta_rel: float = 1e-3
    p0_line: float = 1e-3
    p0_eta_rel: float = 0.25

    def __post_init__(self):
        self._check_range("sigma_line", 1e-9, 1.0)
        self._check_range("q_line", 0.0, 1.0)
        self._check_range("q_eta_rel", 0.0, 10.0)
        self._check_range("p0_line", 1e-9, 1.0)
        self._check_range("p0_eta_rel", 1e-6, 10.0)


def _make_filterpy_ekf(x0: np.ndarray, P0: np.ndarray, R: np.ndarray):
    """A filterpy ExtendedKalmanFilter holding the mean ``x`` (5,), the covariance ``P`` and ``R``.

    :class:`EKF2L` writes its predict and update out (class docstring) and keeps them in this
    object, as :class:`visland.estimation.kalman.KF2P` does with filterpy's KalmanFilter.
    """
    from filterpy.kalman import ExtendedKalmanFilter

    ekf = ExtendedKalmanFilter(dim_x=5, dim_z=4)
    ekf.x = np.array(x0, dtype=float).ravel().copy()
    ekf.P = P0.copy()
    ekf.R = R.copy()
    return ekf


def _ekf_linearisation(y, eta: float, u: tuple) -> tuple:
    """The model at ``(y, eta)`` and its Jacobian, from one evaluation per edge.

    Returns ``(ydot (list of 4), etadot, F (list of 13 floats), observability)``: ``ydot, etadot``
    as :func:`pair_model`; ``F`` the non-zero entries of ``F = [[D, Phi], [0, 2 v3 eta]]`` (thesis
    annex 5.9, ``D = dg/dy + eta dPhi/dy`` block diagonal) in the order of :data:`_F_ENTRIES`;
    ``observability`` thesis 3.40 (``sum Phi_i^2``, as :func:`_observability`).
    """
    gtl, grl, ptl, prl, Jgl, JPl = edge_terms_and_jacobian(y[0], y[1], u)
    gtr, grr, ptr, prr, Jgr, JPr = edge_terms_and_jacobian(y[2], y[3], u)
    F = [Jgl[0][0] + eta * JPl[0][0], Jgl[0][1] + eta * JPl[0][1], ptl,
         Jgl[1][0] + eta * JPl[1][0], Jgl[1][1] + eta * JPl[1][1], prl,
         Jgr[0][0] + eta * JPr[0][0], Jgr[0][1] + eta * JPr[0][1], ptr,
         Jgr[1][0] + eta * JPr[1][0], Jgr[1][1] + eta * JPr[1][1], prr,
         2.0 * u[9] * eta]
    return ([gtl + ptl * eta, grl + prl * eta, gtr + ptr * eta, grr + prr * eta], u[9] * eta * eta, F,
            ptl * ptl + prl * prl + ptr * ptr + prr * prr)


#: (row, column) of the entries :func:`_ekf_linearisation` returns in F.
_F_ENTRIES = ((0, 0), (0, 1), (0, 4), (1, 0), (1, 1), (1, 4), (2, 2), (2, 3), (2, 4), (3, 2), (3, 3), (3, 4),
              (4, 4))


class EKF2L(_LineObserver):
    """Extended Kalman filter on the two edges (thesis annex, 5.7-5.9); filterpy's
    ExtendedKalmanFilter holds the mean and covariance, its predict and update are written out here.

    ``Estimate.state`` holds the mean ``x = [theta_l, rho_l, theta_r, rho_r, eta]`` followed by
    the 25 entries of the covariance ``P`` (row-major). The thesis writes the continuous-time
    filter (5.8); this is its discrete form at the inertial rate:

    - predict (every step): the mean follows the model ``z' = [g + Phi eta, v3 eta^2]`` (Heun),
      ``P <- F_d P F_d^T + Q dt`` with ``F_d = I + F dt`` and
      ``F = dz'/dz = [[D, Phi], [0, 2 v3 eta]]`` (5.9, ``D = dg/dy + eta dPhi/dy``);
    - update (camera frames): ``H = [I4 0]`` (5.9), ``R = sigma_line^2 I4``, the Joseph form of
      filterpy's ``update``. The measured edges are first written in the chart nearest the
      prediction.

    Written out rather than through filterpy's ``predict``/``update`` for the cost target (issue 12:
    under 0.2 s per 100 s approach): with ``H = [I4 0]``, ``P H^T`` is ``P``'s first four columns,
    ``H P H^T`` its upper-left block and ``K H = [K 0]``; ``K = P H^T S^-1`` comes from a Cholesky
    solve (``S`` is symmetric positive definite) instead of an explicit inverse. The model's value,
    its Jacobian and the observability index at the posterior are evaluated once and reused by the
    next step's prediction (same point, same inputs). Same filter as before to round-off (states
    within 1e-9 relative on thesis-1, -4 and -7 at 0, 1 and 5 px).
    """

    name: ClassVar[str] = "ekf-2l"
    params_type: ClassVar[type] = EKF2LParams

    def _reset(self, first, dh0_m, measurement):
        p = self.params
        y0 = self._start(first, measurement)
        eta0 = 1.0 / dh0_m
        P0 = np.diag([p.p0_line ** 2] * 4 + [(p.p0_eta_rel * eta0) ** 2])
        self._ekf = _make_filterpy_ekf(np.array(y0 + [eta0]), P0, np.eye(4) * p.sigma_line ** 2)
        self._I5 = np.eye(5)
        self._Fd = np.eye(5)
        self._q_line_sq = p.q_line ** 2
        self._linearised = None          # (x, u, _ekf_linearisation(x, u)) of the last posterior
        from scipy.linalg.lapack import dposv     # heavy import kept out of the CLI start-up
        self._dposv = dposv

    def _get_state(self):
        return np.concatenate([self._ekf.x, self._ekf.P.ravel()])

    def _set_state(self, state):
        self._ekf.x = state[:5].copy()
        self._ekf.P = state[5:].reshape(5, 5).copy()

    def _dh_from_state(self, state):
        return 1.0 / clip_eta(float(state[4]))

    def _linearise(self, x: list, u: tuple) -> tuple:
        cached = self._linearised
        if cached is not None and cached[1] is u and cached[0] == x:
            return cached[2]
        return _ekf_linearisation(x[:4], x[4], u)

    def _step(self, inp, dt_s, measurement):
        p = self.params
        ekf = self._ekf
        u0 = self._u_prev
        u1 = inputs_of(inp)
        x = ekf.x.tolist()
        y, eta = x[:4], x[4]
        ydot, etadot, F, _ = self._linearise(x, u0)                       # F at the prior (5.9)
        # predict: P = F_d P F_d^T + Q dt, F_d = I + F dt (entries written into the identity)
        Fd = self._Fd
        for (i, j), f in zip(_F_ENTRIES, F):
            Fd[i, j] = (1.0 + f * dt_s) if i == j else f * dt_s
        P = Fd @ ekf.P @ Fd.T
        q_line = self._q_line_sq * dt_s
        for i in range(4):
            P[i, i] += q_line
        P[4, 4] += (p.q_eta_rel * eta) ** 2 * dt_s
        y_new, eta_new = _heun(y, eta, u0, u1, dt_s, first=(ydot, etadot))
        x_prior = np.array(y_new + [eta_new])
        self._u_prev = u1
        if measurement is not None:
            # update, H = [I4 0]: innovation z - H x, S = H P H^T + R, K = P H^T S^-1,
            # x += K (z - H x), P = (I - K H) P (I - K H)^T + K R K^T (Joseph form)
            ym = measured_pair(measurement, y_new)
            PHt = P[:, :4]
            S = P[:4, :4] + ekf.R
            _, Kt, info = self._dposv(S, PHt.T)
            if info != 0:                                                   # not positive definite: LU
                Kt = np.linalg.solve(S, PHt.T)
            K = Kt.T
            x_post = x_prior + K @ (np.array(ym) - x_prior[:4])
            I_KH = self._I5.copy()
            I_KH[:, :4] -= K
            P = I_KH @ P @ I_KH.T + K @ ekf.R @ Kt
        else:
            x_post = x_prior
        eta_post = float(x_post[4])
        if eta_post != clip_eta(eta_post):
            x_post[4] = clip_eta(eta_post)
        ekf.x = x_post
        ekf.P = P
        x = x_post.tolist()
        linearised = _ekf_linearisation(x[:4], x[4], u1)
        self._linearised = (x, u1, linearised)
        return Estimate(t_s=float(inp.t_s), dh_m=1.0 / x[4], observability=linearised[3],
                        coasting=measurement is None, state=self._get_state())


#: SPEC name -> class, for the registry and the tests.
LINE_OBSERVERS = {cls.name: cls for cls in (OJ2L, II2L, CCPI2L, CCCJ2L, EKF2L)}
