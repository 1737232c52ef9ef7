"""The horizon frame of one image: horizon coordinates (s, d) and the runway's vanishing points.

The inertial roll and pitch and the camera mounting fix the horizon (the image of the runway
plane's line at infinity; :func:`visland.features.horizon_line`). Every line of the runway
plane meets it: the runway edges and centre line at the vanishing point V1 of the runway
direction, the threshold and runway end at V2, the vanishing point of the perpendicular ground
direction. This module sets up, in pixels:

- ``s``: signed distance along the horizon from Q, the point where the horizon crosses the
  column ``u = cx``, positive to the right (the SPEC ``d_F`` direction), and
- ``d``: signed distance from the horizon, positive towards the ground.

A line through a point of the horizon is ``s = s0 + k d``: ``s0`` is its horizon crossing
(its d_F) and ``k`` its slope. For the three runway lines through V1, ``k`` is affine in the
line's lateral position on the ground, so the centre line lies midway between the edges:
``k_C = (k_L + k_R) / 2`` (the pencil {L, R; C, horizon} is harmonic, and a line parallel to
the horizon cuts it at a point pair and their midpoint). That is the trapezoid symmetry the
detector relies on; it holds for any roll, pitch and heading deviation.

Pixel conventions (SPEC.md, :mod:`visland.camera`): ``(u, v)`` with (0, 0) at the centre of the
top-left pixel, v down.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from visland.camera import CameraModel
from visland.features import batch_R_camera_from_runway, horizon_line

__all__ = ["HorizonFrame", "horizon_frame", "meet_h", "cross3", "depth_along", "widths_along"]


def cross3(a, b) -> np.ndarray:
    """``np.cross(a, b)`` of 3-vectors (broadcast over leading axes): the same products and
    differences in the same order, hence the same bits, without ``np.cross``'s generality
    (axis handling, 2-vectors), which costs tens of microseconds per call on the detector's
    small arrays.

    Parameters
    ----------
    a, b : array_like, shape (..., 3)
        Homogeneous points or lines (broadcast against each other).

    Returns
    -------
    ndarray, shape (..., 3)
    """
    a, b = np.asarray(a), np.asarray(b)
    if a.shape == (3,) and b.shape == (3,) and a.dtype == b.dtype == np.float64:
        # one pair: the same IEEE double products and differences on Python floats
        (a0, a1, a2), (b0, b1, b2) = a.tolist(), b.tolist()
        return np.array([a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0])
    a0, a1, a2 = a[..., 0], a[..., 1], a[..., 2]
    b0, b1, b2 = b[..., 0], b[..., 1], b[..., 2]
    c0, c1, c2 = a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0
    out = np.empty(np.broadcast_shapes(np.shape(c0), np.shape(c1), np.shape(c2)) + (3,), np.result_type(c0, c1, c2))
    out[..., 0], out[..., 1], out[..., 2] = c0, c1, c2
    return out


def depth_along(fx: float, depth, widths, width_k: float):
    """Depth below the horizon of the ground point ``widths`` runway widths farther along the
    runway (negative: nearer) than the one at ``depth``.

    A ground point at distance ``x`` ahead lies at ``d = f h / x``, and ``n W`` farther at
    ``f / (f / d + n k)`` with ``k = W / h``.

    Parameters
    ----------
    fx : float
        Focal length, pixels.
    depth : float or ndarray
        Depth below the horizon of the starting point, pixels.
    widths : float or ndarray
        Runway widths along the runway, away from the camera (negative: toward it).
    width_k : float
        The runway's width over the camera height, ``W / h`` (the edges' pencil slopes'
        difference).
    """
    return fx / (fx / depth + widths * width_k)


def widths_along(fx: float, depth_near, depth_far, width_k: float):
    """Runway widths along the runway from the ground point at ``depth_near`` to the one at
    ``depth_far``: the inverse of :func:`depth_along`.

    Parameters
    ----------
    fx : float
        Focal length, pixels.
    depth_near, depth_far : float or ndarray
        Depths below the horizon of the two points, pixels.
    width_k : float
        The runway's width over the camera height, ``W / h``.
    """
    return (fx / depth_far - fx / depth_near) / width_k


def meet_h(line_a: np.ndarray, line_b: np.ndarray) -> np.ndarray:
    """Pixel point(s) where homogeneous pixel lines meet.

    Parameters
    ----------
    line_a, line_b : ndarray, shape (..., 3)
        Lines ``a u + b v + c = 0`` (broadcast against each other).

    Returns
    -------
    ndarray, shape (..., 2)
        ``(u, v)`` of each intersection (inf or NaN for parallel lines).
    """
    p = cross3(line_a, line_b)
    with np.errstate(divide="ignore", invalid="ignore"):
        return p[..., :2] / p[..., 2:3]


@dataclass(frozen=True)
class HorizonFrame:
    """Horizon geometry of one frame, in pixels.

    Attributes
    ----------
    camera : CameraModel
    rho, theta : float
        The horizon in the SPEC line chart (normalised coordinates).
    q_uv : ndarray, shape (2,)
        Q, the horizon at ``u = cx``.
    t_uv : ndarray, shape (2,)
        Unit direction of the horizon in pixels, ``t_u > 0``.
    n_uv : ndarray, shape (2,)
        Unit normal of the horizon in pixels, pointing towards the ground.
    down_camera : ndarray, shape (3,)
        The runway plane's down axis in the camera frame (thesis 3.33 ``n``).
    """

    camera: CameraModel
    rho: float
    theta: float
    q_uv: np.ndarray
    t_uv: np.ndarray
    n_uv: np.ndarray
    down_camera: np.ndarray

    # ----------------------------------------------------------------- coordinates
    def to_sd(self, uv) -> np.ndarray:
        """Pixels ``(..., 2)`` to horizon coordinates ``(..., 2)`` = (s, d)."""
        rel = np.asarray(uv, dtype=float) - self.q_uv
        return np.stack([rel @ self.t_uv, rel @ self.n_uv], axis=-1)

    def to_uv(self, sd) -> np.ndarray:
        """Horizon coordinates ``(..., 2)`` to pixels ``(..., 2)``."""
        sd = np.asarray(sd, dtype=float)
        return self.q_uv + sd[..., 0:1] * self.t_uv + sd[..., 1:2] * self.n_uv

    def pencil_from_points(self, uv_a, uv_b) -> tuple[np.ndarray, np.ndarray]:
        """``(s0, k)`` of the lines through pixel point pairs (NaN for lines parallel to the horizon)."""
        a = self.to_sd(uv_a)
        b = self.to_sd(uv_b)
        dd = b[..., 1] - a[..., 1]
        with np.errstate(divide="ignore", invalid="ignore"):
            k = np.where(np.abs(dd) > 1e-9, (b[..., 0] - a[..., 0]) / dd, np.nan)
        return a[..., 0] - k * a[..., 1], k

    def pencil_point(self, s0, k, d) -> np.ndarray:
        """Pixel of the pencil line ``s = s0 + k d`` at depth ``d`` below the horizon."""
        s0, k, d = np.broadcast_arrays(np.asarray(s0, float), np.asarray(k, float), np.asarray(d, float))
        return self.to_uv(np.stack([s0 + k * d, d], axis=-1))

    # ----------------------------------------------------------------- vanishing points
    def vanishing_point_uv(self, s0: float) -> np.ndarray:
        """The pixel of the horizon at ``s = s0`` (the runway's vanishing point V1)."""
        return self.q_uv + s0 * self.t_uv

    def perpendicular_vanishing_point_h(self, s0: float) -> np.ndarray:
        """Homogeneous pixel (3,) of V2, the vanishing point of the ground direction perpendicular
        to the runway whose vanishing point is at ``s0``.

        Both ground directions are orthogonal to the plane's down axis ``n``, and to each other:
        ``r2 = n x r1`` with ``r1 = K^-1 V1``. V2 may be at infinity (third coordinate 0) when
        the threshold's image is parallel to the horizon.
        """
        K = self.camera.K
        v1 = self.vanishing_point_uv(s0)
        r1 = np.linalg.solve(K, np.array([v1[0], v1[1], 1.0]))
        r2 = cross3(self.down_camera, r1)
        v2 = K @ r2
        return v2 / np.linalg.norm(v2)

    def parallel_h(self, depth: float) -> np.ndarray:
        """Homogeneous pixel line (3,) parallel to the horizon at ``depth`` pixels below it."""
        n = self.n_uv
        return np.array([n[0], n[1], -(n @ self.q_uv) - depth])

    # ----------------------------------------------------------------- image tests
    def crosses_image(self, width: int, height: int, margin_px: float = 0.0) -> bool:
        """True when the horizon crosses the image rectangle enlarged by ``margin_px``."""
        lo_u, hi_u = -0.5 - margin_px, width - 0.5 + margin_px
        lo_v, hi_v = -0.5 - margin_px, height - 0.5 + margin_px
        corners = np.array([[lo_u, lo_v], [hi_u, lo_v], [lo_u, hi_v], [hi_u, hi_v]])
        d = (corners - self.q_uv) @ self.n_uv
        return bool(d.min() <= 0.0 <= d.max())

    def ground_bbox(self, width: int, height: int, margin_px: float = 0.0):
        """Bounding box ``(u0, v0, u1, v1)`` (integers, end exclusive) of the image part lying
        below the horizon, ``margin_px`` above it included; None when no ground is in view."""
        polygon = [np.array(p, float) for p in ((-0.5, -0.5), (width - 0.5, -0.5),
                                                (width - 0.5, height - 0.5), (-0.5, height - 0.5))]
        kept = []
        for i, a in enumerate(polygon):        # clip the image rectangle by d >= -margin
            b = polygon[(i + 1) % len(polygon)]
            da = (a - self.q_uv) @ self.n_uv + margin_px
            db = (b - self.q_uv) @ self.n_uv + margin_px
            if da >= 0:
                kept.append(a)
            if (da >= 0) != (db >= 0):
                kept.append(a + (b - a) * (da / (da - db)))
        if len(kept) < 3:
            return None
        pts = np.array(kept)
        u0 = max(0, int(math.floor(pts[:, 0].min() + 0.5)))
        v0 = max(0, int(math.floor(pts[:, 1].min() + 0.5)))
        u1 = min(width, int(math.ceil(pts[:, 0].max() + 0.5)))
        v1 = min(height, int(math.ceil(pts[:, 1].max() + 0.5)))
        if u1 - u0 < 2 or v1 - v0 < 2:
            return None
        return u0, v0, u1, v1


def horizon_frame(camera: CameraModel, roll_rad: float, pitch_rad: float) -> HorizonFrame | None:
    """The horizon of a camera at the given inertial roll and pitch (None if it has no point at ``u = cx``).

    Uses :func:`visland.features.horizon_line` with ``dpsi = 0`` (the horizon does not depend on
    the heading), so Q and the direction of ``s`` are those of the SPEC ``d_F``.

    Parameters
    ----------
    camera : CameraModel
        Intrinsics and mounting (``mount_rpy_rad``).
    roll_rad, pitch_rad : float
        Inertial roll and pitch of the body, radians (ZYX Euler, SPEC).

    Returns
    -------
    HorizonFrame or None
        None when the horizon is parallel to the image columns (no Q).

    References
    ----------
    Gibert et al., range identification in perspective systems (seed 001), appendix, Fig. 6:
    Q and the direction of d_F along the horizon.
    """
    R_camera_from_runway_level = batch_R_camera_from_runway(
        np.asarray(roll_rad, float), np.asarray(pitch_rad, float), np.asarray(0.0), camera.mount_rpy_rad)
    rho, theta = (float(a) for a in horizon_line(R_camera_from_runway_level))
    down_camera = np.asarray(R_camera_from_runway_level)[:, 2].copy()
    c, s = math.cos(theta), math.sin(theta)
    if abs(s) < 1e-9:
        return None            # horizon parallel to the image columns: Q does not exist
    q_uv = np.array([camera.cx, camera.fy * rho / s + camera.cy])
    t_uv = np.array([-camera.fx * s, camera.fy * c])
    t_uv = t_uv / np.linalg.norm(t_uv)
    if t_uv[0] < 0:
        t_uv = -t_uv
    n_uv = np.array([-t_uv[1], t_uv[0]])
    # the ground side is where rays have a positive component along the plane's down axis
    probe = q_uv + 10.0 * n_uv
    ray = np.array([(probe[0] - camera.cx) / camera.fx, (probe[1] - camera.cy) / camera.fy, 1.0])
    if ray @ down_camera < 0:
        n_uv = -n_uv
    return HorizonFrame(camera=camera, rho=rho, theta=theta, q_uv=q_uv, t_uv=t_uv, n_uv=n_uv,
                        down_camera=down_camera)
