"""Self-calibration of the camera mounting (and the runway's slope) from the runway itself (issue 12).

A camera is never mounted exactly as ``camera.json`` says: half a degree of pitch costs the point
observers 15-20 m of height at 100 ft (thesis Table 5.10). This module estimates, online and
causally, the error ``delta = (d_roll, d_pitch, d_yaw)`` of ``mount_rpy`` and the runway's
longitudinal slope ``s`` (``slope_pct / 100``), with their covariance, from three kinds of
measurement that need no runway size:

1. **Runway vanishing point on the horizon.** The runway's direction ``(1, 0, -s)`` (R axes, z
   down; :meth:`visland.runway.Runway.direction_runway`) is horizontal up to the slope, so the
   vanishing point of the two edges, back-projected with the IMU attitude and the mounting, has
   the elevation ``-s``.
2. **Threshold direction on the horizon.** The threshold line is horizontal (no transverse slope)
   and orthogonal to the runway's direction; in the image it is the interpretation plane
   ``m = x' x x''`` of the near corners, so its direction is ``d_rwy x m`` and its elevation is 0.
3. **Epipolar constraint** (the translation's direction seen in the image, Hartley and Zisserman,
   *Multiple View Geometry*, eq. 9.1 with a known translation): a static corner seen along the
   unit bearings ``r_j`` and ``r_k`` (NED axes) from two camera positions ``T`` apart
   (the inertial velocity integrated) satisfies ``r_k . (T x r_j) = 0``. The mounting error
   rotates every bearing; the slope does not enter. This is what separates a mount pitch error
   from a sloped runway: the vanishing point alone sees only their difference.

Measurement model (derived here, checked against the simulator in the tests). With
``R_BC = Rz(y) Ry(p) Rx(r) R0`` (:func:`visland.frames.R_body_from_camera`) a small error
``delta`` of the Euler angles rotates the camera in the body by ``eps_B = J delta`` with
``J = [Rz(y) Ry(p) e_x, Rz(y) e_y, e_z]`` (the ZYX angular-velocity map), so a bearing ``r``
computed with the nominal mounting and the IMU attitude ``R_NB`` is, in truth,
``r + e x r`` with ``e = R_NB J delta``. Linearised about the nominal mounting
(second-order terms are ``|delta|^2 / 2``: 4e-5 rad at 0.5 deg):

- vanishing point, unit ray ``r``:      ``r_z = (-r_y, r_x, 0) R_NB J delta - s``
- threshold direction, unit ``t``:      ``t_z = (-t_y, t_x, 0) R_NB J delta``
- epipolar, corner seen at frames j, k: ``-r_k.(T x r_j) = [(r_k x (T x r_j))^T R_NB,k
  + (r_j x (r_k x T))^T R_NB,j] J delta``  (T divided by its length).

The parameters ``theta = (delta, s)`` are constant, so the filter is recursive least squares in
information form (a Kalman filter without process noise; FilterPy's vocabulary: ``H``, ``R``,
``P``) from a Gaussian prior, with each frame's measurement variance propagated from the corner
pixel noise by finite differences, and a gate on the normalised innovation (a detector's stray
corner does not move the calibration).

What is observable (docs/estimation.md says it for users): roll comes from the threshold's direction
(and the epipolar constraint); pitch minus slope from the vanishing point; pitch and yaw alone
from the epipolar constraint, which needs parallax: it sharpens as the runway approaches
(``T / range`` grows). Yaw is also absorbed by the runway heading (d_F), so it is estimated only
to keep the epipolar constraint unbiased.

A camera.json so wrong that the vanishing point lies more than
:attr:`CalibrationParams.problem_deg` from the predicted horizon is a *calibration problem*: it
is reported (``MountCalibration.problem``) and the correction is not applied.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from visland.camera import CameraModel
from visland.features import batch_R_runway_from_body
from visland.frames import R_body_from_camera

__all__ = ["CalibrationParams", "MountCalibration", "estimate_mount_error", "batch_R_body_from_camera",
           "mount_error_jacobian"]

@dataclass(frozen=True)
class CalibrationParams:
    """Tuning of the self-calibration (:func:`estimate_mount_error`).

    Attributes
    ----------
    pixel_sigma_px : standard deviation of a corner's pixel coordinates (1 px: thesis 5.2.2.1).
    prior_mount_deg : prior standard deviation of each mounting angle's error.
    prior_slope_pct : prior standard deviation of the runway's slope (ICAO: at most 1-2 %).
    baseline_s : time between the two frames of an epipolar pair (longer: more parallax).
    gate_sigma : innovations beyond this many standard deviations are rejected.
    problem_deg : a mounting error estimated beyond this (roll or pitch) is a calibration problem.
    """

    pixel_sigma_px: float = 1.0
    prior_mount_deg: float = 3.0
    prior_slope_pct: float = 2.0
    baseline_s: float = 8.0
    gate_sigma: float = 5.0
    problem_deg: float = 3.0

    def __post_init__(self):
        for name in ("pixel_sigma_px", "prior_mount_deg", "prior_slope_pct", "baseline_s", "gate_sigma",
                     "problem_deg"):
            value = getattr(self, name)
            if not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0):
                raise ValueError(f"CalibrationParams.{name} must be a positive number, got {value!r}")


@dataclass
class MountCalibration:
    """The causal estimate after each frame.

    Attributes
    ----------
    t_s : (m,) frame times.
    mount_error_rad : (m, 3) estimated error of ``mount_rpy`` (roll, pitch, yaw) after the frame:
        the camera is mounted at ``camera.json``'s angles plus this.
    slope_pct : (m,) estimated runway slope, percent (uphill positive).
    sigma : (m, 4) standard deviations of (roll, pitch, yaw) in rad and of the slope in percent.
    n_used, n_rejected : measurements used and gated out (vanishing point, threshold, epipolar).
    problem : "" or one sentence describing a calibration problem (then ``applied`` is False).
    applied : whether the correction is fed to the observers.
    """

    t_s: np.ndarray
    mount_error_rad: np.ndarray
    slope_pct: np.ndarray
    sigma: np.ndarray
    n_used: dict = field(default_factory=dict)
    n_rejected: dict = field(default_factory=dict)
    problem: str = ""
    applied: bool = True

    def summary(self) -> dict:
        """The final estimate in degrees and percent (for run logs and metrics.json)."""
        err = np.degrees(self.mount_error_rad[-1])
        sig = self.sigma[-1]
        return {"mount_error_deg": {"roll": float(err[0]), "pitch": float(err[1]), "yaw": float(err[2])},
                "mount_error_sigma_deg": {"roll": float(math.degrees(sig[0])), "pitch": float(math.degrees(sig[1])),
                                          "yaw": float(math.degrees(sig[2]))},
                "slope_pct": float(self.slope_pct[-1]), "slope_sigma_pct": float(sig[3]),
                "n_used": dict(self.n_used), "n_rejected": dict(self.n_rejected),
                "applied": bool(self.applied), "problem": self.problem}

    def describe(self) -> str:
        s = self.summary()
        e, g = s["mount_error_deg"], s["mount_error_sigma_deg"]
        text = (f"self-calibration: mount error roll {e['roll']:+.3f} +- {g['roll']:.3f}, pitch {e['pitch']:+.3f} +- "
                f"{g['pitch']:.3f}, yaw {e['yaw']:+.3f} +- {g['yaw']:.3f} deg; runway slope "
                f"{s['slope_pct']:+.2f} +- {s['slope_sigma_pct']:.2f} %"
                f"{'' if self.applied else ' (NOT applied)'}")
        return text + (f"; CALIBRATION PROBLEM: {self.problem}" if self.problem else "")


def mount_error_jacobian(mount_rpy_rad) -> np.ndarray:
    """``J``: body-axes rotation vector of a small change of the ZYX mount angles (roll, pitch, yaw),
    shape (3, 3) for one mounting, (n, 3, 3) for an (n, 3) array:
    ``J = [Rz(y) Ry(p) e_x, Rz(y) e_y, e_z]``.

    Parameters
    ----------
    mount_rpy_rad : array_like, shape (3,) or (n, 3)
        The mounting's roll, pitch and yaw, radians.
    """
    mount = np.asarray(mount_rpy_rad, dtype=float)
    pitch, yaw = mount[..., 1], mount[..., 2]
    cp, sp, cy, sy = np.cos(pitch), np.sin(pitch), np.cos(yaw), np.sin(yaw)
    zero, one = np.zeros_like(pitch), np.ones_like(pitch)
    col_roll = np.stack([cy * cp, sy * cp, -sp], axis=-1)
    col_pitch = np.stack([-sy, cy, zero], axis=-1)
    col_yaw = np.stack([zero, zero, one], axis=-1)
    return np.stack([col_roll, col_pitch, col_yaw], axis=-1)


def batch_R_body_from_camera(mount_rpy_rad) -> np.ndarray:
    """:func:`visland.frames.R_body_from_camera` for an (n, 3) array of mountings, shape (n, 3, 3).

    Parameters
    ----------
    mount_rpy_rad : array_like, shape (n, 3)
        Roll, pitch and yaw of each mounting relative to the body, radians.

    Returns
    -------
    ndarray, shape (n, 3, 3)
    """
    mount = np.asarray(mount_rpy_rad, dtype=float)
    zero = R_body_from_camera((0.0, 0.0, 0.0))
    R = batch_R_runway_from_body(mount[:, 0], mount[:, 1], mount[:, 2])      # Rz(y) Ry(p) Rx(r)
    return R @ zero


# --------------------------------------------------------------------------- measurements
def _unit(v):
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def _homog(xy):
    return np.concatenate([xy, np.ones(xy.shape[:-1] + (1,))], axis=-1)


def _horizon_terms(near_uv, far_uv, R_NC, camera):
    """Elevations (NED z of the unit direction) of the runway's vanishing point and of the threshold's
    direction, and the directions themselves; inputs (n, 2, 2) pixels and (n, 3, 3)."""
    xy_n = _homog(camera.pixels_to_normalized(near_uv))
    xy_f = _homog(camera.pixels_to_normalized(far_uv))
    left = np.cross(xy_n[:, 0], xy_f[:, 0])
    right = np.cross(xy_n[:, 1], xy_f[:, 1])
    d_C = np.cross(left, right)
    d_C = d_C * np.where(d_C[:, 2:3] < 0, -1.0, 1.0)         # towards the runway's far end (in front)
    d_C = _unit(d_C)
    m_thr = np.cross(xy_n[:, 0], xy_n[:, 1])
    t_C = _unit(np.cross(d_C, m_thr))
    d_N = np.einsum("nij,nj->ni", R_NC, d_C)
    t_N = np.einsum("nij,nj->ni", R_NC, t_C)
    return d_N, t_N


def _bearings(uv, R_NC, camera):
    return _unit(np.einsum("nij,nkj->nki", R_NC, _homog(camera.pixels_to_normalized(uv))))


#: A pass re-linearises a frame's measurements at the previous pass's estimate once its standard
#: deviations (roll, pitch, yaw) are under this (degrees); before, at the nominal mounting.
LINEARISE_SIGMA_DEG = 0.1

#: Frames whose bearings are averaged into the epipolar constraint's H (see _measurements).
H_WINDOW = 8


def _causal_mean_bearings(near, R_NC, camera, window: int = H_WINDOW):
    """Unit mean NED bearing (m, 2, 3) of each threshold corner over the ``window`` frames before each
    frame (the frame itself excluded), NaN where none of them measured the corners."""
    m = len(near)
    ok = np.isfinite(near).all(axis=(1, 2))
    r = np.zeros((m, 2, 3))
    if ok.any():
        r[ok] = _bearings(near[ok], R_NC[ok], camera)
    c = np.concatenate([np.zeros((1, 2, 3)), np.cumsum(r, axis=0)])
    n = np.concatenate([[0], np.cumsum(ok)])
    idx = np.arange(m)
    lo = np.maximum(idx - window, 0)
    total = c[idx] - c[lo]
    count = (n[idx] - n[lo])[:, None, None]
    with np.errstate(invalid="ignore", divide="ignore"):
        mean = np.where(count > 0, total / np.maximum(count, 1), np.nan)
        return mean / np.linalg.norm(mean, axis=-1, keepdims=True)


def _epipolar(r_k, r_j, T_unit):
    """``r_k . (T x r_j)`` for bearings (n, 2, 3) and unit translations (n, 3)."""
    return np.einsum("nki,nki->nk", r_k, np.cross(T_unit[:, None, :], r_j))


def _rows(vectors, R_NB, J):
    """``vectors (n, [k,] 3)`` as rows of H on delta: ``v^T R_NB J``."""
    if vectors.ndim == 2:
        return np.einsum("ni,nij,jk->nk", vectors, R_NB, J)
    return np.einsum("nqi,nij,jk->nqk", vectors, R_NB, J)


def _measurements(near, far, R_NB, R_BC, J, k_idx, j_idx, T_unit, camera, sigma_px, with_variance):
    """Per frame: ``y (m, 4)``, ``H (m, 4, 4)`` (rows on ``theta - theta_lin``) and the variance ``(m, 4)``
    of the vanishing point, threshold and the two epipolar constraints, linearised at the mounting
    ``R_BC (m, 3, 3)`` whose Euler-angle Jacobian is ``J (m, 3, 3)``; NaN where not measured."""
    m = len(near)
    R_NC = R_NB @ R_BC
    RJ = R_NB @ J
    y = np.full((m, 4), np.nan)
    var = np.full((m, 4), np.nan)
    H = np.zeros((m, 4, 4))
    h_px = 0.5
    four = np.isfinite(near).all(axis=(1, 2)) & np.isfinite(far).all(axis=(1, 2))
    if four.any():
        nf, ff, Rf = near[four], far[four], R_NC[four]
        d_N, t_N = _horizon_terms(nf, ff, Rf, camera)
        y0 = np.stack([d_N[:, 2], t_N[:, 2]], axis=1)
        y[four, :2] = y0
        if with_variance:
            v = np.zeros_like(y0)
            for which in range(2):                       # finite differences over the 8 pixel coordinates
                for c in range(2):
                    for a in range(2):
                        n2, f2 = nf.copy(), ff.copy()
                        (n2 if which == 0 else f2)[:, c, a] += h_px
                        d2, t2 = _horizon_terms(n2, f2, Rf, camera)
                        v += ((np.stack([d2[:, 2], t2[:, 2]], axis=1) - y0) / h_px * sigma_px) ** 2
            var[four, :2] = v
        zeros = np.zeros(len(d_N))
        H[four, 0, :3] = np.einsum("ni,nik->nk", np.stack([-d_N[:, 1], d_N[:, 0], zeros], axis=1), RJ[four])
        H[four, 0, 3] = -1.0
        H[four, 1, :3] = np.einsum("ni,nik->nk", np.stack([-t_N[:, 1], t_N[:, 0], zeros], axis=1), RJ[four])
    if len(k_idx):
        # both frames of a pair at frame k's linearisation point (one mounting, one J)
        R_NC_j = R_NB[j_idx] @ R_BC[k_idx]
        RJ_j = R_NB[j_idx] @ J[k_idx]
        r_k = _bearings(near[k_idx], R_NC[k_idx], camera)
        r_j = _bearings(near[j_idx], R_NC_j, camera)
        z0 = _epipolar(r_k, r_j, T_unit)
        y[k_idx, 2:] = -z0
        if with_variance:
            v = np.zeros_like(z0)
            for c in range(2):
                for a in range(2):
                    for which in range(2):
                        uv = (near[k_idx] if which == 0 else near[j_idx]).copy()
                        uv[:, c, a] += h_px
                        rr = _bearings(uv, R_NC[k_idx] if which == 0 else R_NC_j, camera)
                        z2 = _epipolar(rr, r_j, T_unit) if which == 0 else _epipolar(r_k, rr, T_unit)
                        v += ((z2 - z0) / h_px * sigma_px) ** 2
            # a frame takes part in two pairs (as k and as j): the pairs' errors are correlated, so
            # each counts as half an independent measurement
            var[k_idx, 2:] = 2.0 * v
        # H from the mean bearings of the H_WINDOW frames before k and before j: the same geometry
        # to a fraction of a second, but noise independent of y's (an instrumental variable: H
        # from the frame's own noisy bearings correlates with y and biases the estimate by
        # noise^2 / parallax, 0.05 deg at 1 px with a 3 s baseline) and averaged (far away the
        # parallax is small, and one frame's bearings make a weak, heavy-tailed instrument)
        smooth = _causal_mean_bearings(near, R_NB @ R_BC, camera)
        ri_k = np.where(np.isfinite(smooth[k_idx]), smooth[k_idx], r_k)
        ri_j = np.where(np.isfinite(smooth[j_idx]), smooth[j_idx], r_j)
        a_k = np.cross(ri_k, np.cross(T_unit[:, None, :], ri_j))          # r_k x (T x r_j)
        a_j = np.cross(ri_j, np.cross(ri_k, T_unit[:, None, :]))          # r_j x (r_k x T)
        H[k_idx, 2:, :3] = np.einsum("nqi,nik->nqk", a_k, RJ[k_idx]) + np.einsum("nqi,nik->nqk", a_j, RJ_j)
    return y, H, var


_NAMES = ("vanishing point", "threshold", "epipolar", "epipolar")


def _filter(y, H, var, prior, gate_sigma):
    """Gated recursive least squares in information form; returns theta and sigma after each frame and the counts."""
    m = len(y)
    info = np.diag(1.0 / prior ** 2)
    vec = np.zeros(len(prior))
    theta = np.zeros(len(prior))
    P = np.diag(prior ** 2)
    out_theta = np.zeros((m, len(prior)))
    out_sigma = np.zeros((m, len(prior)))
    used = {"vanishing point": 0, "threshold": 0, "epipolar": 0}
    rejected = dict(used)
    gate2 = gate_sigma ** 2
    usable = np.isfinite(y) & np.isfinite(var) & (var > 0)
    sigma = np.sqrt(np.diag(P))
    for f in range(m):
        cols = np.nonzero(usable[f])[0]
        if cols.size:
            Hf = H[f, cols]
            yf = y[f, cols]
            rf = var[f, cols]
            nu = yf - Hf @ theta
            s = rf + np.einsum("qi,ij,qj->q", Hf, P, Hf)
            keep = nu * nu <= gate2 * s
            for q, c in enumerate(cols):
                (used if keep[q] else rejected)[_NAMES[c]] += 1
            if keep.any():
                Hk, yk, rk = Hf[keep], yf[keep], rf[keep]
                info = info + (Hk.T / rk) @ Hk
                vec = vec + (Hk.T / rk) @ yk
                P = np.linalg.inv(info)
                theta = P @ vec
                sigma = np.sqrt(np.diag(P))
        out_theta[f] = theta
        out_sigma[f] = sigma
    return out_theta, out_sigma, used, rejected


def estimate_mount_error(t_s, near_uv_px, far_uv_px, roll_rad, pitch_rad, heading_rad, position_ned_m,
                         camera: CameraModel, params: CalibrationParams | None = None,
                         passes: int = 3) -> MountCalibration:
    """Causal estimate of the mounting error and the runway slope after each frame (module docstring).

    Parameters
    ----------
    t_s : (m,) frame times.
    near_uv_px, far_uv_px : (m, 2, 2) pixels of the threshold corners (P', P'') and of the
        runway-end corners (left, right), NaN where not measured.
    roll_rad, pitch_rad, heading_rad : (m,) inertial attitude at the frames.
    position_ned_m : (m, 3) the inertial velocity integrated to the frame times (any origin).
    camera : the nominal camera (``camera.json``).
    params : :class:`CalibrationParams` (default its defaults).
    passes : the epipolar constraint's second-order terms are not negligible against its
        first-order ones (the two bearings nearly coincide), so the measurements are
        re-linearised at the previous pass's causal estimate (the one of the frame before:
        still causal) once it is known to LINEARISE_SIGMA_DEG; 3 passes bring the bias far
        under the noise.
    """
    params = params or CalibrationParams()
    t_s = np.asarray(t_s, dtype=float)
    m = len(t_s)
    near = np.asarray(near_uv_px, dtype=float)
    far = np.asarray(far_uv_px, dtype=float)
    R_NB = batch_R_runway_from_body(roll_rad, pitch_rad, heading_rad)
    mount0 = np.asarray(camera.mount_rpy_rad, dtype=float)

    # epipolar pairs: frame k with the last frame at least baseline_s earlier, both with P' and P''
    pts = np.isfinite(near).all(axis=(1, 2))
    ref = np.searchsorted(t_s, t_s - params.baseline_s, side="right") - 1
    pair = pts & (ref >= 0)
    pair[pair] &= pts[ref[pair]]
    k_idx = np.nonzero(pair)[0]
    j_idx = ref[k_idx]
    T = position_ned_m[k_idx] - position_ned_m[j_idx]
    length = np.linalg.norm(T, axis=1)
    ok = length > 1.0
    k_idx, j_idx, T = k_idx[ok], j_idx[ok], T[ok] / length[ok, None]

    prior = np.array([math.radians(params.prior_mount_deg)] * 3 + [params.prior_slope_pct / 100.0])
    lin = np.zeros((m, 3))                    # linearisation point of each frame (mount error)
    var = None
    for _ in range(max(1, passes)):
        mounts = mount0[None, :] + lin
        R_BC = batch_R_body_from_camera(mounts)
        J = mount_error_jacobian(mounts)
        y, H, v = _measurements(near, far, R_NB, R_BC, J, k_idx, j_idx, T, camera, params.pixel_sigma_px,
                                with_variance=var is None)
        var = v if var is None else var
        y = y + np.einsum("nqk,nk->nq", H[:, :, :3], lin)
        theta, sigma, used, rejected = _filter(y, H, var, prior, params.gate_sigma)
        # re-linearise only where the estimate is already good: far away it swings by a degree,
        # and a row linearised a degree off carries second-order errors larger than its noise
        # (the frames before the first good estimate at that estimate: their outputs, from before
        # it, are never applied to the observers, which wait for CALIBRATION_SETTLED_RAD)
        good = sigma[:-1, :3].max(axis=1) <= math.radians(LINEARISE_SIGMA_DEG)
        first = int(np.argmax(good)) if good.any() else len(good)
        lin = np.concatenate([np.zeros((1, 3)), np.where(good[:, None], theta[:-1, :3], 0.0)])
        if first < len(good):
            lin[:first + 1] = theta[first, :3]
    sigma[:, 3] *= 100.0
    calibration = MountCalibration(t_s=t_s, mount_error_rad=theta[:, :3], slope_pct=100.0 * theta[:, 3],
                                   sigma=sigma, n_used=used, n_rejected=rejected)
    worst = np.degrees(np.abs(theta[:, :2])).max(axis=1)
    settled = sigma[:, :2].max(axis=1) < math.radians(0.5)
    bad = settled & (worst > params.problem_deg)
    if bad.any():
        f = int(np.argmax(bad))
        e = np.degrees(theta[-1, :2])
        calibration.problem = (f"the runway's vanishing point and threshold lie far from the horizon that camera.json's "
                               f"mount_rpy_deg and the inertial attitude predict (mount error roll {e[0]:+.2f}, pitch "
                               f"{e[1]:+.2f} deg, more than {params.problem_deg:g} deg from t = {t_s[f]:.2f} s): check "
                               f"camera.json; no correction applied")
        calibration.applied = False
    return calibration
