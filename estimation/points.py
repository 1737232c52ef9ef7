"""Observers on two points: the threshold corners P' and P'' in the virtual frame (thesis 4.1).

The system (thesis 3.29 / 4.1, re-derived in SPEC frames by :mod:`visland.features`)::

    y_i' = Phi_i(y, v) eta,   Phi = (v3 y'1 - v1, v3 y'2 - v2, v3 y''1 - v1, v3 y''2 - v2)
    eta' = v3 eta^2,          eta = 1/dH

with ``y = (y'1, y'2, y''1, y''2)`` the virtual coordinates of P' and P'' (thesis 3.23) and
``v`` the camera velocity in the runway axes (z down). The observability index is
``O = |Phi|^2`` (thesis 3.30).

Time discretisation (all observers here). Between camera frames the model is integrated
*exactly*: in the virtual frame a runway point moves as ``X_v' = -v1, Y_v' = -v2, Z_v' = -v3``,
so with ``D = integral of v dt`` (trapezoid of the 50 Hz velocities)::

    d = 1 - eta D3,   y_1 <- (y_1 - eta D1) / d,   y_2 <- (y_2 - eta D2) / d,   eta <- eta / d.

At a camera frame the observer's correction term (continuous time in the thesis) is applied
over the time since the previous correction, ``dt_c`` (at most ``max_correction_interval_s``,
so a long gap is not corrected as one huge step): a continuous-discrete observer whose fixed
point with exact measurements is the true state, with no lag.

Each observer keeps the predicted points ``y_hat`` and ``eta_hat``; its state vector
(``Estimate.state``) is ``[y'1, y'2, y''1, y''2, eta]`` unless its docstring says otherwise.

References
----------
V. Gibert, "Analyse d'observabilite et synthese d'observateurs robustes pour l'atterrissage
base vision d'avions de ligne sur des pistes inconnues", PhD thesis, 2016 (seed 002).
    Ch. 3.3 (virtual frame, eq. 3.19-3.30) and 4.1-4.3 (the two-point observers, eq. 4.1-4.58;
    eq. 4.55 corrected as ../shared/seeds/README.md says).
V. Gibert, L. Burlion, A. Chriette, J. Boada, F. Plestan, "Nonlinear observers in vision system:
application to civil aircraft landing", European Control Conference, 2015 (seed 000).
    Eq. (21)-(24): the sliding-mode correction (Levant's differentiator).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from visland.estimation.base import Estimate, Observer, ObserverInput, ObserverParams, clip_eta
from visland.estimation.tuning import LEVANT_A1, LEVANT_A2, omega_for_settling_time

__all__ = [
    "PointsParams", "OJParams", "IIParams", "CCCSParams", "CCPIHGParams", "CCPIHOSMParams", "CCCJParams",
    "OJ2P", "II2P", "CCCS2P", "CCPIHG2P", "CCPIHOSM2P", "CCCJ2P",
    "points_phi", "points_observability", "output_combination", "pseudo_inverse_correction",
    "levant_correction", "levant_correction_implicit", "virtual_noise_sigma",
]


#: Longest explicit step of a correction (s): the camera rate the gains were tuned at (25 Hz);
#: a longer interval between frames is corrected in sub-steps (see ``_PointsObserver._step``).
CORRECTION_SUBSTEP_S = 0.04


# --------------------------------------------------------------------------- maths
def points_phi(y, v) -> list:
    """``Phi(y, v)`` of thesis 4.1 for a flat list of point coordinates ``[y1, y2, y1, y2, ...]``.

    Parameters
    ----------
    y : sequence of float, length 2k
        Virtual coordinates ``[y1, y2, y1, y2, ...]`` of k points (thesis 3.23).
    v : sequence of 3 floats
        Camera velocity in runway axes (z down), m/s.

    Returns
    -------
    list of float, length 2k
        ``v3 y_i - v_i`` per coordinate, m/s.
    """
    v1, v2, v3 = v[0], v[1], v[2]
    out = []
    for k in range(0, len(y), 2):
        out.append(v3 * y[k] - v1)
        out.append(v3 * y[k + 1] - v2)
    return out


def points_observability(y, v) -> float:
    """Thesis 3.30: ``O = sum Phi_i^2`` over the points' coordinates, (m/s)^2.

    Parameters
    ----------
    y : sequence of float, length 2k
        Virtual coordinates ``[y1, y2, ...]``.
    v : sequence of 3 floats
        Camera velocity in runway axes, m/s.

    Returns
    -------
    float
    """
    return sum(p * p for p in points_phi(y, v))


def output_combination(y, v) -> float:
    """The combined output ``y_a`` of thesis 4.55, corrected (../shared/seeds/README.md).

    ``y_a = sum over points of (v1 y1 + v2 y2 - v3 (y1^2 + y2^2) / 2)``; then
    ``y_a' = Delta_y eta + chi`` with ``Delta_y = -O = 2 v3 y_a - 2 (v1^2 + v2^2)`` (two points)
    and ``chi = sum (v1' y1 + v2' y2 - v3' (y1^2 + y2^2) / 2)``.

    Parameters
    ----------
    y : sequence of float, length 2k
        Virtual coordinates of the points, flat.
    v : sequence of 3 floats
        Camera velocity in runway axes (z down), m/s.

    Returns
    -------
    float
        ``y_a``, m/s.
    """
    v1, v2, v3 = v[0], v[1], v[2]
    total = 0.0
    for k in range(0, len(y), 2):
        a, b = y[k], y[k + 1]
        total += v1 * a + v2 * b - 0.5 * v3 * (a * a + b * b)
    return total


def pseudo_inverse_correction(phi, b: float, kappa_y, kappa_d) -> tuple[list, float]:
    """``[dtau/dx]^+ kappa`` for ``tau = (y, y')`` (thesis 4.68 / 4.73, any number m of outputs).

    With ``x = (y, eta)`` and ``y' = Phi eta`` the Jacobian is ``J = [[I, 0], [b I, Phi]]``
    where ``b = dPhi_i/dy_i * eta = v3 eta`` (points) and its left pseudo-inverse
    ``(J^T J)^{-1} J^T`` has a closed form: with ``a = 1 + b^2``, ``r = kappa_y + b kappa_d`` and
    ``q = Phi . kappa_d``::

        s   = (a q - b Phi . r) / |Phi|^2          (eta row)
        u_i = (r_i - b Phi_i s) / a                (y rows)

    (Schur complement of ``J^T J = [[a I, b Phi], [b Phi^T, |Phi|^2]]``.) Returns ``(u, s)``.

    Parameters
    ----------
    phi : sequence of float, length m
        The regressor ``Phi`` at ``x_hat``.
    b : float
        ``v3 eta`` (points).
    kappa_y, kappa_d : sequence of float, length m
        The correction on the outputs and on their derivatives.

    Returns
    -------
    u : list of float, length m
        Correction of the outputs.
    s : float
        Correction of eta.
    """
    a = 1.0 + b * b
    r = [ky + b * kd for ky, kd in zip(kappa_y, kappa_d)]
    q = sum(p * kd for p, kd in zip(phi, kappa_d))
    phi2 = sum(p * p for p in phi)
    s = (a * q - b * sum(p * ri for p, ri in zip(phi, r))) / phi2
    u = [(ri - b * p * s) / a for ri, p in zip(r, phi)]
    return u, s


def levant_correction(error: float, lipschitz: float, a1: float = LEVANT_A1, a2: float = LEVANT_A2) -> tuple[float, float]:
    """Levant's second-order sliding-mode correction for one output (thesis 4.48-4.49).

    ``alpha = a1 L^(1/2) |e|^(1/2) sign(e)`` on the output row and ``a2 L sign(e)`` on its
    derivative row (``sign(alpha) = sign(e)``).

    Parameters
    ----------
    error : float
        Output error ``e = y - y_hat``.
    lipschitz : float
        The bound L.
    a1, a2 : float, default 1.5, 1.1
        Levant's coefficients.

    Returns
    -------
    output_row, derivative_row : float
    """
    if error > 0.0:
        return a1 * math.sqrt(lipschitz * error), a2 * lipschitz
    if error < 0.0:
        return -a1 * math.sqrt(-lipschitz * error), -a2 * lipschitz
    return 0.0, 0.0


def levant_correction_implicit(error: float, lipschitz: float, a1: float, a2: float, h: float) -> tuple[float, float]:
    """Levant's correction discretised implicitly over a step ``h`` (no chattering).

    Explicit Euler of ``sign(e)`` makes the correction overshoot the sliding surface at every
    step and chatter (ccpi-hosm-2p: +-7 m of dH at 3-4 km on ideal measurements). Following the
    implicit discretisation of sliding-mode terms (Acary and Brogliato, "Implicit Euler numerical
    scheme and chattering-free implementation of sliding mode systems", Systems & Control
    Letters 59, 2010; for the super-twisting algorithm Brogliato, Polyakov and Efimov, IEEE TAC
    65(8), 2020) the discontinuous terms are evaluated at the end of the step:

    - output row: ``e+ = e - h a1 L^(1/2) |e+|^(1/2) sign(e+)``; with ``s = |e+|^(1/2)`` this is
      ``s^2 + b s - |e| = 0``, ``b = h a1 L^(1/2)``, so ``s = (sqrt(b^2 + 4|e|) - b) / 2`` and the
      correction ``a1 L^(1/2) s sign(e)`` never carries ``e`` across zero;
    - derivative row: the set-valued ``sign(e+)`` in ``[-1, 1]``; its selection that brings
      ``e`` to the surface within the step (the derivative channel moves ``e`` by ``h^2 a2 L``)
      is ``sat(e / (h^2 a2 L))``: ``sign(e)`` far from the surface, proportional on it.

    Away from the surface (``|e| >> h^2 L``) both coincide with :func:`levant_correction`.

    Parameters
    ----------
    error : float
        Output error ``e``.
    lipschitz : float
        The bound L.
    a1, a2 : float
        Levant's coefficients.
    h : float
        The step, seconds.

    Returns
    -------
    output_row, derivative_row : float
    """
    if error == 0.0 or h <= 0.0:
        return 0.0, 0.0
    magnitude = abs(error)
    root_l = math.sqrt(lipschitz)
    b = h * a1 * root_l
    s = 0.5 * (math.sqrt(b * b + 4.0 * magnitude) - b)
    sign = 1.0 if error > 0.0 else -1.0
    layer = h * h * a2 * lipschitz
    return sign * a1 * root_l * s, a2 * lipschitz * (sign if magnitude >= layer else error / layer)


def virtual_noise_sigma(y, image_sigma_rad: float) -> list:
    """Standard deviation of each virtual coordinate (thesis 3.23) for an image noise ``image_sigma_rad``.

    ``y_1 = X/Z`` is the cotangent of the depression angle, so an angle error ``sigma`` moves it
    by ``(1 + y_1^2) sigma``; ``y_2 = Y/Z`` by about ``sqrt(1 + y_1^2) sigma`` (as in
    :mod:`visland.estimation.kalman`). ``y`` is the flat list ``[y1, y2, y1, y2, ...]``.

    Parameters
    ----------
    y : sequence of float
        The flat list of virtual coordinates.
    image_sigma_rad : float
        Image noise as an angle, radians.

    Returns
    -------
    list of float
        One standard deviation per coordinate.
    """
    out = []
    for k in range(0, len(y), 2):
        g = 1.0 + y[k] * y[k]
        out.append(g * image_sigma_rad)
        out.append(math.sqrt(g) * image_sigma_rad)
    return out


# --------------------------------------------------------------------------- parameters
@dataclass(frozen=True)
class PointsParams(ObserverParams):
    """Common to the two-point observers.

    Parameters
    ----------
    max_correction_interval_s : float
        Longest time one camera frame's correction integrates over, seconds (after a gap of
        missing frames the observer corrects as for one nominal interval).
    """

    max_correction_interval_s: float = 0.1

    def __post_init__(self):
        self._check_positive("max_correction_interval_s")


@dataclass(frozen=True)
class OJParams(PointsParams):
    """Identifier-based observer (Jankovic and Ghosh 1995) gains.

    Parameters
    ----------
    k_y : 1/s, output-injection gain of the identifier ``y_hat' = Phi eta_hat + k_y (y - y_hat)``.
    k_eta : s/m^2, adaptation gain ``eta_hat' = v3 eta_hat^2 + k_eta Phi(y)^T (y - y_hat)``.
    """

    k_y: float = 1.0
    k_eta: float = 3.0e-4

    def __post_init__(self):
        super().__post_init__()
        self._check_positive("k_y", "k_eta")


@dataclass(frozen=True)
class IIParams(PointsParams):
    """Immersion and invariance (thesis 4.2.1): ``lambda_`` in s/m^2, the decay rate is ``lambda_ O``.

    Parameters
    ----------
    lambda_ : float
        Gain lambda, s/m^2 (the error decays at the rate ``lambda_ O``, thesis 4.8).
    """

    lambda_: float = 1.0e-4

    def __post_init__(self):
        super().__post_init__()
        self._check_positive("lambda_")


@dataclass(frozen=True)
class _SecondOrderParams(PointsParams):
    """Pole placement ``s^2 + 2 xi omega s + omega^2`` by a 5 % response time and a damping.

    Chapter 5.2.1 of the thesis: response time 6 s, damping 0.8.

    Parameters
    ----------
    response_time_s : float
        5 % response time of the correction's second-order poles, seconds.
    damping : float
        Damping ratio xi of those poles.
    lambda_hg : float
        High-gain scaling of thesis 4.45 (``Lambda = diag(lambda, lambda^2)``, 1 = no scaling).
    """

    response_time_s: float = 6.0
    damping: float = 0.8
    lambda_hg: float = 1.0

    def __post_init__(self):
        super().__post_init__()
        self._check_positive("response_time_s", "lambda_hg")
        self._check_range("damping", 0.05, 0.999)

    @property
    def omega_rad_s(self) -> float:
        return omega_for_settling_time(self.response_time_s, self.damping)

    @property
    def gains(self) -> tuple[float, float]:
        """``(K1 / lambda, K2 / lambda^2)`` with ``K1 = 2 xi omega``, ``K2 = omega^2`` (thesis 4.44-4.46)."""
        omega = self.omega_rad_s
        return 2.0 * self.damping * omega / self.lambda_hg, omega * omega / self.lambda_hg ** 2


@dataclass(frozen=True)
class CCCSParams(_SecondOrderParams):
    """Output combination observer (thesis 4.3.1.2).

    Robustness to image noise (issue 12; both 0 by default, the thesis's observer).

    Parameters
    ----------
    noise_sigma_rad : image noise as an angle (1 px of the SPEC camera = 1/2472 rad). ``y_a`` is
        quadratic in the corners, so noise of variance ``s_i^2`` on each virtual coordinate
        (:func:`virtual_noise_sigma`) biases the measured ``y_a`` by ``-v3/2 sum s_i^2``; with 5 px
        5 km out that is as large as the signal ``Delta_y eta``, and the bias is added back to
        the innovation.
    max_eta_rate : 1/s, bound on the relative rate of the eta correction ``|eta_hat'| / eta_hat``
        (a saturation of the correction term of 4.66: its ``1 / Delta_y`` is large where the
        observability index dips, and with 5 px one noisy frame there threw eta to its bound).
    """

    max_eta_rate: float = 0.0
    noise_sigma_rad: float = 0.0

    def __post_init__(self):
        super().__post_init__()
        self._check_range("max_eta_rate", 0.0, 1e6)
        self._check_range("noise_sigma_rad", 0.0, 0.1)


@dataclass(frozen=True)
class CCPIHGParams(_SecondOrderParams):
    """Pseudo-inverse observer, high-gain correction (thesis 4.3.1.3 with 4.44-4.46): the gains of
    :class:`_SecondOrderParams`."""


@dataclass(frozen=True)
class _LevantParams(PointsParams):
    """The tuning of Levant's second-order sliding-mode correction, shared by the thesis's
    ``ccpi-hosm-2p`` (4.47-4.49) and ECC'15's ``ecc-hosm`` (eq. 23), which differ in ``L`` only.

    Parameters
    ----------
    lipschitz : float
        L of thesis 4.47 (ECC'15 eq. 23), bound on the output's second derivative error (1/s^2
        in virtual coordinates).
    a1, a2 : float
        Levant's coefficients (1.5 and 1.1).
    implicit : bool
        Discretise the sliding-mode terms implicitly (:func:`levant_correction_implicit`, no
        chattering; default) or by explicit Euler of ``sign`` (the thesis's form).
    """

    lipschitz: float = 1.0e-2
    a1: float = LEVANT_A1
    a2: float = LEVANT_A2
    implicit: bool = True

    def __post_init__(self):
        super().__post_init__()
        self._check_positive("lipschitz", "a1", "a2")
        if not isinstance(self.implicit, bool):
            raise ValueError(f"{type(self).__name__}.implicit must be true or false, got {self.implicit!r}")


@dataclass(frozen=True)
class CCPIHOSMParams(_LevantParams):
    """Pseudo-inverse observer, high-order sliding-mode correction (thesis 4.47-4.49); the tuning
    of :class:`_LevantParams` with ``L = 0.01``."""


@dataclass(frozen=True)
class CCCJParams(_SecondOrderParams):
    """Jacobian completion (thesis 4.4.2): second-order poles plus the fictitious output's gain.

    Parameters
    ----------
    k_fictitious : 1/s, gain K3 of 4.89 on the fictitious output ``y_f = psi eta``.
    epsilon : m/s, the threshold of 4.82 below which ``psi = max(eps^2 - |Phi|^2, 0)^2`` acts.
    """

    k_fictitious: float = 1.0
    epsilon: float = 0.5

    def __post_init__(self):
        super().__post_init__()
        self._check_positive("k_fictitious", "epsilon")


# --------------------------------------------------------------------------- common machinery
class _PointsObserver(Observer):
    """Exact model prediction between frames, a correction at each frame (module docstring)."""

    features = "points"
    params_type = PointsParams
    #: dX, dY and the width from the observer's own corners (True) or, on frames that have
    #: them, from the measured ones (the runner reads this)
    deviations_from_own_points = True
    #: integrate the correction in sub-steps at slow frame rates (False for a filter whose
    #: correction is one update per measurement: kf-2p)
    substep_correction = True
    #: project the state's eta onto [ETA_MIN, ETA_MAX] after every step (True), or only the
    #: reported height (False: ii-2p, see its docstring)
    project_state = True

    def _reset(self, first: ObserverInput, dh0_m: float, measurement: np.ndarray) -> None:
        self._y = [float(measurement[0, 0]), float(measurement[0, 1]), float(measurement[1, 0]),
                   float(measurement[1, 1])]
        self._eta = 1.0 / dh0_m
        v = first.v_runway_mps
        self._v = (float(v[0]), float(v[1]), float(v[2]))
        self._t_corrected = float(first.t_s)
        self._shortest_interval = math.inf
        self._init_extra(first, measurement)

    def _init_extra(self, first: ObserverInput, measurement: np.ndarray) -> None:
        """Observer-specific state (override)."""

    def _step(self, inp: ObserverInput, dt_s: float, measurement: np.ndarray | None) -> Estimate:
        v = inp.v_runway_mps
        v_new = (float(v[0]), float(v[1]), float(v[2]))
        v_old = self._v
        d1 = 0.5 * (v_old[0] + v_new[0]) * dt_s
        d2 = 0.5 * (v_old[1] + v_new[1]) * dt_s
        d3 = 0.5 * (v_old[2] + v_new[2]) * dt_s
        self._predict(d1, d2, d3, dt_s, v_old, v_new)
        self._v = v_new
        if measurement is not None:
            interval = float(inp.t_s) - self._t_corrected
            self._shortest_interval = min(getattr(self, "_shortest_interval", math.inf), interval)
            # a gap (missing frames) is corrected as one nominal interval; the nominal interval
            # is the camera's (at 5 Hz, 0.2 s), not a fixed 0.1 s that would halve the gains
            cap = max(self.params.max_correction_interval_s, 1.5 * self._shortest_interval)
            dt_c = min(interval, cap)
            # the correction integrated in sub-steps of at most CORRECTION_SUBSTEP_S against the
            # held measurement (each sub-step re-reads the error): at a slow frame rate one explicit
            # step of dt_c overshoots (a gain times 0.2 s) where the continuous correction does not
            n = max(1, math.ceil(dt_c / CORRECTION_SUBSTEP_S - 1e-9)) if self.substep_correction else 1
            for _ in range(n):
                self._correct(measurement, dt_c / n, v_new)
            self._t_corrected = float(inp.t_s)
        if self.project_state:
            self._eta = clip_eta(self._eta)
        return Estimate(t_s=float(inp.t_s), dh_m=1.0 / clip_eta(self._eta),
                        observability=points_observability(self._y, v_new),
                        coasting=measurement is None, state=self._get_state())

    def _predict(self, d1, d2, d3, dt_s, v_old, v_new) -> None:
        """Exact flow of 4.1 over one step (module docstring)."""
        eta = self._eta
        d = 1.0 - eta * d3
        if d < 0.5:      # only with an absurd eta (dH under twice the step's descent): keep the flow finite
            d = 0.5
        y = self._y
        inv = 1.0 / d
        self._y = [(y[0] - eta * d1) * inv, (y[1] - eta * d2) * inv, (y[2] - eta * d1) * inv, (y[3] - eta * d2) * inv]
        self._eta = eta * inv

    def _correct(self, measurement: np.ndarray, dt_c: float, v) -> None:
        raise NotImplementedError

    def _get_state(self) -> np.ndarray:
        return np.array([*self._y, self._eta])

    def _set_state(self, state: np.ndarray) -> None:
        self._y = [float(a) for a in state[:4]]
        self._eta = float(state[4])

    def _dh_from_state(self, state: np.ndarray) -> float:
        return 1.0 / clip_eta(float(state[4]))

    def predicted_points_yv(self) -> np.ndarray:
        """The observer's current estimate of P' and P'' (virtual coordinates), shape (2, 2)."""
        y = self._y
        return np.array([[y[0], y[1]], [y[2], y[3]]])


def _flat(measurement: np.ndarray) -> list:
    return [float(measurement[0, 0]), float(measurement[0, 1]), float(measurement[1, 0]), float(measurement[1, 1])]


# --------------------------------------------------------------------------- observers
class OJ2P(_PointsObserver):
    """Identifier-based observer of Jankovic and Ghosh (1995) on the two-point system 4.1 (OJ_2P).

    ::

        y_hat'   = Phi(y_hat, v) eta_hat + k_y (y - y_hat)
        eta_hat' = v3 eta_hat^2 + k_eta Phi(y_hat, v)^T (y - y_hat)

    A fast identifier of the outputs whose error, correlated with the regressor Phi, adapts
    eta; with ``V = |e|^2/2 + (eta - eta_hat)^2 / (2 k_eta)`` the cross terms cancel and the
    error converges under persistent excitation (``O > 0``, thesis 3.30). The regressor is taken
    at the identifier's own outputs ``y_hat``: with the measured ``y`` the image noise enters both
    the regressor and the error and their product biases eta. The thesis gives no gains; these
    were tuned on the thesis scenarios (ideal and 1 px) for a few seconds' convergence.
    """

    name = "oj-2p"
    params_type = OJParams

    def _correct(self, measurement, dt_c, v) -> None:
        y_meas = _flat(measurement)
        phi = points_phi(self._y, v)
        p = self.params
        e = [m - h for m, h in zip(y_meas, self._y)]
        self._eta += dt_c * p.k_eta * sum(ph * ei for ph, ei in zip(phi, e))
        self._y = [h + dt_c * p.k_y * ei for h, ei in zip(self._y, e)]


class II2P(_PointsObserver):
    """Immersion and invariance on two points (thesis 4.2.1, Proposition 4.2.1, after [Gibert 15b]).

    ``eta_hat = eta_bar + beta(y, t)`` with ``beta = -lambda y_a`` (4.7: with the corrected
    output combination ``y_a`` of 4.55, ``dbeta/dy . Phi = lambda O``) and ``eta_bar`` driven by
    4.6. Then ``z = eta_hat - eta`` obeys ``z' = -lambda O z + v3 (eta_hat + eta) z``
    (4.8 re-derived: the thesis prints ``v3 z^2``), stable while ``lambda O > v3 (eta_hat + eta)``.

    Sampled form: between frames ``y_hat`` follows the model with ``eta_hat`` so ``eta_bar'`` and
    ``beta'`` make ``eta_hat' = v3 eta_hat^2`` exactly; at a frame ``y_hat`` jumps to the
    measurement and ``beta`` with it: ``eta_hat += -lambda (y_a(y) - y_a(y_hat))``. State:
    ``[y'1, y'2, y''1, y''2, eta_hat]`` (``eta_bar = eta_hat + lambda y_a(y_hat)``).

    The state's eta is not projected onto ``[ETA_MIN, ETA_MAX]`` (only the reported height is):
    a frame's image noise enters ``beta`` and leaves it at the next frame with the opposite sign,
    so eta_hat is the true value plus a noise that does not accumulate; with 5 px far out that
    noise exceeds eta itself, and projecting the negative excursions onto ``ETA_MIN`` kept the
    upward half only, a drift that took ii-2p to the 0.5 m bound (thesis-1 and -2 of
    ``visland study table-5.7``). Unprojected, the jumps cancel as 4.6-4.7 intend.
    """

    name = "ii-2p"
    params_type = IIParams
    project_state = False

    def _correct(self, measurement, dt_c, v) -> None:
        y_meas = _flat(measurement)
        self._eta -= self.params.lambda_ * (output_combination(y_meas, v) - output_combination(self._y, v))
        self._y = y_meas


class CCCS2P(_PointsObserver):
    """Change of coordinates with output combination (thesis 4.3.1.2, eq. 4.55-4.66, corrected).

    On ``x = (y_a, eta)`` with ``y_a' = Delta_y eta + chi`` and ``eta' = v3 eta^2``,
    ``tau(x) = (y_a, Delta_y eta)`` (4.60) is a diffeomorphism while ``Delta_y = -O != 0``; its
    Jacobian is ``[[1, 0], [2 v3 eta, Delta_y]]`` (4.65, ``dDelta_y/dy_a = 2 v3`` from the
    corrected 4.58). With the high-gain term ``kappa = (K1 e, K2 e)``, ``e = y_a - y_a_hat``::

        y_a_hat' = Delta_y(y_a_hat) eta_hat + chi + K1 e
        eta_hat' = v3 eta_hat^2 + (K2 e - 2 v3 eta_hat K1 e) / Delta_y(y_a_hat)      (4.66)

    ``chi`` needs the points between frames: they are predicted with the model and reset to
    each measurement; ``y_a_hat`` is carried as ``y_a(y_hat) + delta`` whose offset obeys
    ``delta' = 2 v3 eta delta`` exactly. State: ``[y'1, y'2, y''1, y''2, eta, y_a_hat]``.
    With image noise: the bias correction of ``y_a`` and the saturation of the eta correction of
    :class:`CCCSParams` (both off by default).
    """

    name = "cccs-2p"
    params_type = CCCSParams

    def _init_extra(self, first, measurement) -> None:
        self._delta = 0.0     # y_a_hat - y_a(y_hat, v)
        self._k1, self._k2 = self.params.gains

    def _predict(self, d1, d2, d3, dt_s, v_old, v_new) -> None:
        eta0 = self._eta
        super()._predict(d1, d2, d3, dt_s, v_old, v_new)
        self._delta *= math.exp(2.0 * d3 * 0.5 * (eta0 + self._eta))

    def _correct(self, measurement, dt_c, v) -> None:
        y_meas = _flat(measurement)
        ya_hat = output_combination(self._y, v) + self._delta
        e = output_combination(y_meas, v) - ya_hat
        sigma = self.params.noise_sigma_rad
        if sigma > 0.0:
            # y_a is quadratic in y: image noise of variance s_i^2 on each coordinate biases it by
            # -v3/2 sum s_i^2 (5 px, 5 km out: as large as the signal Delta_y eta); removed here
            e += 0.5 * v[2] * sum(si * si for si in virtual_noise_sigma(self._y, sigma))
        # Delta_y = -O (4.56-4.58 corrected) at the predicted points: always negative, whereas
        # 2 v3 y_a_hat - 2 (v1^2 + v2^2) can change sign while y_a_hat is still wrong
        delta_y = -max(points_observability(self._y, v), 1e-9)
        k1, k2 = self._k1, self._k2
        deta = dt_c * (k2 * e - 2.0 * v[2] * self._eta * k1 * e) / delta_y
        cap = self.params.max_eta_rate * dt_c * self._eta
        if cap > 0.0 and abs(deta) > cap:
            deta = math.copysign(cap, deta)
        self._eta += deta
        ya_new = ya_hat + dt_c * k1 * e
        self._y = y_meas
        self._delta = ya_new - output_combination(y_meas, v)

    def _get_state(self) -> np.ndarray:
        return np.array([*self._y, self._eta, output_combination(self._y, self._v) + self._delta])

    def _set_state(self, state: np.ndarray) -> None:
        super()._set_state(state)
        self._delta = float(state[5]) - output_combination(self._y, self._v)


class CCPIHG2P(_PointsObserver):
    """Change of coordinates with the Moore-Penrose pseudo-inverse, high-gain (thesis 4.3.1.3).

    ``tau(x) = (y, y')`` (4.67) immerses ``x = (y, eta)`` (dim 5) into dim 8; the observer in the
    original coordinates is ``x_hat' = f(x_hat) + [dtau/dx]^+ kappa`` (Conjecture 4.3.1, 4.73)
    with the high-gain ``kappa = Lambda^-1 K (y - y_hat)`` (4.44-4.46) and the closed-form
    pseudo-inverse of :func:`pseudo_inverse_correction` (Jacobian 4.68 at ``x_hat``).
    """

    name = "ccpi-hg-2p"
    params_type = CCPIHGParams

    def _init_extra(self, first, measurement) -> None:
        self._k1, self._k2 = self.params.gains

    def _kappa(self, e):
        return [self._k1 * ei for ei in e], [self._k2 * ei for ei in e]

    def _correct(self, measurement, dt_c, v) -> None:
        y_meas = _flat(measurement)
        e = [m - h for m, h in zip(y_meas, self._y)]
        self._h = dt_c
        kappa_y, kappa_d = self._kappa(e)
        phi = points_phi(self._y, v)
        u, s = pseudo_inverse_correction(phi, v[2] * self._eta, kappa_y, kappa_d)
        self._y = [h + dt_c * ui for h, ui in zip(self._y, u)]
        self._eta += dt_c * s


class CCPIHOSM2P(CCPIHG2P):
    """The pseudo-inverse observer with Levant's high-order sliding-mode correction (thesis 4.47-4.49).

    Same structure as :class:`CCPIHG2P`; ``kappa`` is the super-twisting differentiator's
    correction on each output, ``(a1 L^(1/2) |e|^(1/2) sign e, a2 L sign e)``: finite-time
    convergence of the ``(y, y')`` estimates, robust to bounded model errors.
    """

    name = "ccpi-hosm-2p"
    params_type = CCPIHOSMParams

    def _init_extra(self, first, measurement) -> None:
        pass

    def _kappa(self, e):
        p = self.params
        if p.implicit:
            pairs = [levant_correction_implicit(ei, p.lipschitz, p.a1, p.a2, self._h) for ei in e]
        else:
            pairs = [levant_correction(ei, p.lipschitz, p.a1, p.a2) for ei in e]
        return [a for a, _ in pairs], [b for _, b in pairs]


def _quaternion_matrix(a: float, b: float, c: float, d: float):
    """Left-multiplication matrix of the quaternion (a, b, c, d): orthogonal columns, det (a^2+b^2+c^2+d^2)^2."""
    return ((a, -b, -c, -d), (b, a, -d, c), (c, d, a, -b), (d, -c, b, a))


class CCCJ2P(_PointsObserver):
    """Jacobian completion on two points (thesis 4.4.2, after Bernard et al. 2015).

    Reduced system 4.88 with three outputs: the two corners share their along-track ratio, so
    the outputs are ``y_1 = (y'1 + y''1)/2`` (one value, averaged over both corners), ``y'2`` and
    ``y''2`` (the thesis text keeps ``y''1`` and drops ``y''2`` while calling the *second*
    coordinates equal; in the virtual frame it is the first ones that coincide, and keeping both
    lateral coordinates keeps observability when the velocity points at one corner).

    ``tau = (y, y', y_f)`` with the fictitious output ``y_f = psi eta``,
    ``psi = max(eps^2 - |Phi|^2, 0)^2`` (4.81-4.82), completed by ``gamma w`` (``w`` in R^3, 4.85)
    so that the lower-right block of ``dtau_e/d(x, w)`` is the quaternion matrix of
    ``(Phi_1, Phi_2, Phi_3, psi)``: columns orthogonal, determinant ``(|Phi|^2 + psi^2)^2 > 0``
    everywhere (4.90-4.91 print a sign pattern whose last rows repeat entries; any completion
    with orthogonal columns does what 4.91 is for). The observer 4.86 with the high-gain
    ``kappa = (K1 e, K2 e, K3 e_f)`` (4.89) then reads, with ``M`` that block and ``S`` the
    ``dy'/dy`` rows::

        y_hat'      = Phi eta_hat + K1 e
        (eta, w)'   = (v3 eta^2, 0) + M^T (kappa_d - S kappa_y) / (|Phi|^2 + psi^2)

    (terms of 4.86 of order ``w_hat`` are dropped: ``w_hat`` starts at 0 and never feeds back into
    ``x_hat``; it is reported in the state). State:
    ``[y_1, y'2, y''2, eta, w1, w2, w3]``.
    """

    name = "cccj-2p"
    params_type = CCCJParams

    def _init_extra(self, first, measurement) -> None:
        self._w = [0.0, 0.0, 0.0]
        self._k1, self._k2 = self.params.gains

    def _correct(self, measurement, dt_c, v) -> None:
        p = self.params
        y = self._y
        y_hat = (0.5 * (y[0] + y[2]), y[1], y[3])
        y_meas = (0.5 * (float(measurement[0, 0]) + float(measurement[1, 0])), float(measurement[0, 1]),
                  float(measurement[1, 1]))
        e = [m - h for m, h in zip(y_meas, y_hat)]
        v1, v2, v3 = v
        eta = self._eta
        phi = (v3 * y_hat[0] - v1, v3 * y_hat[1] - v2, v3 * y_hat[2] - v2)
        phi2 = phi[0] ** 2 + phi[1] ** 2 + phi[2] ** 2
        gap = p.epsilon ** 2 - phi2
        psi = gap * gap if gap > 0.0 else 0.0
        # dy_f/dy_i = eta dpsi/dy_i = eta * 2 max(gap, 0) * (-2 Phi_i v3)
        dpsi = [(-4.0 * gap * ph * v3 if gap > 0.0 else 0.0) for ph in phi]
        e_f = 0.0 - psi * eta          # the true system is observable: y_f = 0
        k1, k2, k3 = self._k1, self._k2, p.k_fictitious
        kappa_y = [k1 * ei for ei in e]
        kappa_d = [k2 * e[0], k2 * e[1], k2 * e[2], k3 * e_f]
        s_kappa = [v3 * eta * kappa_y[0], v3 * eta * kappa_y[1], v3 * eta * kappa_y[2],
                   eta * sum(dp * ky for dp, ky in zip(dpsi, kappa_y))]
        rhs = [kd - sk for kd, sk in zip(kappa_d, s_kappa)]
        M = _quaternion_matrix(phi[0], phi[1], phi[2], psi)
        norm2 = phi2 + psi * psi
        sol = [sum(M[r][c] * rhs[r] for r in range(4)) / norm2 for c in range(4)]     # M^T rhs / |q|^2
        self._eta = eta + dt_c * sol[0]
        self._w = [w + dt_c * s for w, s in zip(self._w, sol[1:])]
        y_new = [h + dt_c * ky for h, ky in zip(y_hat, kappa_y)]
        # back to the two-corner layout (both corners carry the shared first coordinate)
        self._y = [y_new[0], y_new[1], y_new[0], y_new[2]]

    def _get_state(self) -> np.ndarray:
        y = self._y
        return np.array([0.5 * (y[0] + y[2]), y[1], y[3], self._eta, *self._w])

    def _set_state(self, state: np.ndarray) -> None:
        self._y = [float(state[0]), float(state[1]), float(state[0]), float(state[2])]
        self._eta = float(state[3])
        self._w = [float(a) for a in state[4:7]]

    def _dh_from_state(self, state: np.ndarray) -> float:
        return 1.0 / clip_eta(float(state[3]))
