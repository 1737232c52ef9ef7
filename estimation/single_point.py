"""Seed 001: range identification for one point of a perspective system, and its academic example.

The system (seed 001 eq. 1-2): a point ``x`` (camera frame) moves as ``x' = A(t) x + B(t)``
(rotation and translation known) and is seen as ``y = (x1/x3, x2/x3)`` (focal 1).

Observer (eq. 3-13). The map ``Psi(x) = (y1, y1', y2)`` (eq. 3) is a change of coordinates
while its Jacobian is invertible (eq. 4-5); in ``zeta = Psi(x)`` the system is in observable
canonical form and the observer ``zeta_hat' = F zeta_hat + Phi(zeta_hat) + kappa`` (eq. 7) is
expressed in the original coordinates through the inverse Jacobian (eq. 9-10)::

    x_hat' = A x_hat + B + [dPsi/dx (x_hat)]^-1 kappa(y, x_hat)

with the high-gain term ``kappa = Lambda^-1 K (y - C(x_hat))`` (eq. 11-13):
``Lambda = diag(lambda1, lambda1^2, lambda2)``, ``K = [[K1, 0], [K2, 0], [0, K3]]``,
``K1 = 2 xi omega``, ``K2 = omega^2``, ``K3 = alpha`` (poles of ``(s + alpha)(s^2 + 2 xi omega s
+ omega^2)``). The Jacobian, written out (``g = x1' x3 - x1 x3'``, ``x' = A x + B``)::

    dy1/dx  = (1/x3, 0, -x1/x3^2)
    dy1'/dx = (A1j x3 + x1' d_j3 - x3' d_j1 - x1 A3j) / x3^2 - 2 g d_j3 / x3^3
    dy2/dx  = (0, 1/x3, -x2/x3^2)

Its determinant is the observability index (eq. 4). The academic example (eq. 14-16: A, B,
``x(0) = (1, 1.5, 2.5)``, ``x_hat(0) = (0.4, 0.6, 1)``, xi = 0.99, omega = 7, alpha = 1) is
:func:`academic_example`.

References
----------
V. Gibert, L. Burlion, A. Chriette, J. Boada, F. Plestan, "A new observer for range
identification in perspective vision systems", Advances in Aerospace Guidance, Navigation
and Control (seeds 001 and 003).
    Eq. 1-16.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from visland.estimation.base import ObserverParams

__all__ = ["SinglePointParams", "SinglePointEstimate", "SinglePointObserver", "psi_jacobian",
           "academic_example", "AcademicResult", "ACADEMIC_A", "ACADEMIC_B", "ACADEMIC_X0", "ACADEMIC_X0_HAT"]

#: Seed 001 eq. 14-16.
ACADEMIC_A = np.array([[-0.2, 0.4, -0.6], [0.1, -0.2, 0.3], [0.3, -0.4, 0.4]])
ACADEMIC_B = np.array([0.5, 0.25, 0.3])
ACADEMIC_X0 = np.array([1.0, 1.5, 2.5])
ACADEMIC_X0_HAT = np.array([0.4, 0.6, 1.0])


@dataclass(frozen=True)
class SinglePointParams(ObserverParams):
    """Seed 001 high-gain tuning (section 4.1): damping xi, pulsation omega, alpha, lambda1, lambda2.

    Attributes
    ----------
    damping, omega_rad_s : float
        Damping xi and pulsation omega (rad/s) of the high-gain correction.
    alpha : float
        The seed's alpha.
    lambda1, lambda2 : float
        The seed's lambda_1 and lambda_2.
    """

    damping: float = 0.99
    omega_rad_s: float = 7.0
    alpha: float = 1.0
    lambda1: float = 1.0
    lambda2: float = 1.0

    def __post_init__(self):
        self._check_positive("omega_rad_s", "alpha", "lambda1", "lambda2")
        self._check_range("damping", 0.05, 2.0)


@dataclass
class SinglePointEstimate:
    """One step of :class:`SinglePointObserver`.

    Attributes
    ----------
    t_s : float
        Time, seconds.
    x_hat : ndarray, shape (3,)
        The state estimate.
    depth : float
        The depth estimate ``x3``.
    observability : float
        The observability index ``det dPsi/dx``.
    """

    t_s: float
    x_hat: np.ndarray
    depth: float
    observability: float


def psi_jacobian(x, A, B) -> np.ndarray:
    """``dPsi/dx`` for ``Psi = (y1, y1', y2)`` at ``x`` (rows in that order), shape (3, 3).

    Parameters
    ----------
    x : array_like, shape (3,)
        The state.
    A : array_like, shape (3, 3)
        The system matrix of ``x' = A x + B``.
    B : array_like, shape (3,)
        Its constant input.

    Returns
    -------
    ndarray, shape (3, 3)
    """
    x1, x2, x3 = float(x[0]), float(x[1]), float(x[2])
    xdot = A @ x + B
    g = xdot[0] * x3 - x1 * xdot[2]
    J = np.empty((3, 3))
    J[0] = (1.0 / x3, 0.0, -x1 / x3 ** 2)
    for j in range(3):
        dg = A[0, j] * x3 - x1 * A[2, j] + (xdot[0] if j == 2 else 0.0) - (xdot[2] if j == 0 else 0.0)
        J[1, j] = dg / x3 ** 2 - (2.0 * g / x3 ** 3 if j == 2 else 0.0)
    J[2] = (0.0, 1.0 / x3, -x2 / x3 ** 2)
    return J


class SinglePointObserver:
    """The seed 001 observer (eq. 10-13) for ``x' = A x + B``, ``y = (x1/x3, x2/x3)``.

    ``reset(t_s, x_hat0)`` sets the initial guess; ``step(t_s, y, A, B)`` integrates the observer
    from the previous time to ``t_s`` (classical RK4, ``y``, ``A`` and ``B`` held over the step)
    and returns a :class:`SinglePointEstimate`. A NaN measurement coasts on the model.

    Parameters
    ----------
    params : SinglePointParams, optional
        Tuning (default :class:`SinglePointParams`).
    """

    def __init__(self, params: SinglePointParams | None = None):
        self.params = params or SinglePointParams()
        p = self.params
        self._gains = (2.0 * p.damping * p.omega_rad_s / p.lambda1, p.omega_rad_s ** 2 / p.lambda1 ** 2,
                       p.alpha / p.lambda2)
        self._t = None
        self._x = None

    def reset(self, t_s: float, x_hat0) -> None:
        x0 = np.asarray(x_hat0, dtype=float)
        if x0.shape != (3,) or not np.isfinite(x0).all():
            raise ValueError(f"x_hat0 must be 3 finite numbers, got {x_hat0!r}")
        if x0[2] <= 0:
            raise ValueError(f"x_hat0[2] (the depth guess) must be positive, got {x0[2]!r}")
        self._t = float(t_s)
        self._x = x0.copy()

    def _rhs(self, x, y, A, B):
        model = A @ x + B
        if y is None:
            return model
        k1, k2, k3 = self._gains
        e1 = y[0] - x[0] / x[2]
        e2 = y[1] - x[1] / x[2]
        kappa = np.array([k1 * e1, k2 * e1, k3 * e2])
        return model + np.linalg.solve(psi_jacobian(x, A, B), kappa)

    def step(self, t_s: float, y, A, B) -> SinglePointEstimate:
        if self._t is None:
            raise ValueError("call reset() before step()")
        dt = float(t_s) - self._t
        if not dt > 0:
            raise ValueError(f"time must increase: t = {t_s!r} after {self._t!r}")
        A = np.asarray(A, dtype=float)
        B = np.asarray(B, dtype=float)
        if A.shape != (3, 3) or B.shape != (3,) or not (np.isfinite(A).all() and np.isfinite(B).all()):
            raise ValueError("A must be a finite 3x3 matrix and B a finite 3-vector")
        if y is not None:
            y = np.asarray(y, dtype=float)
            if y.shape != (2,):
                raise ValueError(f"y must have shape (2,), got {y.shape}")
            if not np.isfinite(y).all():
                y = None       # missing measurement: coast on the model
        x = self._x
        k1 = self._rhs(x, y, A, B)
        k2 = self._rhs(x + 0.5 * dt * k1, y, A, B)
        k3 = self._rhs(x + 0.5 * dt * k2, y, A, B)
        k4 = self._rhs(x + dt * k3, y, A, B)
        x_new = x + dt / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4)
        if np.isfinite(x_new).all() and x_new[2] > 0:
            self._x = x_new
        self._t = float(t_s)
        obs = float(np.linalg.det(psi_jacobian(self._x, A, B)))
        return SinglePointEstimate(self._t, self._x.copy(), float(self._x[2]), obs)


@dataclass
class AcademicResult:
    """Trajectories of the academic example.

    Attributes
    ----------
    t_s : ndarray, shape (n,)
        Times, seconds.
    x, x_hat : ndarray, shape (n, 3)
        Truth and estimate.
    observability : ndarray, shape (n,)
        ``det dPsi/dx`` along the run.
    """

    t_s: np.ndarray
    x: np.ndarray
    x_hat: np.ndarray
    observability: np.ndarray

    def relative_depth_error_at(self, t_s: float) -> float:
        """``|x3_hat - x3| / x3`` at time ``t_s`` (nearest sample)."""
        i = int(np.argmin(np.abs(self.t_s - t_s)))
        return float(abs(self.x_hat[i, 2] - self.x[i, 2]) / abs(self.x[i, 2]))


def academic_example(duration_s: float = 5.0, dt_s: float = 1e-3, noise_fraction: float = 0.0, seed: int = 0,
                     params: SinglePointParams | None = None) -> AcademicResult:
    """Seed 001 section 4.1: the observer on eq. 14-16, truth by the exact matrix exponential.

    ``noise_fraction`` adds the seed's "1 % random noise" (Gaussian, relative to each measured
    coordinate) when non-zero.

    Parameters
    ----------
    duration_s : float, default 5
        Simulated time, seconds.
    dt_s : float, default 0.001
        Step, seconds.
    noise_fraction : float, default 0
        Relative measurement noise (0.01: the seed's 1 %).
    seed : int, default 0
        Seed of the noise generator.
    params : SinglePointParams, optional
        Tuning.

    Returns
    -------
    AcademicResult
    """
    from scipy.linalg import expm
    if not (math.isfinite(duration_s) and duration_s > 0 and math.isfinite(dt_s) and 0 < dt_s <= 0.1):
        raise ValueError("duration_s must be positive and dt_s in (0, 0.1]")
    A, B = ACADEMIC_A, ACADEMIC_B
    n = int(round(duration_s / dt_s)) + 1
    t = np.arange(n) * dt_s
    # exact discretisation of x' = A x + B over dt: augmented matrix exponential
    aug = np.zeros((4, 4))
    aug[:3, :3] = A
    aug[:3, 3] = B
    step = expm(aug * dt_s)
    x = np.empty((n, 3))
    x[0] = ACADEMIC_X0
    for k in range(1, n):
        x[k] = step[:3, :3] @ x[k - 1] + step[:3, 3]
    rng = np.random.default_rng(seed)
    observer = SinglePointObserver(params)
    observer.reset(0.0, ACADEMIC_X0_HAT)
    x_hat = np.empty((n, 3))
    x_hat[0] = ACADEMIC_X0_HAT
    obs = np.empty(n)
    obs[0] = np.linalg.det(psi_jacobian(ACADEMIC_X0_HAT, A, B))
    for k in range(1, n):
        y = x[k - 1, :2] / x[k - 1, 2]
        if noise_fraction:
            y = y * (1.0 + noise_fraction * rng.standard_normal(2))
        est = observer.step(t[k], y, A, B)
        x_hat[k] = est.x_hat
        obs[k] = est.observability
    return AcademicResult(t_s=t, x=x, x_hat=x_hat, observability=obs)
