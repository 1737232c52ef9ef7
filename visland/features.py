"""Runway image features: exact projection ("analyse d'images simulée", thesis 5.1.2),
their dynamics (thesis 3.24, 3.29, 3.37/3.39) and the observability indices (3.30, 3.40).

Conventions: see :mod:`visland.camera` (pixels with (0, 0) at the centre of the top-left
pixel, normalised coordinates ``x = (u - cx)/fx``, lines ``x cos(theta) + y sin(theta) = rho``
with theta in [-pi/2, pi/2)) and :mod:`visland.frames` (R runway, C camera, V virtual).

Everything here is vectorised over frames: arrays carry a leading frame axis ``n``.

Derivations (re-done for the SPEC frames; the tests check each one by finite differences
on a flown trajectory):

Points in the virtual frame (thesis 3.23-3.24). A runway point P has virtual coordinates
``p_V = p_R(P) - c_R`` (runway axes, origin at the camera centre c). With
``y_v = (X_v/Z_v, Y_v/Z_v)`` and ``eta = 1/Z_v = 1/dH`` (runway points have Z_v = dH)::

    y_v1' = (v3 y_v1 - v1) eta,   y_v2' = (v3 y_v2 - v2) eta,   eta' = v3 eta^2      (3.24)

with ``v = v_R`` the camera velocity in the runway axes (z down). Two threshold corners
share eta (3.29); the observability term is ``O = sum (v3 y1 - v1)^2 + (v3 y2 - v2)^2``
over both points (3.30).

Lines (thesis 3.32-3.39). The image line is the interpretation plane through the camera
centre, normal ``m = (cos theta, sin theta, -rho)`` in C. For a static world line of
direction d through X0, ``M = X0 x d`` obeys ``M' = -v_C x d - w_C x M`` (camera velocity
v_C, angular velocity w_C, both in C). The runway plane is ``n . X = dH`` with ``n`` the
runway down axis in C (thesis 3.33, ``n = cR0 [0 0 1]``). Taking d along ``n x m`` and X0
the foot of the perpendicular from C gives ``M = -dH m / |n x m|``: M points *against*
m, which flips the sign of the translational terms. With ``eta = 1/dH > 0`` and
``s = cos(theta) v0 + sin(theta) v1 - rho v2``::

    theta' = -rho cos(theta) w0 - rho sin(theta) w1 - w2 - eta (n0 sin(theta) - n1 cos(theta)) s
    rho'   = (1 + rho^2)(sin(theta) w0 - cos(theta) w1) - eta (n0 rho cos(theta) + n1 rho sin(theta) + n2) s

which is thesis 3.37 with ``(a_p, b_p, c) = n`` and ``d_p = -dH`` (the thesis's plane
``a i + b j + c k + d_p = 0``, normal pointing down, has ``d_p = -dH``); Chaumette's
interaction matrix with plane ``n . X - dH = 0`` gives the same. Two edges stacked give 3.39
and the observability term 3.40 is the squared norm of the four eta coefficients.

Heading from the vanishing point (seed 001 appendix, eq. 18-19). ``d_F`` is the signed
pixel distance along the horizon from Q (the horizon at u = cx) to the vanishing point of
the runway direction, positive to the right. The horizon depends only on roll, pitch and the
mounting; turning d_F back into dpsi back-projects the vanishing point and reads its
azimuth in the level heading frame (no closed form needed, any mounting). With no mounting
rotation this reproduces ``d_F = fx (tan(phi) tan(theta) - tan(dpsi)/cos(theta))``.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from visland.camera import CameraModel, intersect_lines, line_through_points, wrap_line_chart
from visland.frames import R_body_from_camera
from visland.runway import CORNER_NAMES, Runway

__all__ = [
    "batch_R_runway_from_body",
    "batch_R_camera_from_runway",
    "project_runway_corners",
    "runway_lines",
    "vanishing_point_xy",
    "horizon_line",
    "dF_from_vanishing_point",
    "dpsi_from_dF",
    "virtual_from_pixels",
    "point_virtual_dynamics",
    "line_dynamics_terms",
    "observability_points",
    "observability_lines",
    "IdealFeatures",
    "ideal_features",
]


# --------------------------------------------------------------------------- rotations
def _batch_rot(axis: int, angle) -> np.ndarray:
    angle = np.asarray(angle, dtype=float)
    c, s = np.cos(angle), np.sin(angle)
    out = np.zeros(angle.shape + (3, 3))
    i, j = [(1, 2), (2, 0), (0, 1)][axis]
    out[..., axis, axis] = 1.0
    out[..., i, i] = c
    out[..., j, j] = c
    out[..., i, j] = -s
    out[..., j, i] = s
    return out


def batch_R_runway_from_body(roll_rad, pitch_rad, dpsi_rad) -> np.ndarray:
    """``Rz(dpsi) Ry(pitch) Rx(roll)`` for arrays of angles.

    Parameters
    ----------
    roll_rad, pitch_rad : array_like, shape (...)
        Body roll and pitch, radians.
    dpsi_rad : array_like, shape (...)
        Heading deviation ``psi - psi_rwy`` from the runway axis, radians.

    Returns
    -------
    ndarray, shape (..., 3, 3)
        ``R_runway_from_body``: body coordinates to runway coordinates (R: x along the
        centreline, y right, z down).
    """
    return _batch_rot(2, dpsi_rad) @ _batch_rot(1, pitch_rad) @ _batch_rot(0, roll_rad)


def batch_R_camera_from_runway(roll_rad, pitch_rad, dpsi_rad, mount_rpy_rad) -> np.ndarray:
    """``R_camera_from_runway`` for arrays of attitudes relative to the runway.

    Parameters
    ----------
    roll_rad, pitch_rad, dpsi_rad : array_like, shape (...)
        Attitude of the body relative to the runway: roll, pitch and heading deviation
        ``psi - psi_rwy``, radians.
    mount_rpy_rad : sequence of 3 floats
        The camera's roll, pitch and yaw relative to the body, radians.

    Returns
    -------
    ndarray, shape (..., 3, 3)
        Runway coordinates to OpenCV camera coordinates (x right, y down, z forward).
    """
    R_rb = batch_R_runway_from_body(roll_rad, pitch_rad, dpsi_rad)
    R_rc = R_rb @ R_body_from_camera(mount_rpy_rad)
    return np.swapaxes(R_rc, -1, -2)


# --------------------------------------------------------------------------- projection
def project_runway_corners(R_camera_from_runway, p_camera_runway_m, runway: Runway, camera: CameraModel):
    """Pixels of the four corners (:data:`visland.runway.CORNER_NAMES` order).

    Parameters
    ----------
    R_camera_from_runway : ndarray, shape (n, 3, 3)
        Rotation from the runway frame R to the camera frame C, one per frame.
    p_camera_runway_m : ndarray, shape (n, 3)
        Camera centre c in R (metres), one row per frame.
    runway : visland.runway.Runway
        Its corners (:meth:`Runway.corners_runway_m`).
    camera : visland.camera.CameraModel
        Intrinsics (and lens) used to project.

    Returns
    -------
    uv : ndarray, shape (n, 4, 2)
        Pixels (SPEC: (0, 0) at the centre of the top-left pixel, u right, v down), NaN behind
        the camera.
    in_front : ndarray of bool, shape (n, 4)
        In front of the camera.
    visible : ndarray of bool, shape (n, 4)
        In front and inside the image.
    """
    corners = runway.corners_runway_m()                                     # (4, 3)
    rel = corners[None, :, :] - np.asarray(p_camera_runway_m)[:, None, :]   # (n, 4, 3) in R axes
    p_C = np.einsum("nij,nkj->nki", R_camera_from_runway, rel)
    uv, in_front = camera.project(p_C)
    visible = in_front & camera.in_image(uv)
    return uv, in_front, visible


def runway_lines(R_camera_from_runway, p_camera_runway_m, runway: Runway) -> dict:
    """SPEC ``(rho, theta)`` of the left edge, right edge and centre line.

    Parameters
    ----------
    R_camera_from_runway : ndarray, shape (n, 3, 3)
        Runway-to-camera rotation at each frame.
    p_camera_runway_m : ndarray, shape (n, 3)
        Camera centre in the runway frame, metres.
    runway : visland.runway.Runway
        Its edge and centre lines (:meth:`Runway.edge_lines_runway_m`).

    Returns
    -------
    dict of str to (ndarray, ndarray)
        ``{"left", "right", "center"}`` -> ``(rho, theta_rad)``, each shape (n,): lines
        ``x cos(theta) + y sin(theta) = rho`` in normalised coordinates, theta in [-pi/2, pi/2).
    """
    out = {}
    for name, (point_R, direction_R) in runway.edge_lines_runway_m().items():
        rel = point_R[None, :] - np.asarray(p_camera_runway_m)
        X0 = np.einsum("nij,nj->ni", R_camera_from_runway, rel)
        d = np.einsum("nij,j->ni", R_camera_from_runway, direction_R)
        m = np.cross(X0, d)                        # interpretation-plane normal: m . (x, y, 1) = 0
        h = np.hypot(m[:, 0], m[:, 1])
        out[name] = wrap_line_chart(-m[:, 2] / h, np.arctan2(m[:, 1], m[:, 0]))
    return out


def vanishing_point_xy(R_camera_from_runway, direction_runway=None) -> np.ndarray:
    """Normalised image of the runway direction.

    Parameters
    ----------
    R_camera_from_runway : ndarray, shape (n, 3, 3)
        Runway-to-camera rotation at each frame.
    direction_runway : array_like, shape (3,), optional
        The centreline's direction in R (default runway +x, a level runway;
        :meth:`visland.runway.Runway.direction_runway` for a sloped one).

    Returns
    -------
    ndarray, shape (n, 2)
        Normalised coordinates ``(x, y)`` of the vanishing point.
    """
    R = np.asarray(R_camera_from_runway)
    d = R[..., :, 0] if direction_runway is None else R @ np.asarray(direction_runway, dtype=float)
    return d[..., :2] / d[..., 2:3]


def horizon_line(R_camera_from_runway) -> tuple[np.ndarray, np.ndarray]:
    """SPEC ``(rho, theta)`` of the horizon: directions orthogonal to the down axis ``n``.

    Parameters
    ----------
    R_camera_from_runway : ndarray, shape (..., 3, 3)
        Runway-to-camera rotation (only roll, pitch and the mounting matter).

    Returns
    -------
    rho, theta_rad : ndarray, shape (...)
        The horizon ``x cos(theta) + y sin(theta) = rho`` in normalised coordinates.
    """
    n = np.asarray(R_camera_from_runway)[..., :, 2]
    h = np.hypot(n[..., 0], n[..., 1])
    return wrap_line_chart(-n[..., 2] / h, np.arctan2(n[..., 1], n[..., 0]))


def _horizon_geometry(horizon_rho, horizon_theta, camera: CameraModel):
    """Q (pixels, where the horizon crosses u = cx) and the unit horizon direction in pixels (u > 0)."""
    c, s = np.cos(horizon_theta), np.sin(horizon_theta)
    with np.errstate(divide="ignore", invalid="ignore"):
        y_q = np.where(np.abs(s) > 1e-12, horizon_rho / s, np.nan)   # x = 0 on the line
    q_px = np.stack([np.full_like(y_q, camera.cx), camera.fy * y_q + camera.cy], axis=-1)
    # direction along the line in normalised coords is (-s, c); in pixels (-fx s, fy c)
    t = np.stack([-camera.fx * s, camera.fy * c], axis=-1)
    t = t * np.where(t[..., 0:1] < 0, -1.0, 1.0)
    t = t / np.linalg.norm(t, axis=-1, keepdims=True)
    return q_px, t


def dF_from_vanishing_point(vp_xy, horizon_rho, horizon_theta, camera: CameraModel) -> np.ndarray:
    """Signed pixel distance along the horizon from Q to the vanishing point (SPEC d_F).

    The vanishing point is projected on the horizon, so a measured point slightly off the
    horizon still gives a d_F.

    Parameters
    ----------
    vp_xy : array_like, shape (..., 2)
        Vanishing point, normalised coordinates.
    horizon_rho, horizon_theta : array_like, shape (...)
        The horizon line (SPEC chart, normalised coordinates; theta in radians).
    camera : visland.camera.CameraModel
        Intrinsics (pixels).

    Returns
    -------
    ndarray, shape (...)
        d_F in pixels, from Q (the horizon at u = cx) to the vanishing point, positive to the
        right (seed 001 eq. 18).
    """
    q_px, t = _horizon_geometry(horizon_rho, horizon_theta, camera)
    vp_px = camera.normalized_to_pixels(vp_xy)
    return np.sum((vp_px - q_px) * t, axis=-1)


def dpsi_from_dF(dF_px, roll_rad, pitch_rad, camera: CameraModel) -> np.ndarray:
    """Heading deviation (rad) from d_F, the inertial roll and pitch and the camera mounting.

    Inverse of the d_F measurement (seed 001 eq. 19, for any mounting): the vanishing point
    is ``Q + d_F t`` on the horizon; back-projected into the level heading frame L
    (body with roll and pitch undone: ``R_L_from_camera = Ry(pitch) Rx(roll) R_body_from_camera``)
    its direction is ``(cos dpsi, -sin dpsi, 0)``.

    Parameters
    ----------
    dF_px : array_like, shape (...)
        d_F in pixels (:func:`dF_from_vanishing_point`).
    roll_rad, pitch_rad : array_like, shape (...)
        Inertial roll and pitch, radians.
    camera : visland.camera.CameraModel
        Intrinsics and mounting.

    Returns
    -------
    ndarray, shape (...)
        ``dpsi = psi - psi_rwy`` in radians.
    """
    roll = np.asarray(roll_rad, dtype=float)
    pitch = np.asarray(pitch_rad, dtype=float)
    dF = np.asarray(dF_px, dtype=float)
    R_cr0 = batch_R_camera_from_runway(roll, pitch, np.zeros_like(roll), camera.mount_rpy_rad)
    h_rho, h_theta = horizon_line(R_cr0)
    q_px, t = _horizon_geometry(h_rho, h_theta, camera)
    vp_px = q_px + dF[..., None] * t
    ray_C = np.concatenate([camera.pixels_to_normalized(vp_px), np.ones(dF.shape + (1,))], axis=-1)
    ray_L = np.einsum("...ji,...j->...i", R_cr0, ray_C)    # R_L_from_camera = R_camera_from_runway(dpsi=0)^T
    return np.arctan2(-ray_L[..., 1], ray_L[..., 0])


def virtual_from_pixels(uv, R_runway_from_camera, camera: CameraModel) -> np.ndarray:
    """Virtual-frame coordinates ``y_v = (X_v/Z_v, Y_v/Z_v)`` of pixel points (thesis 3.23).

    Parameters
    ----------
    uv : array_like, shape (n, k, 2)
        k pixel points per frame (SPEC pixel convention).
    R_runway_from_camera : ndarray, shape (n, 3, 3)
        Camera-to-runway rotation at each frame (the virtual frame V has the runway's axes).
    camera : visland.camera.CameraModel
        Intrinsics (pixels to normalised coordinates).

    Returns
    -------
    ndarray, shape (n, k, 2)
        ``y_v``, dimensionless.
    """
    uv = np.asarray(uv, dtype=float)
    xy = camera.pixels_to_normalized(uv)
    ray_C = np.concatenate([xy, np.ones(xy.shape[:-1] + (1,))], axis=-1)
    ray_V = np.einsum("nij,nkj->nki", R_runway_from_camera, ray_C)
    return ray_V[..., :2] / ray_V[..., 2:3]


# --------------------------------------------------------------------------- dynamics
def point_virtual_dynamics(y_v, eta, v_runway_mps) -> tuple[np.ndarray, np.ndarray]:
    """Thesis 3.24 / 3.29: time derivatives of virtual-frame points and of ``eta = 1/dH``.

    Parameters
    ----------
    y_v : array_like, shape (..., k, 2)
        Virtual coordinates of k runway points.
    eta : array_like, shape (...)
        Inverse height ``1/dH``, 1/m.
    v_runway_mps : array_like, shape (..., 3)
        Camera velocity in runway axes (z down), m/s.

    Returns
    -------
    y_v_dot : ndarray, shape (..., k, 2)
        ``Phi * eta`` with ``Phi = v3 y - v12`` (the observability terms of 3.26 / 3.30), 1/s.
    eta_dot : ndarray, shape (...)
        ``v3 eta^2``, 1/(m s).
    """
    y_v = np.asarray(y_v, dtype=float)
    v = np.asarray(v_runway_mps, dtype=float)
    eta = np.asarray(eta, dtype=float)
    phi = v[..., None, 2:3] * y_v - v[..., None, 0:2]
    return phi * eta[..., None, None], v[..., 2] * eta ** 2


def line_dynamics_terms(rho, theta, v_camera_mps, omega_camera_rps, n_camera) -> tuple[np.ndarray, np.ndarray]:
    """Thesis 3.37 in SPEC frames: ``(theta', rho') = g + Phi * eta`` with ``eta = 1/dH > 0``.

    See the module docstring for the derivation and the sign of Phi.

    Parameters
    ----------
    rho, theta : array_like, shape (...)
        Line in the SPEC chart (normalised coordinates; theta in radians).
    v_camera_mps : array_like, shape (..., 3)
        Camera velocity in C, m/s.
    omega_camera_rps : array_like, shape (..., 3)
        Camera angular velocity in C, rad/s.
    n_camera : array_like, shape (..., 3)
        Runway down axis in C (thesis 3.33), unit vector.

    Returns
    -------
    g : ndarray, shape (..., 2)
        The rotational terms, ordered (theta, rho), per second.
    Phi : ndarray, shape (..., 2)
        The coefficients of eta, ordered (theta, rho), m/s.
    """
    rho = np.asarray(rho, dtype=float)
    c, s = np.cos(theta), np.sin(theta)
    v = np.asarray(v_camera_mps, dtype=float)
    w = np.asarray(omega_camera_rps, dtype=float)
    n = np.asarray(n_camera, dtype=float)
    g_theta = -rho * c * w[..., 0] - rho * s * w[..., 1] - w[..., 2]
    g_rho = (1.0 + rho ** 2) * (s * w[..., 0] - c * w[..., 1])
    speed = c * v[..., 0] + s * v[..., 1] - rho * v[..., 2]
    phi_theta = -(n[..., 0] * s - n[..., 1] * c) * speed
    phi_rho = -(n[..., 0] * rho * c + n[..., 1] * rho * s + n[..., 2]) * speed
    return np.stack([g_theta, g_rho], axis=-1), np.stack([phi_theta, phi_rho], axis=-1)


def observability_points(y_v, v_runway_mps) -> np.ndarray:
    """Thesis 3.30: ``sum over points of (v3 y1 - v1)^2 + (v3 y2 - v2)^2``, in (m/s)^2.

    Parameters
    ----------
    y_v : array_like, shape (..., k, 2)
        Virtual coordinates of the k points.
    v_runway_mps : array_like, shape (..., 3)
        Camera velocity in runway axes (z down), m/s.

    Returns
    -------
    ndarray, shape (...)
        The observability index, (m/s)^2.
    """
    phi = np.asarray(v_runway_mps)[..., None, 2:3] * np.asarray(y_v) - np.asarray(v_runway_mps)[..., None, 0:2]
    return np.sum(phi ** 2, axis=(-1, -2))


def observability_lines(lines, v_camera_mps, omega_camera_rps, n_camera) -> np.ndarray:
    """Thesis 3.40: squared norm of the eta coefficients of the stacked edge dynamics (3.39).

    Parameters
    ----------
    lines : iterable of (rho, theta)
        The edges, each in the SPEC chart (arrays of shape (...)).
    v_camera_mps : array_like, shape (..., 3)
        Camera velocity in C, m/s.
    omega_camera_rps : array_like, shape (..., 3)
        Camera angular velocity in C, rad/s.
    n_camera : array_like, shape (..., 3)
        Runway down axis in C.

    Returns
    -------
    ndarray, shape (...)
        The observability index, (m/s)^2.
    """
    total = 0.0
    for rho, theta in lines:
        _, phi = line_dynamics_terms(rho, theta, v_camera_mps, omega_camera_rps, n_camera)
        total = total + np.sum(phi ** 2, axis=-1)
    return total


# --------------------------------------------------------------------------- ideal features
@dataclass
class IdealFeatures:
    """Image features of each frame (the ``labels.csv`` content).

    Attributes
    ----------
    t_s : ndarray, shape (n,)
        Frame times, seconds.
    corners_uv : ndarray, shape (n, 4, 2)
        Corner pixels in :data:`visland.runway.CORNER_NAMES` order (NaN behind the camera).
    corners_visible : ndarray of bool, shape (n, 4)
        In front of the camera and inside the image.
    lines : dict of str to (ndarray, ndarray)
        ``{"left", "right", "center"}`` -> ``(rho, theta_rad)`` SPEC lines, each (n,).
    dF_px : ndarray, shape (n,)
        d_F, pixels (seed 001 eq. 18).
    dpsi_rad : ndarray, shape (n,)
        Heading deviation recovered from d_F with the *nominal* camera and the inertial attitude.
    yv_near : ndarray, shape (n, 2, 2)
        Virtual coordinates of P' and P'' (thesis 3.23) computed from the pixels the same way.
    obs_points, obs_lines : ndarray, shape (n,)
        Observability indices 3.30 and 3.40 on the true motion, (m/s)^2.
    """

    t_s: np.ndarray
    corners_uv: np.ndarray
    corners_visible: np.ndarray
    lines: dict
    dF_px: np.ndarray
    dpsi_rad: np.ndarray
    yv_near: np.ndarray
    obs_points: np.ndarray
    obs_lines: np.ndarray

    def __len__(self):
        return len(self.t_s)

    def as_columns(self) -> dict:
        """Columns of the SPEC labels schema (plus the documented extras), SI angles in degrees/rad as named."""
        cols = {"t_s": self.t_s}
        for k, name in enumerate(CORNER_NAMES):
            cols[f"{name}_u_px"] = self.corners_uv[:, k, 0]
            cols[f"{name}_v_px"] = self.corners_uv[:, k, 1]
        for name in ("left", "right", "center"):
            cols[f"{name}_rho"] = self.lines[name][0]
            cols[f"{name}_theta_rad"] = self.lines[name][1]
        cols["dF_px"] = self.dF_px
        cols["dpsi_deg"] = np.degrees(self.dpsi_rad)
        for k, name in enumerate(CORNER_NAMES):
            cols[f"{name}_visible"] = self.corners_visible[:, k].astype(int)
        cols["yv1_near_left"] = self.yv_near[:, 0, 0]
        cols["yv2_near_left"] = self.yv_near[:, 0, 1]
        cols["yv1_near_right"] = self.yv_near[:, 1, 0]
        cols["yv2_near_right"] = self.yv_near[:, 1, 1]
        cols["obs_points"] = self.obs_points
        cols["obs_lines"] = self.obs_lines
        return cols


def ideal_features(states, runway: Runway, camera: CameraModel, camera_true: CameraModel | None = None,
                   imu_roll_rad=None, imu_pitch_rad=None, pixel_noise_px: float = 0.0,
                   rng: np.random.Generator | None = None) -> IdealFeatures:
    """Exact image features along a trajectory (thesis 5.1.2, "analyse d'images simulée").

    Parameters
    ----------
    states : :class:`visland.flight.FrameStates` at the camera frame times (truth).
    runway : the runway seen.
    camera : the nominal camera (what the estimator is told, ``camera.json``).
    camera_true : the camera as actually mounted (nominal plus calibration error); default
        ``camera``. Pixels are formed with it.
    imu_roll_rad, imu_pitch_rad : inertial attitude used to turn d_F into dpsi and pixels
        into virtual coordinates (default: the true attitude).
    pixel_noise_px : standard deviation of white Gaussian noise added to each corner
        coordinate (thesis 5.2.2.1: 1 px, 5 px); the lines are then the lines through the
        noisy corners and d_F comes from their intersection.
    rng : seeded generator for the noise (required when ``pixel_noise_px > 0``).
    """
    camera_true = camera_true or camera
    roll = states.roll_rad if imu_roll_rad is None else np.asarray(imu_roll_rad)
    pitch = states.pitch_rad if imu_pitch_rad is None else np.asarray(imu_pitch_rad)
    R_cr = batch_R_camera_from_runway(states.roll_rad, states.pitch_rad, states.dpsi_rad, camera_true.mount_rpy_rad)
    uv, in_front, visible = project_runway_corners(R_cr, states.p_runway_m, runway, camera_true)
    lines = runway_lines(R_cr, states.p_runway_m, runway)
    vp_xy = vanishing_point_xy(R_cr, runway.direction_runway())
    if pixel_noise_px < 0 or not math.isfinite(pixel_noise_px):
        raise ValueError(f"pixel_noise_px must be a non-negative number, got {pixel_noise_px!r}")
    if pixel_noise_px > 0:
        if rng is None:
            raise ValueError("rng is required when pixel_noise_px > 0 (seed every random generator)")
        uv = uv + rng.normal(0.0, pixel_noise_px, size=uv.shape)
        xy = camera_true.pixels_to_normalized(uv)
        lines = {
            "left": line_through_points(xy[:, 0], xy[:, 2]),
            "right": line_through_points(xy[:, 1], xy[:, 3]),
            "center": line_through_points(0.5 * (xy[:, 0] + xy[:, 1]), 0.5 * (xy[:, 2] + xy[:, 3])),
        }
        vp_xy = intersect_lines(*lines["left"], *lines["right"])
    # what an estimator sees: the nominal camera and the inertial attitude
    R_cr_level = batch_R_camera_from_runway(roll, pitch, np.zeros_like(roll), camera.mount_rpy_rad)
    h_rho, h_theta = horizon_line(R_cr_level)
    # the image's pixels are those of camera_true; read them with the nominal intrinsics (same K)
    dF = dF_from_vanishing_point(vp_xy, h_rho, h_theta, camera)
    dpsi_meas = dpsi_from_dF(dF, roll, pitch, camera)
    R_rc_meas = np.swapaxes(batch_R_camera_from_runway(roll, pitch, dpsi_meas, camera.mount_rpy_rad), -1, -2)
    yv_near = virtual_from_pixels(uv[:, :2, :], R_rc_meas, camera)
    # observability on the true motion
    v_C = np.einsum("nij,nj->ni", R_cr, states.v_runway_mps)
    n_C = R_cr @ runway.normal_runway()        # the runway plane's normal (3.33; tilted on a sloped runway)
    omega_C = np.einsum("ij,nj->ni", camera_true.R_body_from_camera.T, states.omega_body_rps)
    yv_true = (runway.corners_runway_m()[None, :2, :2] - states.p_runway_m[:, None, :2]) / (
        -states.p_runway_m[:, None, 2:3])
    obs_p = observability_points(yv_true, states.v_runway_mps)
    obs_l = observability_lines([lines["left"], lines["right"]], v_C, omega_C, n_C)
    return IdealFeatures(t_s=np.asarray(states.t_s), corners_uv=uv, corners_visible=visible, lines=lines,
                         dF_px=dF, dpsi_rad=dpsi_meas, yv_near=yv_near, obs_points=obs_p, obs_lines=obs_l)

