"""``dickmanns-4d``: the 4D approach of Dickmanns and Schell (seed 004) as one extended Kalman filter.

Dickmanns and Schell estimate the aircraft's full state relative to the runway with an EKF on a
dynamic model of the aircraft, measuring runway borders and the horizon in small windows placed
by the prediction ("when it is known what to look for"), with wind in the model and a second
filter for the runway's width. This module is that filter for visland's sensors.

================================  ===================================================  =======================
seed 004                          here                                                 where
================================  ===================================================  =======================
state x of eq. (1): (u, v, w),    ``[x/H, y/H, 1/H, vx, vy, vz, ax, ay, az, wx, wy,    :data:`STATE_NAMES`
(p, q, r), (Phi, Theta, Psi),     W/H]``: position of the camera (= centre of
(x, y, H)                         gravity, thesis hypothesis 11) relative to the
                                  threshold centre, ground velocity (runway axes,
                                  z down), attitude correction, horizontal wind,
                                  runway width W
dynamical model eq. (1)-(3)       point-mass kinematics driven by the inertial rates:  :func:`state_derivative`
                                  ``p' = v``, the air velocity turning with the body
                                  (``v' = Omega x (v - w)``), wind and W constant
perspective mapping eq. (4),      the same mapping written for runway *lines* (edges,  :func:`line_normals_runway`,
(4a)-(4o)                         threshold) and the level plane (horizon):            :func:`predict_vision`
                                  interpretation-plane normal ``m = (P - c) x d``
                                  turned into the camera
"eight windows on the runway      the two edges and the threshold line in the SPEC      :func:`predict_vision`
boundaries and two on the         chart (rho, theta); the horizon of the inertial
horizon for the roll angle"       roll and pitch
(sec. 3, Fig. 3)
"aerodynamic speed" (sec. 4)      true airspeed ``tas_mps`` and zero sideslip          :func:`predict_air_data`
"another Kalman filter for        W as a state of this filter                          ``omega = W/H``
runway width" (sec. 7.1)
EKF "based upon [8]" (sec. 4)     continuous-discrete EKF: Heun prediction of the      :class:`Dickmanns4D`
                                  mean at the 50 Hz inertial rate,
                                  ``P <- F_d P F_d^T + Q dt``, one joint update
================================  ===================================================  =======================

The position is held as ``(x/H, y/H, 1/H)`` and the width as ``W/H``: the image alone fixes the
ratios (a runway line's interpretation plane does not change when the whole scene is scaled) and
only the motion, with the measured velocity, fixes the scale ``1/H``. This inverse-depth form
(the thesis's ``eta = 1/dH``, thesis 3.24) keeps the filter linear enough while the scale is still
20 % off: written in (x, y, H) directly, the same filter collapsed the scene towards H = 0 within
ten frames of 1 px noise (the ratio measurements' Jacobian is nearly blind to the scale, so the
linearised update moved it by tens of per cent on noise). ``x, y, H, W`` are reported.

Where this departs from the seed, and why
-----------------------------------------
1. **No pan-tilt platform.** The seed's camera sits on a two-axis platform fixated on the runway
   (angles psi, theta of eq. 4d-4o). visland's camera is fixed to the body at its calibrated
   mounting (SPEC ``mount_rpy_deg``) and at the centre of gravity (``l = 0`` in 4d-4o): the seed's
   coefficients reduce to the rotation ``R_camera_from_runway``, and there is no platform lag (the
   seed's "rather large error briefly during flare onset" came from that lag).
2. **No aerodynamic model, no control inputs.** The seed propagates the Do 128's 12-state
   multi-point model driven by elevator, thrust, aileron and rudder (eq. 1-3). visland estimates
   the approach of an aircraft it does not know: the model is point-mass kinematics driven by the
   inertial rates. With the angles of attack and sideslip constant, the air velocity turns with
   the body, ``v_a' = Omega x v_a`` (``Omega`` the body rates in runway axes); the ground velocity
   is ``v = v_a + w``. Changes of the angle of attack and of the wind are process noise (a wind
   change moves the ground velocity at once, so the two share it).
3. **Inertial ground velocity.** As the thesis's observers (thesis hypothesis 2), the filter
   measures the inertial unit's ground velocity: it gives the scene its scale (the image alone
   gives only x/H, y/H and W/H) and makes the comparison with the thesis fair. The seed had gyros
   and an air-speed meter; its scale came from the aircraft model and its control inputs.
4. **Attitude as a correction.** The inertial roll, pitch and heading and the runway heading from
   d_F (:mod:`visland.estimation.inputs`) give ``R_runway_from_camera``; the state holds a small
   correction ``A = Rz(az) Ry(ay) Rx(ax)`` (runway axes), the camera's attitude being
   ``A R_runway_from_camera``. ``az`` is the error of the runway heading and turns the inertial
   velocity into runway axes as well; ``ax, ay`` tilt the camera only, and the horizon of the
   inertial roll and pitch ties them (the seed's two horizon windows measured the roll).
5. **Lines instead of gradient windows.** The seed correlates ternary masks with the image in ten
   windows (sec. 3, Fig. 3); visland's detector (or the labels) gives whole lines in the SPEC
   chart. Each line's noise is that of a line through two image points with ``image_sigma_rad``
   of noise across it: the threshold corners for the threshold; the threshold corner and a point
   ``noise_edge_length_m`` further along for an edge. Far away, where the runway is a few pixels
   wide, the lines' angles are weak and weighed so. ``noise_edge_length_m`` enters only that
   weight, never the geometry: the runway's size is unknown to the estimators (SPEC).
6. **Wind.** Horizontal only (``wx, wy``, runway axes), observable with the true airspeed
   (telemetry column ``tas_mps``) and the zero sideslip of coordinated flight: ``|v - w| = tas``
   and the air velocity has no component along the body y axis. A vertical wind cannot be told
   from a change in the angle of attack without an incidence probe: it stays in the ground
   velocity. Without airspeed the wind is not estimated (the observer says so once,
   :attr:`Dickmanns4D.notes`) and its states stay at zero.

Conventions (SPEC, :mod:`visland.frames`, :mod:`visland.camera`): runway frame R (x along the
centreline from the threshold centre, y right, z down), ``H = -z`` the height; the left edge is the
line ``y = -W/2`` (as seen by a pilot landing), the threshold ``x = 0``. Lines
``x cos(theta) + y sin(theta) = rho`` in normalised image coordinates, theta in [-pi/2, pi/2); a
measured line is written in the representative ``(rho, theta)`` or ``(-rho, theta +- pi)`` nearest
the prediction.

References
----------
E. D. Dickmanns, F.-R. Schell, "Autonomous landing of airplanes by dynamic machine vision"
(seed 004).
    Eq. (1)-(4o), sec. 3-4 (model, measurements, EKF) and 7 (accuracy).
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import ClassVar

import numpy as np
from scipy.linalg.lapack import dposv as _dposv

from visland.estimation.base import Estimate, Observer, ObserverInput, ObserverParams, clip_eta
from visland.estimation.deviations import DEFAULT_AIM_DISTANCE_M, Deviations, deviations_from_lines

__all__ = ["Dickmanns4D", "Dickmanns4DParams", "STATE_NAMES", "rotation_correction", "line_normals_runway",
           "line_from_normal", "predict_vision", "predict_air_data", "predict_ins_velocity", "state_derivative",
           "state_jacobian", "segment_line_covariance", "NO_AIRSPEED_NOTE"]

#: Names of the state components (SI units: 1/m, m/s, rad).
STATE_NAMES = ("x_over_h", "y_over_h", "eta_per_m", "vx_mps", "vy_mps", "vz_mps", "ax_rad", "ay_rad", "az_rad",
               "wind_x_mps", "wind_y_mps", "width_over_h")
_XI, _ZETA, _ETA, _VX, _VY, _VZ, _AX, _AY, _AZ, _WX, _WY, _OMEGA = range(12)
N_STATES = 12

NO_AIRSPEED_NOTE = ("no airspeed (telemetry column tas_mps): the wind cannot be estimated; "
                    "dickmanns-4d runs without wind states")

_I12 = np.eye(N_STATES)


# --------------------------------------------------------------------------- parameters
@dataclass(frozen=True)
class Dickmanns4DParams(ObserverParams):
    """Noise model and tuning of :class:`Dickmanns4D` (the Q, R and P(0) of the EKF).

    Attributes
    ----------
    image_sigma_rad : float
        Noise of an image point across a measured line, radians (normalised units; 1 px of the
        SPEC camera is 1/2472). Sets each line's R through the two-point model (module docstring, 5).
    noise_edge_length_m : float
        Length of runway past the threshold over which an edge is taken to be measured, for its
        noise only: the shortest runway of visland's scenes (1800 m), so an edge is never trusted
        more than a short runway would allow.
    threshold_sigma_factor : float
        Multiplies ``image_sigma_rad`` for the threshold line only. 1 models the two near corners
        as independent points (visland's simulated measurements); a detector that finds both
        corners on one fitted threshold line errs on both alike (on the 512 px renders of
        ``dickmanns-wind``: the same 0.3 px across the line on both corners, lag-1
        autocorrelation 0.5 at 5 Hz), so the line is worth less than two independent points.
    horizon_sigma_rad : float
        Accuracy of the horizon from the inertial roll and pitch, radians.
    velocity_sigma_mps : float
        Noise of each inertial ground-velocity component, m/s.
    airspeed_sigma_mps : float
        Noise of the true airspeed, m/s (air data: about 1 kt).
    sideslip_sigma_rad : float
        How far from zero the sideslip is taken to stay (coordinated flight), radians.
    q_velocity : float
        Process noise density of the ground velocity, m/s^2 per sqrt(Hz): changes of the angle of
        attack and other departures from the point-mass model.
    q_wind : float
        Process noise density of the horizontal wind, m/s per sqrt(s) (gusts); the same noise
        moves the ground velocity.
    q_attitude : float
        Process noise density of the attitude correction, rad per sqrt(s).
    q_position : float
        Process noise density of the position, m per sqrt(s) (a numerical floor).
    p0_height_fraction : float
        Initial standard deviation of ``1/H`` relative to the guess's (the seeds start 20 % off).
    p0_ratio_fraction : float
        Initial standard deviation of ``x/H, y/H, W/H`` relative to their first measurement.
    p0_attitude_rad : float
        Initial standard deviation of each attitude correction.
    p0_wind_mps : float
        Initial standard deviation of each wind component.
    inertial_update_interval_s : float
        Longest time between two updates with the inertial velocity (and air data) when no camera
        frame comes (every camera frame updates with everything).
    estimate_wind : bool
        Carry the wind states when the telemetry has airspeed (False: never).
    """

    image_sigma_rad: float = 1.0 / 2472.0
    noise_edge_length_m: float = 1800.0
    threshold_sigma_factor: float = 1.0
    horizon_sigma_rad: float = math.radians(0.2)
    velocity_sigma_mps: float = 0.05
    airspeed_sigma_mps: float = 0.5
    sideslip_sigma_rad: float = math.radians(1.0)
    q_velocity: float = 0.3
    q_wind: float = 0.3
    q_attitude: float = math.radians(0.02)
    q_position: float = 0.01
    p0_height_fraction: float = 0.25
    p0_ratio_fraction: float = 0.1
    p0_attitude_rad: float = math.radians(0.5)
    p0_wind_mps: float = 5.0
    inertial_update_interval_s: float = 0.1
    estimate_wind: bool = True

    def __post_init__(self):
        self._check_range("image_sigma_rad", 1e-7, 0.1)
        self._check_range("noise_edge_length_m", 10.0, 1e5)
        self._check_range("threshold_sigma_factor", 1e-3, 100.0)
        self._check_range("horizon_sigma_rad", 1e-6, 0.5)
        self._check_range("velocity_sigma_mps", 1e-4, 50.0)
        self._check_range("airspeed_sigma_mps", 1e-3, 50.0)
        self._check_range("sideslip_sigma_rad", 1e-4, 0.5)
        self._check_range("q_velocity", 0.0, 100.0)
        self._check_range("q_wind", 0.0, 100.0)
        self._check_range("q_attitude", 0.0, 1.0)
        self._check_range("q_position", 0.0, 100.0)
        self._check_range("p0_height_fraction", 1e-4, 10.0)
        self._check_range("p0_ratio_fraction", 1e-4, 10.0)
        self._check_range("p0_attitude_rad", 1e-6, 0.5)
        self._check_range("p0_wind_mps", 1e-3, 50.0)
        self._check_range("inertial_update_interval_s", 0.0, 10.0)
        if not isinstance(self.estimate_wind, bool):
            raise ValueError(f"Dickmanns4DParams.estimate_wind must be true or false, got {self.estimate_wind!r}")


# --------------------------------------------------------------------------- geometry
def rotation_correction(ax: float, ay: float, az: float) -> np.ndarray:
    """``A = Rz(az) Ry(ay) Rx(ax)`` (3, 3): the attitude correction in runway axes.

    Its derivatives (used by :func:`predict_vision`) follow from ``Rz' = [e_z]x Rz`` and
    ``Rx' = Rx [e_x]x``: ``dA/daz = [e_z]x A``, ``dA/dax = A [e_x]x``,
    ``dA/day = A [Rx^T e_y]x``.

    Parameters
    ----------
    ax, ay, az : float
        Correction angles (rad) about the runway x, y and z axes (state entries ``ax_rad``,
        ``ay_rad``, ``az_rad`` of :data:`STATE_NAMES`).

    Returns
    -------
    numpy.ndarray, shape (3, 3)
        ``A``, the rotation applied on the runway side of ``R_runway_from_camera``.

    References
    ----------
    E. D. Dickmanns, F.-R. Schell, "Autonomous landing of airplanes by dynamic machine vision"
    (seed 004), the attitude angles (Phi, Theta, Psi) of the state of eq. (1), here a small correction.
    """
    return np.array(_rotation_rows(ax, ay, az))


def _rotation_rows(ax: float, ay: float, az: float) -> tuple:
    """The rows of :func:`rotation_correction` as tuples of floats (the filter's inner loop)."""
    cx, sx = math.cos(ax), math.sin(ax)
    cy, sy = math.cos(ay), math.sin(ay)
    cz, sz = math.cos(az), math.sin(az)
    return ((cz * cy, cz * sy * sx - sz * cx, cz * sy * cx + sz * sx),
            (sz * cy, sz * sy * sx + cz * cx, sz * sy * cx - cz * sx),
            (-sy, cy * sx, cy * cx))


def line_normals_runway(xi: float, zeta: float, omega: float) -> np.ndarray:
    """Interpretation-plane normals (runway axes, up to scale) of the left edge, right edge, threshold
    and the level plane (horizon), rows of a (4, 3) array.

    A runway line through ``P`` with direction ``d`` seen from the camera at ``c = (x, y, -H)`` spans
    the plane of normal ``(P - c) x d`` (seed eq. 4 written for a line: all its points map onto the
    image line ``m_C . (x, y, 1) = 0``, ``m_C = R_camera_from_runway m``). Divided by H, with
    ``xi = x/H``, ``zeta = y/H``, ``omega = W/H``::

        left edge  P = (0, -W/2, 0), d = e_x:   m = (0, 1, zeta + omega/2)
        right edge P = (0, +W/2, 0), d = e_x:   m = (0, 1, zeta - omega/2)
        threshold  P = (0, 0, 0),    d = e_y:   m = (-1, 0, -xi)
        horizon    the level plane through c:   m = e_z  (runway down axis, thesis 3.33)

    The derivatives are along e_z: ``dm/dzeta = e_z`` (edges), ``dm/domega = +-e_z/2``,
    ``dm/dxi = -e_z`` (threshold).

    Parameters
    ----------
    xi, zeta : float
        ``x/H`` and ``y/H``: the camera's position in the runway frame over its height H (no unit).
    omega : float
        ``W/H``: the runway width over the height (no unit).

    Returns
    -------
    numpy.ndarray, shape (4, 3)
        One normal a row, runway axes: left edge, right edge, threshold, horizon.

    References
    ----------
    E. D. Dickmanns, F.-R. Schell, "Autonomous landing of airplanes by dynamic machine vision"
    (seed 004), eq. (4), (4a)-(4o): the perspective mapping, written here for lines.
    """
    return np.array([[0.0, 1.0, zeta + 0.5 * omega],
                     [0.0, 1.0, zeta - 0.5 * omega],
                     [-1.0, 0.0, -xi],
                     [0.0, 0.0, 1.0]])


#: d m_z / d(xi, zeta, omega) per row of :func:`line_normals_runway` (m's other entries are constant).
_DMZ = ((0.0, 1.0, 0.5),
        (0.0, 1.0, -0.5),
        (-1.0, 0.0, 0.0),
        (0.0, 0.0, 0.0))


def line_from_normal(m) -> tuple:
    """``(theta, rho)`` of the image line ``m . (x, y, 1) = 0`` and its Jacobian d(theta, rho)/dm (2, 3).

    ``theta = atan2(m1, m0)``, ``rho = -m2 / hypot(m0, m1)``; no chart wrap: the sign of ``m`` picks
    the representative, so a prediction follows its line continuously.

    Parameters
    ----------
    m : array_like, shape (3,)
        Normal of the image line in normalised image coordinates (camera frame C, SPEC chart
        ``x cos(theta) + y sin(theta) = rho``); ``(m0, m1)`` must not both be zero.

    Returns
    -------
    (theta, rho) : tuple of float
        The line's angle (rad, not wrapped) and distance (normalised units, thesis f = 1).
    J : numpy.ndarray, shape (2, 3)
        ``d(theta, rho) / dm``.

    References
    ----------
    Thesis (seed 002) eq. 3.34, the (rho, theta) chart of a line.
    """
    m0, m1, m2 = float(m[0]), float(m[1]), float(m[2])
    h2 = m0 * m0 + m1 * m1
    h = math.sqrt(h2)
    h3 = h2 * h
    J = np.array([[-m1 / h2, m0 / h2, 0.0],
                  [m2 * m0 / h3, m2 * m1 / h3, -1.0 / h]])
    return (math.atan2(m1, m0), -m2 / h), J


def predict_vision(state, R_runway_from_camera, with_threshold: bool) -> tuple:
    """Predicted image lines and their Jacobian with respect to the state.

    Returns ``(z_hat, H, normals_camera)``: ``z_hat`` lists ``(theta, rho)`` of the left edge, the
    right edge, the threshold (when ``with_threshold``) and the horizon; ``H`` is d z_hat / d state,
    shape (len(z_hat), 12); ``normals_camera`` (k, 3) the camera-axes normals of the same lines,
    which orient the measured lines.

    The camera's attitude is ``A R_runway_from_camera`` (state correction ``A``,
    :func:`rotation_correction`), so a runway-axes normal ``m`` appears as ``m_C = R_in^T A^T m``
    (``R_in = R_runway_from_camera``). With ``m_A = A^T m``: ``dm_C/dax = -R_in^T (e_x x m_A)``,
    ``dm_C/day = -R_in^T (u x m_A)`` with ``u = (0, cos ax, -sin ax)``, and
    ``dm_C/daz = -R_in^T A^T (e_z x m)``; ``dm_C/dq = (R_in^T A^T e_z) dm_z/dq`` for the ratios q.

    Parameters
    ----------
    state : array_like, shape (12,)
        The filter's mean in :data:`STATE_NAMES` order (SI units: 1/m, m/s, rad).
    R_runway_from_camera : array_like, shape (3, 3)
        Camera attitude from the inertial unit and the d_F runway heading: turns camera-frame (C)
        vectors into runway axes (R).
    with_threshold : bool
        Whether the threshold line is measured this frame (it adds a third line).

    Returns
    -------
    z_hat : numpy.ndarray, shape (2k,)
        ``(theta, rho)`` of each of the k predicted lines (rad, normalised units), flattened.
    H : numpy.ndarray, shape (2k, 12)
        ``d z_hat / d state``.
    normals_camera : list of tuple, length k
        The lines' normals in camera axes (3 floats each).

    References
    ----------
    E. D. Dickmanns, F.-R. Schell, "Autonomous landing of airplanes by dynamic machine vision"
    (seed 004), eq. (4), (4a)-(4o) and sec. 3 (windows on the runway borders and the horizon).
    """
    rows = (0, 1, 2, 3) if with_threshold else (0, 1, 3)
    H = np.zeros((2 * len(rows), N_STATES))
    s = state.tolist() if isinstance(state, np.ndarray) else [float(v) for v in state]
    z, M_C, _ = _vision_rows(s, np.asarray(R_runway_from_camera, dtype=float).tolist(), rows, H, 0)
    return np.array(z), H, M_C


def _vision_rows(s, R, rows, H, row0: int) -> tuple:
    """Body of :func:`predict_vision` on Python floats, writing its Jacobian into ``H[row0:]``.

    ``s`` the state as a list of floats, ``R`` the rows of ``R_runway_from_camera``, ``rows`` the
    lines wanted (indices into :func:`line_normals_runway`). Returns ``(z, M_C, M)``: the predicted
    ``(theta, rho)`` flattened, the camera-axes normals, and the columns of ``M = R_in^T A^T``
    (the runway axes as the corrected camera sees them; reused by the lines' noise). A handful of
    3-vectors per frame: on floats, where numpy's per-call cost would dominate the 50 Hz budget.

    Every normal of :func:`line_normals_runway` is a fixed combination of the runway axes, so
    ``m_C = M m`` is built from the columns ``M e_x, M e_y, M e_z``: the edges ``M e_y + m_z M e_z``,
    the threshold ``-M e_x - xi M e_z``, the horizon ``M e_z``; and ``dm_C/daz = M (e_z x m)``
    with the sign of the docstring above is ``M e_x`` for an edge, ``M e_y`` for the threshold and 0
    for the horizon.
    """
    xi, zeta, omega, ax = s[_XI], s[_ZETA], s[_OMEGA], s[_AX]
    (a00, a01, a02), (a10, a11, a12), (a20, a21, a22) = _rotation_rows(ax, s[_AY], s[_AZ])
    (r00, r01, r02), (r10, r11, r12), (r20, r21, r22) = R
    ca, sa = math.cos(ax), math.sin(ax)
    # columns of M = R_in^T A^T (A^T e_x is A's first row)
    mx0, mx1, mx2 = r00 * a00 + r10 * a01 + r20 * a02, r01 * a00 + r11 * a01 + r21 * a02, r02 * a00 + r12 * a01 + r22 * a02
    my0, my1, my2 = r00 * a10 + r10 * a11 + r20 * a12, r01 * a10 + r11 * a11 + r21 * a12, r02 * a10 + r12 * a11 + r22 * a12
    mz0, mz1, mz2 = r00 * a20 + r10 * a21 + r20 * a22, r01 * a20 + r11 * a21 + r21 * a22, r02 * a20 + r12 * a21 + r22 * a22
    z = []
    M_C = []
    i = row0
    for row in rows:
        if row < 2:                                                       # edges: m = (0, 1, m_z)
            mz = zeta + 0.5 * omega if row == 0 else zeta - 0.5 * omega
            ma0, ma1, ma2 = a10 + a20 * mz, a11 + a21 * mz, a12 + a22 * mz  # m_A = A^T m
            c0, c1, c2 = my0 + mz * mz0, my1 + mz * mz1, my2 + mz * mz2
            dz0, dz1, dz2 = mx0, mx1, mx2
        elif row == 2:                                                    # threshold: m = (-1, 0, -xi)
            ma0, ma1, ma2 = -a00 - a20 * xi, -a01 - a21 * xi, -a02 - a22 * xi
            c0, c1, c2 = -mx0 - xi * mz0, -mx1 - xi * mz1, -mx2 - xi * mz2
            dz0, dz1, dz2 = my0, my1, my2
        else:                                                             # horizon: m = e_z
            ma0, ma1, ma2 = a20, a21, a22
            c0, c1, c2 = mz0, mz1, mz2
            dz0 = dz1 = dz2 = 0.0
        M_C.append((c0, c1, c2))
        h2 = c0 * c0 + c1 * c1
        h = math.sqrt(h2)
        h3 = h2 * h
        z.append(math.atan2(c1, c0))
        z.append(-c2 / h)
        # Jacobian of (theta, rho) in m_C (line_from_normal)
        jt0, jt1 = -c1 / h2, c0 / h2
        jr0, jr1, jr2 = c2 * c0 / h3, c2 * c1 / h3, -1.0 / h
        # dm_C/dax = -R_in^T (e_x x m_A) = R_in^T (0, ma2, -ma1)
        d0 = r10 * ma2 - r20 * ma1
        d1 = r11 * ma2 - r21 * ma1
        d2 = r12 * ma2 - r22 * ma1
        H[i, _AX] = jt0 * d0 + jt1 * d1
        H[i + 1, _AX] = jr0 * d0 + jr1 * d1 + jr2 * d2
        # dm_C/day = -R_in^T (u x m_A), u = (0, cos ax, -sin ax)
        u0, u1, u2 = -(ca * ma2 + sa * ma1), sa * ma0, ca * ma0
        d0 = r00 * u0 + r10 * u1 + r20 * u2
        d1 = r01 * u0 + r11 * u1 + r21 * u2
        d2 = r02 * u0 + r12 * u1 + r22 * u2
        H[i, _AY] = jt0 * d0 + jt1 * d1
        H[i + 1, _AY] = jr0 * d0 + jr1 * d1 + jr2 * d2
        if row != 3:                                                      # dm_C/daz
            H[i, _AZ] = jt0 * dz0 + jt1 * dz1
            H[i + 1, _AZ] = jr0 * dz0 + jr1 * dz1 + jr2 * dz2
            # dm_C/dq = M e_z dm_z/dq for the ratios q (_DMZ)
            g_t = jt0 * mz0 + jt1 * mz1
            g_r = jr0 * mz0 + jr1 * mz1 + jr2 * mz2
            if row == 2:
                H[i, _XI], H[i + 1, _XI] = -g_t, -g_r
            else:
                H[i, _ZETA], H[i + 1, _ZETA] = g_t, g_r
                half = 0.5 if row == 0 else -0.5
                H[i, _OMEGA], H[i + 1, _OMEGA] = g_t * half, g_r * half
        i += 2
    return z, M_C, ((mx0, mx1, mx2), (my0, my1, my2), (mz0, mz1, mz2))


def predict_ins_velocity(state) -> tuple:
    """Inertial ground velocity in the input's runway axes, ``Rz(az)^T v``, and its Jacobian (3, 12).

    The input turns the NED velocity into runway axes with the estimated runway heading; ``az`` is
    that heading's error, so the true runway-axes velocity is ``Rz(az)`` times the input's.

    Parameters
    ----------
    state : array_like, shape (12,)
        The filter's mean in :data:`STATE_NAMES` order.

    Returns
    -------
    v_hat : numpy.ndarray, shape (3,)
        Predicted inertial ground velocity (m/s) in the input's runway axes.
    H : numpy.ndarray, shape (3, 12)
        ``d v_hat / d state``.

    References
    ----------
    E. D. Dickmanns, F.-R. Schell, "Autonomous landing of airplanes by dynamic machine vision"
    (seed 004), sec. 4 (inertial sensors); departure 3 of this module: the inertial velocity gives the scale.
    """
    H = np.zeros((3, N_STATES))
    return np.array(_ins_velocity_rows([float(v) for v in state], H, 0)), H


def _ins_velocity_rows(s, H, i: int) -> list:
    """Body of :func:`predict_ins_velocity` on floats: Jacobian into ``H[i:i+3]``, returns the 3 values."""
    vx, vy, vz, az = s[_VX], s[_VY], s[_VZ], s[_AZ]
    c, sn = math.cos(az), math.sin(az)
    H[i, _VX], H[i, _VY], H[i, _AZ] = c, sn, -sn * vx + c * vy
    H[i + 1, _VX], H[i + 1, _VY], H[i + 1, _AZ] = -sn, c, -c * vx - sn * vy
    H[i + 2, _VZ] = 1.0
    return [c * vx + sn * vy, -sn * vx + c * vy, vz]


def predict_air_data(state, body_y_runway_in) -> tuple:
    """True airspeed and body-lateral air velocity predicted from the state, and their Jacobian (2, 12).

    ``a = v - w`` (``w = (wx, wy, 0)``) is the air velocity; ``tas = |a|``; zero sideslip is
    ``u . a = 0`` with ``u = Rz(az) e_yB`` the body y axis in the true runway axes
    (``body_y_runway_in``: the same axis in the input's runway axes, from the inertial attitude).

    Parameters
    ----------
    state : array_like, shape (12,)
        The filter's mean in :data:`STATE_NAMES` order.
    body_y_runway_in : array_like, shape (3,)
        Unit body y axis (right wing) in the input's runway axes.

    Returns
    -------
    z_hat : numpy.ndarray, shape (2,)
        Predicted true airspeed (m/s) and body-lateral air velocity (m/s, zero in coordinated flight).
    H : numpy.ndarray, shape (2, 12)
        ``d z_hat / d state``.

    References
    ----------
    E. D. Dickmanns, F.-R. Schell, "Autonomous landing of airplanes by dynamic machine vision"
    (seed 004), sec. 4 ("aerodynamic speed" from the air velocity meter).
    """
    H = np.zeros((2, N_STATES))
    z = _air_data_rows([float(v) for v in state], tuple(float(v) for v in body_y_runway_in), H, 0)
    return np.array(z), H


def _air_data_rows(s, body_y_runway_in, H, i: int) -> list:
    """Body of :func:`predict_air_data` on floats: Jacobian into ``H[i:i+2]``, returns the 2 values."""
    a0, a1, a2 = s[_VX] - s[_WX], s[_VY] - s[_WY], s[_VZ]
    speed = math.sqrt(a0 * a0 + a1 * a1 + a2 * a2)
    c, sn = math.cos(s[_AZ]), math.sin(s[_AZ])
    e0, e1, e2 = body_y_runway_in
    u0, u1 = c * e0 - sn * e1, sn * e0 + c * e1
    H[i, _VX], H[i, _VY], H[i, _VZ] = a0 / speed, a1 / speed, a2 / speed
    H[i, _WX], H[i, _WY] = -a0 / speed, -a1 / speed
    H[i + 1, _VX], H[i + 1, _VY], H[i + 1, _VZ] = u0, u1, e2
    H[i + 1, _WX], H[i + 1, _WY] = -u0, -u1
    H[i + 1, _AZ] = -u1 * a0 + u0 * a1                       # (dRz/daz e) . a
    return [speed, u0 * a0 + u1 * a1 + e2 * a2]


def state_derivative(state, omega_runway_rps, with_wind: bool = True) -> list:
    """Point-mass kinematics in the inverse-depth state (module docstring, departure 2).

    With ``x' = vx``, ``y' = vy``, ``H' = -vz`` and ``eta = 1/H``::

        (x/H)' = eta (vx + (x/H) vz)      (y/H)' = eta (vy + (y/H) vz)      eta' = vz eta^2
        (W/H)' = (W/H) eta vz             v' = Omega x (v - w)              a', w' = 0

    Parameters
    ----------
    state : sequence of float, length 12
        The state in :data:`STATE_NAMES` order (SI units: 1/m, m/s, rad).
    omega_runway_rps : sequence of float, length 3
        Body angular rates (rad/s) turned into runway axes.
    with_wind : bool, optional
        Whether the wind states enter the air velocity ``v - w`` (False: ``w`` taken as zero).

    Returns
    -------
    list of float, length 12
        ``d state / dt`` (per second).

    References
    ----------
    E. D. Dickmanns, F.-R. Schell, "Autonomous landing of airplanes by dynamic machine vision"
    (seed 004), eq. (1)-(3), the dynamical model, reduced to point-mass kinematics (departure 2).
    """
    xi, zeta, eta, vx, vy, vz = state[0], state[1], state[2], state[3], state[4], state[5]
    a0, a1 = (vx - state[_WX], vy - state[_WY]) if with_wind else (vx, vy)
    o0, o1, o2 = omega_runway_rps[0], omega_runway_rps[1], omega_runway_rps[2]
    return [eta * (vx + xi * vz), eta * (vy + zeta * vz), vz * eta * eta,
            o1 * vz - o2 * a1, o2 * a0 - o0 * vz, o0 * a1 - o1 * a0,
            0.0, 0.0, 0.0, 0.0, 0.0, state[_OMEGA] * eta * vz]


def _heun_step(x, omega0, omega1, dt: float, with_wind: bool) -> list:
    """One step of Heun's method on :func:`state_derivative`: ``x + dt/2 (k1 + k2)`` with
    ``k1 = f(x, omega0)``, ``k2 = f(x + dt k1, omega1)`` (``x`` a list of floats; returns a new list).

    The same floats as the two calls and the element-wise sums written with lists, on the seven
    derivatives that are not zero (position ratios, velocity, ``W/H``): the attitude correction and
    the wind stay as they are. Runs at every inertial step.
    """
    xi, zeta, eta, vx, vy, vz = x[0], x[1], x[2], x[3], x[4], x[5]
    wx, wy, om = x[_WX], x[_WY], x[_OMEGA]
    o0, o1, o2 = omega0[0], omega0[1], omega0[2]
    a0, a1 = (vx - wx, vy - wy) if with_wind else (vx, vy)
    d0, d1, d2 = eta * (vx + xi * vz), eta * (vy + zeta * vz), vz * eta * eta
    d3, d4, d5 = o1 * vz - o2 * a1, o2 * a0 - o0 * vz, o0 * a1 - o1 * a0
    d11 = om * eta * vz
    mxi, mzeta, meta = xi + dt * d0, zeta + dt * d1, eta + dt * d2
    mvx, mvy, mvz, mom = vx + dt * d3, vy + dt * d4, vz + dt * d5, om + dt * d11
    o0, o1, o2 = omega1[0], omega1[1], omega1[2]
    a0, a1 = (mvx - wx, mvy - wy) if with_wind else (mvx, mvy)
    e0, e1, e2 = meta * (mvx + mxi * mvz), meta * (mvy + mzeta * mvz), mvz * meta * meta
    e3, e4, e5 = o1 * mvz - o2 * a1, o2 * a0 - o0 * mvz, o0 * a1 - o1 * a0
    e11 = mom * meta * mvz
    h = 0.5 * dt
    out = list(x)
    out[0], out[1], out[2] = xi + h * (d0 + e0), zeta + h * (d1 + e1), eta + h * (d2 + e2)
    out[3], out[4], out[5] = vx + h * (d3 + e3), vy + h * (d4 + e4), vz + h * (d5 + e5)
    out[_OMEGA] = om + h * (d11 + e11)
    return out


def state_jacobian(state, omega_runway_rps, with_wind: bool = True) -> np.ndarray:
    """``F = d state_derivative / d state`` (12, 12).

    Parameters
    ----------
    state : sequence of float, length 12
        The state in :data:`STATE_NAMES` order.
    omega_runway_rps : sequence of float, length 3
        Body angular rates (rad/s) in runway axes.
    with_wind : bool, optional
        As in :func:`state_derivative`.

    Returns
    -------
    numpy.ndarray, shape (12, 12)
        The Jacobian of :func:`state_derivative` (per second).

    References
    ----------
    E. D. Dickmanns, F.-R. Schell, "Autonomous landing of airplanes by dynamic machine vision"
    (seed 004), eq. (1)-(3), linearised for the EKF (sec. 4).
    """
    xi, zeta, eta, vx, vy, vz = state[0], state[1], state[2], state[3], state[4], state[5]
    omega = state[_OMEGA]
    o0, o1, o2 = omega_runway_rps[0], omega_runway_rps[1], omega_runway_rps[2]
    F = np.zeros((N_STATES, N_STATES))
    F[_XI, _XI], F[_XI, _ETA], F[_XI, _VX], F[_XI, _VZ] = eta * vz, vx + xi * vz, eta, eta * xi
    F[_ZETA, _ZETA], F[_ZETA, _ETA], F[_ZETA, _VY], F[_ZETA, _VZ] = eta * vz, vy + zeta * vz, eta, eta * zeta
    F[_ETA, _ETA], F[_ETA, _VZ] = 2.0 * vz * eta, eta * eta
    F[_OMEGA, _OMEGA], F[_OMEGA, _ETA], F[_OMEGA, _VZ] = eta * vz, omega * vz, omega * eta
    # v' = [Omega]x (v - w)
    F[_VX, _VY], F[_VX, _VZ] = -o2, o1
    F[_VY, _VX], F[_VY, _VZ] = o2, -o0
    F[_VZ, _VX], F[_VZ, _VY] = -o1, o0
    if with_wind:
        F[_VX, _WY] = o2
        F[_VY, _WX] = -o2
        F[_VZ, _WX], F[_VZ, _WY] = o1, -o0
    return F


def _transition_matrix(state, omega_runway_rps, with_wind: bool, T: float) -> np.ndarray:
    """``F_d = I + F T`` (12, 12) with ``F`` of :func:`state_jacobian`, written entry by entry into a copy
    of the identity (the same values as ``I + state_jacobian(...) * T`` without the two whole-matrix
    operations: the covariance propagation runs at every update)."""
    xi, zeta, eta, vx, vy, vz = state[0], state[1], state[2], state[3], state[4], state[5]
    omega = state[_OMEGA]
    o0, o1, o2 = omega_runway_rps[0] * T, omega_runway_rps[1] * T, omega_runway_rps[2] * T
    Fd = _I12.copy()
    d = 1.0 + eta * vz * T
    Fd[_XI, _XI], Fd[_XI, _ETA], Fd[_XI, _VX], Fd[_XI, _VZ] = d, (vx + xi * vz) * T, eta * T, eta * xi * T
    Fd[_ZETA, _ZETA], Fd[_ZETA, _ETA], Fd[_ZETA, _VY], Fd[_ZETA, _VZ] = d, (vy + zeta * vz) * T, eta * T, eta * zeta * T
    Fd[_ETA, _ETA], Fd[_ETA, _VZ] = 1.0 + 2.0 * vz * eta * T, eta * eta * T
    Fd[_OMEGA, _OMEGA], Fd[_OMEGA, _ETA], Fd[_OMEGA, _VZ] = d, omega * vz * T, omega * eta * T
    Fd[_VX, _VY], Fd[_VX, _VZ] = -o2, o1
    Fd[_VY, _VX], Fd[_VY, _VZ] = o2, -o0
    Fd[_VZ, _VX], Fd[_VZ, _VY] = -o1, o0
    if with_wind:
        Fd[_VX, _WY] = o2
        Fd[_VY, _WX] = -o2
        Fd[_VZ, _WX], Fd[_VZ, _WY] = o1, -o0
    return Fd


def segment_line_covariance(a_xy, b_xy, m_reference, sigma: float) -> tuple:
    """Covariance of ``(theta, rho)`` of the line through two image points, as ``(var_theta, cov, var_rho)``.

    Each point errs by ``sigma`` (normalised units) across the line, independently (along the line
    it does not move the line). With homogeneous points ``a_h``, ``b_h`` the normal is
    ``m = a_h x b_h``; moving ``a`` by ``e`` along the line's unit normal ``n`` changes ``m`` by
    ``e (n, 0) x b_h``, and ``b`` by ``e a_h x (n, 0)``; with ``J = d(theta, rho)/dm``
    (:func:`line_from_normal`) and ``G = J [dm/de_a, dm/de_b]`` the covariance is
    ``sigma^2 G G^T``. ``m_reference`` orients ``m`` (the theta-rho covariance changes sign with the
    representative).

    Parameters
    ----------
    a_xy, b_xy : array_like, shape (2,)
        The two image points in normalised image coordinates (``x = (u - cx)/fx``, ``y = (v - cy)/fy``).
    m_reference : array_like, shape (3,)
        A normal of the same line (e.g. the predicted one) whose sign picks the representative.
    sigma : float
        Standard deviation of each point across the line (normalised units).

    Returns
    -------
    (var_theta, cov_theta_rho, var_rho) : tuple of float
        In rad^2, rad x normalised units, normalised units^2; ``(1e6, 0, 1e6)`` when the two points
        coincide.

    References
    ----------
    E. D. Dickmanns, F.-R. Schell, "Autonomous landing of airplanes by dynamic machine vision"
    (seed 004), sec. 3 (measurement noise of the border windows), replaced here by lines (departure 5).
    """
    return _segment_line_covariance(float(a_xy[0]), float(a_xy[1]), float(b_xy[0]), float(b_xy[1]), m_reference,
                                    sigma)


def _segment_line_covariance(a0: float, a1: float, b0: float, b1: float, m_reference, sigma: float) -> tuple:
    """Body of :func:`segment_line_covariance` on floats, in closed form: with ``L = |b - a|``,
    ``G = J [dm/de_a, dm/de_b]`` is ``(-1/L, 1/L)`` for theta and ``s (|b|^2 - a.b, |a|^2 - a.b) / L^2``
    for rho (``s`` the sign that orients ``m`` along ``m_reference``)."""
    m0, m1, m2 = a1 - b1, b0 - a0, a0 * b1 - a1 * b0              # (a0, a1, 1) x (b0, b1, 1)
    h2 = m0 * m0 + m1 * m1
    if h2 < 1e-30:
        return 1e6, 0.0, 1e6
    ab = a0 * b0 + a1 * b1
    ga_r = (b0 * b0 + b1 * b1 - ab) / h2
    gb_r = (a0 * a0 + a1 * a1 - ab) / h2
    if m0 * m_reference[0] + m1 * m_reference[1] + m2 * m_reference[2] < 0:
        ga_r, gb_r = -ga_r, -gb_r
    s2 = sigma * sigma
    return 2.0 * s2 / h2, s2 * (gb_r - ga_r) / math.sqrt(h2), s2 * (ga_r * ga_r + gb_r * gb_r)


def _edge_pair_observability(y, v, n) -> float:
    """:func:`visland.estimation.lines_model.pair_observability` of the edges ``y[:4]`` (``(theta, rho)``
    of the left and right edge) for the camera velocity ``v`` and runway down axis ``n`` (camera
    axes, floats): the same floats (its ``Phi`` terms written out; the rotation terms ``g`` do not
    enter thesis 3.40)."""
    v0, v1, v2 = v
    n0, n1, n2 = n
    phi = []
    for theta, rho in ((y[0], y[1]), (y[2], y[3])):
        c = math.cos(theta)
        s = math.sin(theta)
        speed = c * v0 + s * v1 - rho * v2
        phi.append(-(n0 * s - n1 * c) * speed)
        phi.append(-(rho * (n0 * c + n1 * s) + n2) * speed)
    ptl, prl, ptr, prr = phi
    return ptl * ptl + prl * prl + ptr * ptr + prr * prr


def _body_y_runway(inp: ObserverInput) -> tuple:
    """Body y axis in the input's runway axes: second column of ``Rz(dpsi) Ry(pitch) Rx(roll)``."""
    cr, sr = math.cos(inp.roll_rad), math.sin(inp.roll_rad)
    cp, sp = math.cos(inp.pitch_rad), math.sin(inp.pitch_rad)
    cz, sz = math.cos(inp.dpsi_rad), math.sin(inp.dpsi_rad)
    x1 = sp * sr                                          # Ry Rx e_y = (sp sr, cr, cp sr)
    return (cz * x1 - sz * cr, sz * x1 + cz * cr, cp * sr)


def _aligned(theta: float, rho: float, theta_ref: float) -> tuple:
    """The representative ``(theta, rho)`` of a SPEC line nearest ``theta_ref``."""
    while theta - theta_ref > 0.5 * math.pi:
        theta -= math.pi
        rho = -rho
    while theta - theta_ref < -0.5 * math.pi:
        theta += math.pi
        rho = -rho
    return theta, rho


def _threshold_points(points_yv, R_runway_from_camera) -> tuple:
    """Normalised image points ``((x, y), (x, y))`` of P' and P'' back from their virtual coordinates
    (thesis 3.23): the ray ``(y_v1, y_v2, 1)`` in runway axes turned into the camera, ``R^T ray``."""
    (r00, r01, r02), (r10, r11, r12), (r20, r21, r22) = R_runway_from_camera
    out = []
    for y1, y2 in (points_yv.tolist() if isinstance(points_yv, np.ndarray) else points_yv):
        c2 = r02 * y1 + r12 * y2 + r22
        out.append(((r00 * y1 + r10 * y2 + r20) / c2, (r01 * y1 + r11 * y2 + r21) / c2))
    return out


def _theta_rho(m0: float, m1: float, m2: float) -> tuple:
    """``(theta, rho)`` of :func:`line_from_normal` without its Jacobian (floats)."""
    return math.atan2(m1, m0), -m2 / math.sqrt(m0 * m0 + m1 * m1)


# --------------------------------------------------------------------------- the filter
class Dickmanns4D(Observer):
    """Extended Kalman filter of the 4D approach (seed 004; see the module docstring).

    State (``Estimate.state`` holds the 12 values of :data:`STATE_NAMES`, the 144 entries of the
    covariance ``P`` (row-major), then the time its propagation is pending (see below))::

        s = [x/H, y/H, 1/H, vx, vy, vz, ax, ay, az, wx, wy, W/H]

    - predict (every inertial step): the mean follows :func:`state_derivative` with Heun's method
      (body rates in runway axes at both ends of the step). The covariance is carried to the next
      update in one go, ``P <- F_d P F_d^T + Q T`` with ``F_d = I + F T`` over the time ``T`` since
      the last update (``F`` of :func:`state_jacobian` at the predicted mean; ``T`` is 0.04 s at
      25 Hz, where ``F T`` is of order 1e-3 and the second-order terms are far below the noise);
      ``Q`` is that of :class:`Dickmanns4DParams`, the wind's noise shared with the horizontal
      ground velocity.
    - update, on every camera frame and at least every ``inertial_update_interval_s``: the
      inertial ground velocity (:func:`predict_ins_velocity`); with airspeed, ``tas`` and zero
      sideslip (:func:`predict_air_data`); on camera frames the two edges, the threshold line when
      both threshold corners are measured, and the horizon (:func:`predict_vision`). One joint
      update (Maybeck, the seed's reference [8]): ``K = P H^T S^-1``, ``P <- P - K S K^T``.

    ``dH = 1/eta``, ``dX = x - D``, ``dY = y`` and the width ``W`` come from the state
    (:meth:`deviations`); the observability reported is thesis 3.40 on the predicted edges at the
    last camera frame (the index of the line observers).
    """

    name: ClassVar[str] = "dickmanns-4d"
    features: ClassVar[str] = "lines"
    params_type: ClassVar[type] = Dickmanns4DParams

    def __init__(self, params=None):
        super().__init__(params)
        self.notes: list[str] = []
        self._x = np.zeros(N_STATES)
        self._P = np.eye(N_STATES)
        self._pending_s = 0.0
        self._packed = None                 # (x, P, pending, packed state) of the last step (_pack)
        self._omega_prev = np.zeros(3)
        self._with_wind = False
        self._t_update = 0.0
        self._observability = 0.0
        self._dpsi_in = 0.0
        p = self.params
        q = np.zeros(N_STATES)
        q[_VX:_VZ + 1] = p.q_velocity ** 2
        q[_VX:_VY + 1] += p.q_wind ** 2                     # a wind change moves the ground velocity
        q[_AX:_AZ + 1] = p.q_attitude ** 2
        self._Q_base = np.diag(q)
        self._q_diag = q.tolist()
        qw = p.q_wind ** 2                                  # with the wind states: their own noise, shared
        self._Q_wind = self._Q_base.copy()
        self._Q_wind[_WX, _WX] = self._Q_wind[_WY, _WY] = qw
        self._Q_wind[_VX, _WX] = self._Q_wind[_WX, _VX] = self._Q_wind[_VY, _WY] = self._Q_wind[_WY, _VY] = qw

    # ---- state bookkeeping
    def _get_state(self):
        packed = self._packed
        if packed is not None and packed[0] is self._x and packed[1] is self._P and packed[2] == self._pending_s:
            return packed[3].copy()
        return np.concatenate([self._x, self._P.ravel(), [self._pending_s]])

    def _pack(self, x) -> np.ndarray:
        """The state of :meth:`_get_state` after a step (``x`` the mean as floats), kept for the next
        step's backup: the covariance is copied only when it changed (every other inertial step
        only moves the mean), and the mean becomes a view of the packed array."""
        packed = self._packed
        if packed is not None and packed[1] is self._P:
            a = packed[3].copy()
            a[:N_STATES] = x
            a[-1] = self._pending_s
        else:
            a = np.concatenate([x, self._P.ravel(), [self._pending_s]])
        self._x = a[:N_STATES]
        self._packed = (self._x, self._P, self._pending_s, a)
        return a

    def _set_state(self, state):
        self._x = state[:N_STATES].copy()
        self._P = state[N_STATES:N_STATES + N_STATES * N_STATES].reshape(N_STATES, N_STATES).copy()
        self._pending_s = float(state[-1])
        self._packed = None

    def _dh_from_state(self, state):
        return 1.0 / clip_eta(float(state[_ETA]))

    @property
    def with_wind(self) -> bool:
        """True when the wind states are estimated (airspeed available and enabled)."""
        return self._with_wind

    @property
    def state(self) -> np.ndarray:
        """The mean (12,), :data:`STATE_NAMES` order (a copy)."""
        return self._x.copy()

    @property
    def covariance(self) -> np.ndarray:
        """The covariance (12, 12) at the last update (a copy)."""
        return self._P.copy()

    def deviations(self, aim_distance_m: float = DEFAULT_AIM_DISTANCE_M) -> Deviations:
        """SPEC deviations from the state: ``dH = 1/eta``, ``dX = x - D``, ``dY = y``, width ``W``."""
        x = self._x.tolist()
        h = 1.0 / x[_ETA]
        return Deviations(x[_XI] * h - aim_distance_m, x[_ZETA] * h, h, x[_OMEGA] * h)

    def dx_sigma_m(self) -> float:
        """Standard deviation of ``dX`` from the covariance (first order), metres.

        ``x = xi / eta``, so ``dx = dxi / eta - (xi / eta^2) deta``: with ``H = 1/eta``,
        ``delta X = H delta(x/H) + (x/H) delta H``. On an approach the second term dominates: the
        along-track range is the image ratio ``x/H`` (threshold line, well measured) times the
        height scale, and the scale comes only from the image's motion against the inertial
        velocity, so ``x/H`` (about 16 at 2 km on a 3 deg path) multiplies the height error. On
        ``dickmanns-wind`` at 1 px this is 9 m at 2 km from the threshold and 3 m at 1 km, and the
        errors agree with it (NEES 0.4-1.1 over seeds 0-3).

        Returns
        -------
        float
            ``sqrt(J P J^T)`` with ``J = d(x/H / eta)/d(state)``.
        """
        xi, eta = float(self._x[_XI]), float(self._x[_ETA])
        j_xi, j_eta = 1.0 / eta, -xi / (eta * eta)
        P = self._P
        var = j_xi * j_xi * P[_XI, _XI] + 2.0 * j_xi * j_eta * P[_XI, _ETA] + j_eta * j_eta * P[_ETA, _ETA]
        return math.sqrt(max(var, 0.0))

    def wind_runway_mps(self) -> tuple:
        """Estimated horizontal wind ``(wx, wy)`` in runway axes (NaN when not estimated)."""
        if not self._with_wind:
            return math.nan, math.nan
        return float(self._x[_WX]), float(self._x[_WY])

    def extra_outputs(self) -> dict:
        """Per-step outputs beyond ``Estimate``: the wind (estimates.csv ``wind_x_mps, wind_y_mps``) and
        the heading deviation corrected by the filter, ``dpsi_rad`` (the input's plus ``az``)."""
        wx, wy = self.wind_runway_mps()
        return {"wind_x_mps": wx, "wind_y_mps": wy, "dpsi_rad": self._dpsi_in + float(self._x[_AZ])}

    # ---- reset
    def _reset(self, first: ObserverInput, dh0_m: float, measurement: np.ndarray) -> None:
        p = self.params
        self.notes = []
        tas = first.tas_mps
        self._with_wind = bool(p.estimate_wind and tas is not None and math.isfinite(tas))
        if p.estimate_wind and not self._with_wind:
            self.notes.append(NO_AIRSPEED_NOTE)
        R_rc = first.R_runway_from_camera
        ratios = deviations_from_lines(measurement, R_rc, 1.0)          # at H = 1: y/H and W/H
        zeta0 = ratios.dy_m if math.isfinite(ratios.dy_m) else 0.0
        omega0 = ratios.width_m if math.isfinite(ratios.width_m) and ratios.width_m > 0 else 0.15
        eta0 = 1.0 / dh0_m
        if first.points_yv is not None and np.isfinite(first.points_yv).all():
            xi0 = -0.5 * float(first.points_yv[0, 0] + first.points_yv[1, 0])     # thesis 3.23: X_v = -x
            sigma_xi = p.p0_ratio_fraction * abs(xi0) + 0.01
        else:
            # no threshold yet: on a 3 deg glide path to the default aiming point, loosely
            xi0 = DEFAULT_AIM_DISTANCE_M * eta0 - 1.0 / math.tan(math.radians(3.0))
            sigma_xi = abs(xi0)
        x = np.zeros(N_STATES)
        x[_XI], x[_ZETA], x[_ETA], x[_OMEGA] = xi0, zeta0, eta0, omega0
        x[_VX:_VZ + 1] = first.v_runway_mps
        self._x = x
        P = np.zeros((N_STATES, N_STATES))
        P[_XI, _XI] = sigma_xi ** 2
        P[_ZETA, _ZETA] = (p.p0_ratio_fraction * abs(zeta0) + 0.01) ** 2
        P[_ETA, _ETA] = (p.p0_height_fraction * eta0) ** 2
        P[_OMEGA, _OMEGA] = (p.p0_ratio_fraction * omega0 + 0.01) ** 2
        for i in (_VX, _VY, _VZ):
            P[i, i] = p.velocity_sigma_mps ** 2 + 0.25
        for i in (_AX, _AY, _AZ):
            P[i, i] = p.p0_attitude_rad ** 2
        for i in (_WX, _WY):
            P[i, i] = p.p0_wind_mps ** 2 if self._with_wind else 0.0
        self._P = P
        self._pending_s = 0.0
        self._packed = None
        self._omega_prev = R_rc @ first.omega_camera_rps
        self._t_update = float(first.t_s)
        self._observability = 0.0
        self._dpsi_in = float(first.dpsi_rad)

    # ---- one step
    def _step(self, inp: ObserverInput, dt_s: float, measurement) -> Estimate:
        p = self.params
        R_rc = inp.R_runway_from_camera
        (r00, r01, r02), (r10, r11, r12), (r20, r21, r22) = R_rc.tolist()
        w0, w1, w2 = inp.omega_camera_rps.tolist()
        omega1 = [r00 * w0 + r01 * w1 + r02 * w2, r10 * w0 + r11 * w1 + r12 * w2, r20 * w0 + r21 * w1 + r22 * w2]
        # Heun's method on the mean
        x = _heun_step(self._x.tolist(), self._omega_prev, omega1, dt_s, self._with_wind)
        x[_ETA] = clip_eta(x[_ETA])
        self._omega_prev = omega1
        self._dpsi_in = float(inp.dpsi_rad)
        self._pending_s += dt_s
        t = float(inp.t_s)
        if measurement is not None or t - self._t_update >= p.inertial_update_interval_s - 1e-9:
            self._propagate_covariance(omega1, x)
            x = self._update(inp, measurement, x)
            self._t_update = t
        state = self._pack(x)
        return Estimate(t_s=t, dh_m=1.0 / x[_ETA], observability=self._observability,
                        coasting=measurement is None, state=state.copy())

    def _propagate_covariance(self, omega_runway_rps, x) -> None:
        """``P <- F_d P F_d^T + Q T`` over the pending time ``T`` (class docstring); ``x`` the mean as
        a list of floats."""
        p = self.params
        T = self._pending_s
        if T <= 0.0:
            return
        Fd = _transition_matrix(x, omega_runway_rps, self._with_wind, T)
        Q = self._Q_wind if self._with_wind else self._Q_base     # (the wind's noise shared with the velocity)
        QT = Q * T
        eta = x[_ETA]
        q_pos = (p.q_position * eta) ** 2                     # position noise in the ratio coordinates
        QT[_XI, _XI] = (self._q_diag[_XI] + q_pos) * T
        QT[_ZETA, _ZETA] = (self._q_diag[_ZETA] + q_pos) * T
        QT[_ETA, _ETA] = (self._q_diag[_ETA] + q_pos * eta * eta) * T
        P = np.dot(np.dot(Fd, self._P), Fd.T)
        P += QT
        self._P = P
        self._pending_s = 0.0

    def _update(self, inp: ObserverInput, measurement, s) -> list:
        """One joint update (class docstring); ``s`` the predicted mean as a list of floats. Sets the
        covariance; returns the corrected mean (floats)."""
        p = self.params
        tas = inp.tas_mps
        with_air = self._with_wind and math.isfinite(tas)
        with_vision = measurement is not None
        points = inp.points_yv.tolist() if with_vision and inp.points_yv is not None else None
        with_threshold = points is not None and math.isfinite(points[0][0] + points[0][1] + points[1][0]
                                                              + points[1][1])
        n_diag = 5 if with_air else 3
        m_total = n_diag + ((8 if with_threshold else 6) if with_vision else 0)
        H = np.zeros((m_total, N_STATES))
        R = np.zeros((m_total, m_total))
        # inertial ground velocity
        h = _ins_velocity_rows(s, H, 0)
        v = inp.v_runway_mps.tolist()
        innovation = [v[0] - h[0], v[1] - h[1], v[2] - h[2]]
        r_v = p.velocity_sigma_mps ** 2
        R[0, 0] = R[1, 1] = R[2, 2] = r_v
        if with_air:                                                    # air data
            h = _air_data_rows(s, _body_y_runway(inp), H, 3)
            innovation += [tas - h[0], 0.0 - h[1]]
            R[3, 3] = p.airspeed_sigma_mps ** 2
            R[4, 4] = (p.sideslip_sigma_rad * tas) ** 2
        if with_vision:                                                 # image lines
            R_rc = inp.R_runway_from_camera.tolist()
            rows = (0, 1, 2, 3) if with_threshold else (0, 1, 3)
            h, M_C, M = _vision_rows(s, R_rc, rows, H, n_diag)
            z = [0.0] * len(h)
            lines = measurement.tolist()
            for k in range(2):
                z[2 * k], z[2 * k + 1] = _aligned(lines[k][1], lines[k][0], h[2 * k])
            k = 2
            if with_threshold:
                (a0, a1), (b0, b1) = _threshold_points(points, R_rc)
                theta, rho = _theta_rho(a1 - b1, b0 - a0, a0 * b1 - a1 * b0)
                z[4], z[5] = _aligned(theta, rho, h[4])
                k = 3
            theta, rho = _theta_rho(*R_rc[2])                         # horizon of the inertial attitude (level down axis)
            z[2 * k], z[2 * k + 1] = _aligned(theta, rho, h[2 * k])
            innovation += [z[i] - h[i] for i in range(len(h))]
            self._vision_covariance(s, M, M_C, with_threshold, R, n_diag)
            # thesis 3.40 on the predicted edges (the line observers' index)
            self._observability = _edge_pair_observability(h, inp.v_camera_mps.tolist(), inp.n_camera.tolist())
        # Kalman update (Maybeck, the seed's [8]): K = P H^T S^-1, P <- P - K S K^T; S is symmetric
        # positive definite, so its Cholesky factor solves for K^T (LAPACK dposv: a third of the
        # time numpy.linalg.solve takes on 13 x 13, most of which is call overhead)
        P = self._P
        PHt = np.dot(P, H.T)
        S = np.dot(H, PHt)
        S += R
        _, Kt, info = _dposv(S, PHt.T)
        if info != 0:                                                   # not positive definite: LU
            Kt = np.linalg.solve(S, PHt.T)
        x = (np.array(s) + np.dot(innovation, Kt)).tolist()
        x[_ETA] = clip_eta(x[_ETA])
        P = P - np.dot(PHt, Kt)
        P_sym = P.T.copy()                      # 0.5 (P + P^T), without numpy's strided add
        P_sym += P
        P_sym *= 0.5
        self._P = P_sym
        return x

    def _vision_covariance(self, s, M, M_C, with_threshold: bool, R, i0: int) -> None:
        """R of the vision block, written into ``R[i0:, i0:]``: each runway line through two image
        points (module docstring, 5). ``s`` the state (floats), ``M`` the columns of
        ``R_in^T A^T`` (:func:`_vision_rows`)."""
        p = self.params
        sigma = p.image_sigma_rad
        (mx0, mx1, mx2), (my0, my1, my2), (mz0, mz1, mz2) = M
        xi, zeta, omega, eta = s[_XI], s[_ZETA], s[_OMEGA], s[_ETA]

        # the threshold corners and the points noise_edge_length_m along each edge, seen from the
        # camera (runway-axes directions (d0, d1, 1) divided by H, turned into normalised image points)
        far_x = p.noise_edge_length_m * eta - xi
        left, right = -0.5 * omega - zeta, 0.5 * omega - zeta
        points = []
        for d0, d1 in ((-xi, left), (far_x, left), (-xi, right), (far_x, right)):
            c2 = d0 * mx2 + d1 * my2 + mz2
            points.append(None if c2 <= 1e-9 else ((d0 * mx0 + d1 * my0 + mz0) / c2, (d0 * mx1 + d1 * my1 + mz1) / c2))
        near_left, far_left, near_right, far_right = points
        blocks = [(near_left, far_left, M_C[0], sigma), (near_right, far_right, M_C[1], sigma)]
        if with_threshold:
            blocks.append((near_left, near_right, M_C[2], sigma * p.threshold_sigma_factor))
        i = i0
        for a, b, m, sigma_k in blocks:
            if a is None or b is None:
                R[i, i] = R[i + 1, i + 1] = 1e2
            else:
                R[i, i], R[i, i + 1], R[i + 1, i + 1] = _segment_line_covariance(a[0], a[1], b[0], b[1], m, sigma_k)
                R[i + 1, i] = R[i, i + 1]
            i += 2
        R[i, i] = R[i + 1, i + 1] = p.horizon_sigma_rad ** 2

    # ---- for the detector: the lines this filter expects in a frame
    def predicted_lines(self, inp: ObserverInput) -> dict:
        """The runway lines expected at ``inp.t_s`` (later than the last step); nothing is changed.

        The mean is carried to ``inp.t_s`` by the model (inertial rates of ``inp``). Returns
        ``{"left", "right", "threshold", "horizon": (rho, theta) in the SPEC chart, "near_xy": (2, 2)
        normalised threshold corners P', P'' (NaN behind the camera), "far_xy": (2, 2) the points
        ``noise_edge_length_m`` further along the left and right edges, "dpsi_rad": the heading
        deviation corrected by the filter}``: what :func:`visland.detection.predicted.prior_from_prediction`
        turns into the detector's search window (seed 004's prediction-placed windows).
        """
        from visland.camera import wrap_line_chart
        if self._t_s is None:
            raise ValueError(f"{self.name}: call reset() before predicted_lines()")
        dt = float(inp.t_s) - self._t_s
        x = self._x.tolist()
        omega1 = (inp.R_runway_from_camera @ inp.omega_camera_rps).tolist()
        if dt > 0:
            k1 = state_derivative(x, self._omega_prev, self._with_wind)
            mid = [x[i] + dt * k1[i] for i in range(N_STATES)]
            k2 = state_derivative(mid, omega1, self._with_wind)
            x = [x[i] + 0.5 * dt * (k1[i] + k2[i]) for i in range(N_STATES)]
        x = np.array(x)
        z, _, _ = predict_vision(x, inp.R_runway_from_camera, with_threshold=True)
        out = {}
        for k, name in enumerate(("left", "right", "threshold", "horizon")):
            rho, theta = wrap_line_chart(np.array(z[2 * k + 1]), np.array(z[2 * k]))
            out[name] = (float(rho), float(theta))
        A = rotation_correction(x[_AX], x[_AY], x[_AZ])
        R_cr = (A @ inp.R_runway_from_camera).T
        far_x = self.params.noise_edge_length_m * x[_ETA] - x[_XI]
        ends = np.array([[-x[_XI], -0.5 * x[_OMEGA] - x[_ZETA], 1.0],
                         [-x[_XI], 0.5 * x[_OMEGA] - x[_ZETA], 1.0],
                         [far_x, -0.5 * x[_OMEGA] - x[_ZETA], 1.0],
                         [far_x, 0.5 * x[_OMEGA] - x[_ZETA], 1.0]]) @ R_cr.T
        with np.errstate(divide="ignore", invalid="ignore"):
            xy = np.where(ends[:, 2:3] > 1e-9, ends[:, :2] / ends[:, 2:3], np.nan)
        out["near_xy"], out["far_xy"] = xy[:2], xy[2:]
        out["dpsi_rad"] = float(inp.dpsi_rad) + float(x[_AZ])
        return out
