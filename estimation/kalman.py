"""Kalman filter with pseudo-measurements on two points (thesis annex, "filtre de Kalman continu
grâce aux pseudo-mesures"; the thesis's EKF_2P, SPEC ``kf-2p``), built on filterpy.

In the virtual frame (runway axes at the camera, thesis 3.19-3.20) the threshold corners
P' = (X, Y', Z) and P'' = (X, Y'', Z) share X (same distance to the threshold) and Z = dH, and
move as a pure integrator of the known velocity::

    x = [X, Y', Y'', Z],     x' = -B v,   B v = (v1, v2, v2, v3)              (3.20, annex 5.4)

The image gives ``y = (X/Z, Y/Z)`` per corner, a nonlinear output; the annex turns it into
linear *pseudo-measurements* that are zero by construction (annex 5.5)::

    y'1 Z - X = 0,   y'2 Z - Y' = 0,   y''1 Z - X = 0,   y''2 Z - Y'' = 0

i.e. ``z = 0 = H(y) x`` with ``H`` built from the measured ``y``: a linear time-varying system, so
the ordinary Kalman filter applies (discretised here: ``F = I``, ``u = integral of v dt``).

One change from the annex: ``H`` is evaluated at the *predicted* ratios ``y_hat = x_hat/Z_hat``
and the pseudo-measurement becomes ``z = (y_hat - y) Z_hat``, which leaves the innovation
``z - H x_hat = X_hat - y Z_hat`` of 5.5 unchanged. With the measured ``y`` inside ``H`` the
measurement noise enters both ``H`` and the innovation; their product always has the same
sign and drags the whole solution towards the trivial ``x = 0`` (it satisfies every
pseudo-measurement): at 1 px of noise dH collapsed to 5 % of the truth within half a second.
With ``y_hat`` the update is the extended Kalman filter of the ratio outputs multiplied by Z,
unbiased to first order; with ideal measurements both forms coincide.

A measurement error ``delta y`` enters as ``Z delta y``, so ``R = diag(Z_hat^2 sigma_y^2)`` with
``sigma_y`` the image noise carried to virtual coordinates (an angle ``sigma`` moves
``X/Z = cot(elevation)`` by ``(1 + y1^2) sigma`` and ``Y/Z`` by about ``sqrt(1 + y1^2) sigma``)
plus the heading error's rotation of the rays about the vertical.
The initial covariance follows the height guess: ``X, Y', Y''`` are initialised as ``y Z0``, so
their errors are ``y`` times Z's (``P0 = J J^T sigma_Z^2 + diag``, ``J = (y1, y'2, y''2, 1)``).

Robust update (issue 12, not in the annex). With 5 px of corner noise the first seconds' runway
heading is off by 1-3 deg (a biased, heavy-tailed vanishing point far out), far beyond
``heading_sigma_rad``: the innovations were tens of standard deviations, P collapsed to a
decimetre while dH was 100-200 m off, and kf-2p ended 60 m off at 100 ft (thesis-4, 5 px).
The update is therefore Huber-weighted on the normalised innovation ``d = sqrt(y^T S^-1 y)``,
``S = H P H^T + R`` (Huber, "Robust estimation of a location parameter", Ann. Math. Statist.
35(1), 1964; its Kalman form as in Karlgaard and Schaub, "Huber-based divided difference
filtering", J. Guidance Control Dyn. 30(3), 2007): up to ``d = c`` the ordinary update; beyond,
``R`` is scaled by ``d / c`` so the innovation's influence stays bounded and P shrinks only as
much as the measurement deserves. ``c = 3.64`` is the 99 % point of chi-square with 4 degrees of
freedom: on measurements that fit the model (ideal or as noisy as ``image_sigma_rad`` says) the
filter is the annex's.

State (``Estimate.state``): ``[X, Y', Y'', Z]`` in metres; ``dH = Z``.

References
----------
V. Gibert, "Analyse d'observabilite et synthese d'observateurs robustes pour l'atterrissage
base vision d'avions de ligne sur des pistes inconnues", PhD thesis, 2016 (seed 002).
    Annex 5.4-5.6: the Kalman filter with pseudo-measurements (EKF_2P).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from visland.estimation.base import ETA_MAX, ETA_MIN, Estimate, ObserverInput
from visland.estimation.points import PointsParams, _PointsObserver

__all__ = ["KFParams", "KF2P"]


@dataclass(frozen=True)
class KFParams(PointsParams):
    """Tuning of the pseudo-measurement Kalman filter.

    Parameters
    ----------
    max_correction_interval_s : longest time a single correction integrates, seconds.
    initial_height_sigma_fraction : standard deviation of the initial dH error, as a fraction of
        the guess (the seeds start 20 % off).
    image_sigma_rad : image measurement noise as an angle (1 px of the SPEC camera = 1/2472 rad).
    heading_sigma_rad : uncertainty of the heading deviation used to build the virtual frame. The
        heading comes from d_F (its running mean, :mod:`visland.estimation.inputs`): its error is a
        slowly varying bias, not white noise, so it is inflated (1 deg) to keep the filter from
        trusting the lateral rows too much early in the approach.
    velocity_sigma_mps : process noise, as a random velocity error (m/s) integrated over each step.
    huber_threshold : threshold ``c`` of the Huber-weighted update on the normalised innovation
        ``d = sqrt(y^T S^-1 y)`` (module docstring, "Robust update"); 0 turns it off (the annex's
        filter as printed). Default ``sqrt(chi2_4(0.99)) = 3.64``.
    """

    initial_height_sigma_fraction: float = 0.25
    image_sigma_rad: float = 1.0 / 2472.0
    heading_sigma_rad: float = 0.02
    velocity_sigma_mps: float = 0.02
    huber_threshold: float = 3.64

    def __post_init__(self):
        super().__post_init__()
        self._check_positive("initial_height_sigma_fraction", "image_sigma_rad", "heading_sigma_rad",
                             "velocity_sigma_mps")
        self._check_range("huber_threshold", 0.0, 1e6)


class KF2P(_PointsObserver):
    """Kalman filter with pseudo-measurements on P' and P'' (thesis annex 5.4-5.6); filterpy's
    KalmanFilter holds the state and covariance, its predict and update are written out here.
    """

    substep_correction = False          # one Kalman update per measurement
    name = "kf-2p"
    # the filter's corners follow its model more than the measurements (process noise small
    # against the pseudo-measurement noise): on detected corners they lagged by metres of dY
    deviations_from_own_points = False
    params_type = KFParams

    def _reset(self, first: ObserverInput, dh0_m: float, measurement: np.ndarray) -> None:
        from filterpy.kalman import KalmanFilter      # heavy import kept out of the CLI start-up
        p = self.params
        y = measurement
        y1 = 0.5 * (y[0, 0] + y[1, 0])
        kf = KalmanFilter(dim_x=4, dim_z=4, dim_u=3)
        kf.x = np.array([y1 * dh0_m, y[0, 1] * dh0_m, y[1, 1] * dh0_m, dh0_m])
        J = np.array([y1, y[0, 1], y[1, 1], 1.0])
        sigma_z = p.initial_height_sigma_fraction * dh0_m
        kf.P = np.outer(J, J) * sigma_z ** 2 + np.eye(4) * 1.0
        self._kf = kf
        self._H = np.zeros((4, 4))
        self._H[0, 0] = self._H[2, 0] = -1.0
        self._H[1, 1] = self._H[3, 2] = -1.0
        self._R = np.zeros((4, 4))
        self._z = np.zeros(4)
        self._eye = np.eye(4)
        v = first.v_runway_mps
        self._v = (float(v[0]), float(v[1]), float(v[2]))
        self._t_corrected = float(first.t_s)
        self._y = [float(y[0, 0]), float(y[0, 1]), float(y[1, 0]), float(y[1, 1])]
        self._eta = 1.0 / dh0_m

    def _predict(self, d1, d2, d3, dt_s, v_old, v_new) -> None:
        # the prediction x = F x + B u, P = F P F' + Q with F = I, u = (d1, d2, d3) the camera's
        # displacement in the runway frame and B = -[[1,0,0], [0,1,0], [0,1,0], [0,0,1]] (both
        # corners share the threshold's x and z), Q = (velocity_sigma_mps dt)^2 I, written out
        # here rather than through filterpy's predict (four 4x4 products at every 50 Hz step);
        # the update (_correct) is filterpy's written out likewise, with the Huber weight
        kf = self._kf
        x = kf.x
        x[0] -= d1
        x[1] -= d2
        x[2] -= d2
        x[3] -= d3
        q = (self.params.velocity_sigma_mps * dt_s) ** 2
        P = kf.P
        for i in range(4):
            P[i, i] += q
        self._sync_outputs()

    def _correct(self, measurement: np.ndarray, dt_c: float, v) -> None:
        kf = self._kf
        x = kf.x
        z_hat = max(x[3], 1.0 / ETA_MAX)
        # H at the predicted ratios y_hat = x_hat / Z_hat (see the module docstring), and the
        # pseudo-measurement z = (y_hat - y) Z_hat, so that z - H x_hat = X_hat - y Z_hat as in 5.5
        y_hat = (x[0] / z_hat, x[1] / z_hat, x[0] / z_hat, x[2] / z_hat)
        H = self._H
        z = self._z
        y_meas = (measurement[0, 0], measurement[0, 1], measurement[1, 0], measurement[1, 1])
        for i in range(4):
            H[i, 3] = y_hat[i]
            z[i] = (y_hat[i] - y_meas[i]) * z_hat
        p = self.params
        y1_sq = 0.5 * (measurement[0, 0] ** 2 + measurement[1, 0] ** 2)
        y2_sq = 0.5 * (measurement[0, 1] ** 2 + measurement[1, 1] ** 2)
        # image noise through the virtual-frame sensitivity, plus the heading error's rotation of the
        # ray about the vertical (delta y1 = y2 dpsi, delta y2 = -y1 dpsi)
        var1 = (p.image_sigma_rad * (1.0 + y1_sq)) ** 2 + y2_sq * p.heading_sigma_rad ** 2
        var2 = p.image_sigma_rad ** 2 * (1.0 + y1_sq) + y1_sq * p.heading_sigma_rad ** 2
        R = self._R
        R[0, 0] = R[2, 2] = z_hat * z_hat * var1
        R[1, 1] = R[3, 3] = z_hat * z_hat * var2
        # the update of filterpy's KalmanFilter.update written out (it would recompute S, and its
        # allocations cost a fifth of the step): innovation y = z - H x, S = H P H' + R,
        # K = P H' S^-1, x += K y, Joseph-form P = (I - K H) P (I - K H)' + K R K'
        P = kf.P
        innovation = z - H @ x
        PHt = P @ H.T
        S = H @ PHt + R
        S_inv = np.linalg.inv(S)
        c = p.huber_threshold
        if c > 0.0:
            # Huber-weighted update (module docstring, "Robust update"): an innovation beyond c
            # standard deviations is given the weight c / d, i.e. R scaled by d / c
            d = math.sqrt(max(float(innovation @ S_inv @ innovation), 0.0))
            self.last_normalised_innovation = d
            if d > c:
                R = R * (d / c)
                S = H @ PHt + R
                S_inv = np.linalg.inv(S)
        K = PHt @ S_inv
        kf.x = x + K @ innovation
        I_KH = self._eye - K @ H
        kf.P = I_KH @ P @ I_KH.T + K @ R @ K.T
        kf.y = innovation
        kf.S = S
        self._sync_outputs()

    def _sync_outputs(self) -> None:
        x = self._kf.x
        z = float(x[3])
        if not 1.0 / ETA_MAX <= z <= 1.0 / ETA_MIN:
            # keep dH in the physical domain (the projection of the other observers) without touching P
            z = min(max(z, 1.0 / ETA_MAX), 1.0 / ETA_MIN)
            x[3] = z
        self._y = [x[0] / z, x[1] / z, x[0] / z, x[2] / z]
        self._eta = 1.0 / z

    def _step(self, inp: ObserverInput, dt_s: float, measurement: np.ndarray | None) -> Estimate:
        estimate = super()._step(inp, dt_s, measurement)
        estimate.dh_m = float(self._kf.x[3])
        return estimate

    def _get_state(self) -> np.ndarray:
        return self._kf.x.copy()

    def _set_state(self, state: np.ndarray) -> None:
        self._kf.x = np.array(state, dtype=float)
        self._sync_outputs()

    def _dh_from_state(self, state: np.ndarray) -> float:
        z = float(state[3])
        return z if math.isfinite(z) and z > 0 else 1.0 / ETA_MAX

    @property
    def covariance(self) -> np.ndarray:
        """The filter's error covariance P (4x4, m^2)."""
        return self._kf.P.copy()

