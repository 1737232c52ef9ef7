"""Do the tracked points move as one rigid runway would? (drift detection across points)

Thesis 5.3.2.1 names the remedy: track several points, so that a drifting one shows. Here is
the test. Every tracked point lies on the ground plane. In the level frame of the
designation (:mod:`visland.tracking.motion`), a ground point P seen from camera centre
``c_k`` at height ``dH_k`` has virtual coordinates (thesis 3.23)
``y_v(P, k) = (P_xy - c_k,xy) / dH_k``. Writing ``q_i = y_v(P_i, 0)`` at the designation
frame 0, for every frame k::

    y_v(P_i, k) = s_k q_i + b_k,   s_k = dH_0 / dH_k,   b_k = (c_0,xy - c_k,xy) / dH_k

(substitute ``P_i,xy = c_0,xy + dH_0 q_i``). So with the attitude known from the inertial
unit, all points move together through three unknowns ``(s_k, b_k)``: a scale and a shift in
the virtual plane, shared by every point. Two points give four equations (one to spare:
the direction of the segment between them must keep its bearing), the four runway corners
eight (five to spare).

The fit is linear. A measured pixel ``uv_i`` gives ``y_i = G_k^-1(uv_i)`` with
``G_k = K R_C_from_L`` (virtual to pixels); the pixel residual is linearised as
``J_i (y_i - s_k q_i - b_k)``, ``J_i`` the derivative of ``G_k`` at ``y_i``, so
least squares in pixels is ``J_i [q_i | I] (s, b) = J_i y_i``, two rows per corner point and
one row (the component across the edge, ``n_i^T J_i ...``) per edge point, which may slide
along its edge without being wrong. Residuals are then measured exactly through ``G_k``.

Which point drifts: each point is compared with where the motion fitted on the *other*
points puts it (leave-one-out, so that a drifting point cannot pull the fit towards itself).
If one is beyond the threshold, the point whose removal leaves the others most consistent
is set aside, and the test is repeated on the rest while a spare equation remains. With
only two corner points a disagreement is seen but cannot be blamed on either.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from visland.tracking.template import apply_homography, homography_jacobian

__all__ = ["PlaneMotion", "ConsistencyResult", "fit_plane_motion", "check_consistency", "prediction_std_px"]


@dataclass(frozen=True)
class PlaneMotion:
    """Ground-plane motion since the designation: ``y_v = scale * q + shift`` (see module docstring).

    Attributes
    ----------
    scale : float
        ``s_k = dH_0 / dH_k`` (grows as the aircraft descends).
    shift : ndarray, shape (2,)
        ``b_k = (c_0 - c_k)_xy / dH_k`` (virtual coordinates, dimensionless).
    """

    scale: float
    shift: np.ndarray

    def virtual(self, q) -> np.ndarray:
        """Virtual coordinates ``(..., 2)`` now of points with designation coordinates ``q (..., 2)``."""
        return self.scale * np.asarray(q, dtype=float) + self.shift

    def designation(self, y_v) -> np.ndarray:
        """Inverse of :meth:`virtual`: designation coordinates of points seen now at ``y_v``."""
        return (np.asarray(y_v, dtype=float) - self.shift) / self.scale

    def pixels(self, q, G_virtual_to_pixels: np.ndarray) -> np.ndarray:
        """Pixels ``(..., 2)`` now of points with designation coordinates ``q``."""
        return apply_homography(G_virtual_to_pixels, self.virtual(q))


@dataclass(frozen=True)
class ConsistencyResult:
    """Outcome of :func:`check_consistency` for the points given (arrays of shape (n,)).

    ``motion`` is fitted on the points kept (None if too few equations). ``residual_px`` is
    each point's distance to where ``motion`` puts it (across the edge for edge points; NaN
    if no motion). ``consistent`` flags points within their threshold; ``decided`` is False
    when the points disagree but too few remain to tell which one drifts (or when there are
    no spare equations at all: ``checked`` False). ``prediction_std_px`` is how precisely
    ``motion`` places each point (see :func:`prediction_std_px`, which ``information``, the
    fit's ``A^T A``, serves for other points): a point may be re-projected or searched for
    where the motion puts it only when this is small.

    Attributes
    ----------
    motion : PlaneMotion or None
    residual_px, consistent : ndarray, shape (n,)
    threshold_px : float
        The threshold the residuals were held to, pixels.
    checked, decided : bool
    prediction_std_px : ndarray, shape (n,), optional
    information : ndarray, shape (3, 3), optional
    """

    motion: PlaneMotion | None
    residual_px: np.ndarray
    consistent: np.ndarray
    threshold_px: float
    checked: bool
    decided: bool
    prediction_std_px: np.ndarray | None = None
    information: np.ndarray | None = None


def _blocks(q, uv, G_virtual_to_pixels, normals):
    """Per point, the linearised pixel equations ``A_i (s, b) = r_i``: one or two rows each.

    ``A_i = J_i [q_i | I]`` (rows across the edge only for an edge point: ``n_i^T A_i``) and
    ``r_i = J_i y_i``, with ``y_i = G^-1(uv_i)`` and ``J_i`` the derivative of ``G`` there.
    """
    y = apply_homography(np.linalg.inv(G_virtual_to_pixels), uv)
    blocks = []
    for k in range(len(q)):
        J = homography_jacobian(G_virtual_to_pixels, y[k])
        A = np.column_stack([J @ q[k], J])            # (2, 3): d(pixels)/d(s, b1, b2)
        r = J @ y[k]
        n = normals[k]
        if n is not None:
            A, r = n[None, :] @ A, np.atleast_1d(n @ r)
        blocks.append((A, r))
    return blocks


def _solve(blocks, keep):
    """Least squares over the kept blocks: ``(theta, information A^T A)`` or ``(None, None)``."""
    rows = sum(len(blocks[k][1]) for k in np.nonzero(keep)[0])
    if rows < 3:
        return None, None
    information = np.zeros((3, 3))
    rhs = np.zeros(3)
    for k in np.nonzero(keep)[0]:
        A, r = blocks[k]
        information += A.T @ A
        rhs += A.T @ r
    eigenvalues = np.linalg.eigvalsh(information)
    if not eigenvalues[0] > 1e-12 * max(eigenvalues[-1], 1e-300):
        return None, None
    theta = np.linalg.solve(information, rhs)
    if not (np.all(np.isfinite(theta)) and theta[0] > 0):
        return None, None
    return theta, information


def _n_rows(normals, keep) -> int:
    return sum(1 if normals[k] is not None else 2 for k in np.nonzero(keep)[0])


def _motion(theta) -> PlaneMotion:
    return PlaneMotion(scale=float(theta[0]), shift=np.array(theta[1:], dtype=float))


def _fit(q, uv, G_virtual_to_pixels, normals, keep):
    """Least squares of the module docstring: (motion, normal matrix A^T A) or (None, None)."""
    theta, information = _solve(_blocks(q, uv, G_virtual_to_pixels, normals), keep)
    if theta is None:
        return None, None
    return _motion(theta), information


def fit_plane_motion(q, uv, G_virtual_to_pixels, normals=None, keep=None) -> PlaneMotion | None:
    """Least-squares ground-plane motion from points with known designation coordinates.

    Parameters
    ----------
    q : (n, 2) designation virtual coordinates.
    uv : (n, 2) measured pixels now.
    G_virtual_to_pixels : (3, 3) ``K R_C_from_L`` now.
    normals : sequence of n entries, None for a corner point or a unit (2,) pixel direction
        across the edge for an edge point.
    keep : (n,) bool, the points to use (default all).

    Returns None with fewer than three equations or a degenerate configuration.
    """
    q = np.asarray(q, dtype=float).reshape(-1, 2)
    uv = np.asarray(uv, dtype=float).reshape(-1, 2)
    n = len(q)
    normals = [None] * n if normals is None else list(normals)
    keep = np.ones(n, dtype=bool) if keep is None else np.asarray(keep, dtype=bool)
    return _fit(q, uv, G_virtual_to_pixels, normals, keep)[0]


def prediction_std_px(motion: PlaneMotion, information: np.ndarray, q, G_virtual_to_pixels,
                      sigma_px: float) -> np.ndarray:
    """Standard deviation (pixels, largest axis) of where ``motion`` puts points ``q (k, 2)``.

    With each fitted equation's pixel noise ``sigma_px``, the motion's covariance is
    ``sigma^2 (A^T A)^-1``; a point's pixel ``G(s q + b)`` moves by ``J_G [q | I]`` per unit of
    ``(s, b)``, which carries the covariance to the image.

    Parameters
    ----------
    motion : PlaneMotion
        The fitted motion.
    information : ndarray, shape (3, 3)
        The fit's ``A^T A`` (:attr:`ConsistencyResult.information`).
    q : array_like, shape (k, 2)
        Designation virtual coordinates of the points to place.
    G_virtual_to_pixels : ndarray, shape (3, 3)
        ``K R_C_from_L`` now.
    sigma_px : float
        Pixel noise of each fitted equation.

    Returns
    -------
    ndarray, shape (k,)
        Pixels.
    """
    q = np.asarray(q, dtype=float).reshape(-1, 2)
    covariance = sigma_px ** 2 * np.linalg.inv(information)
    out = np.empty(len(q))
    for k, qk in enumerate(q):
        J_G = homography_jacobian(G_virtual_to_pixels, motion.virtual(qk))
        J = J_G @ np.column_stack([qk, np.eye(2)])
        out[k] = math.sqrt(max(float(np.linalg.eigvalsh(J @ covariance @ J.T)[-1]), 0.0))
    return out


def _residuals(motion, q, uv, G, normals) -> np.ndarray:
    error = np.asarray(uv, dtype=float) - motion.pixels(q, G)
    out = np.empty(len(error))
    for k, n in enumerate(normals):
        out[k] = abs(float(n @ error[k])) if n is not None else float(np.hypot(*error[k]))
    return out


def check_consistency(q, uv, G_virtual_to_pixels, threshold_px: float, normals=None,
                      sigma_px: float = 0.2) -> ConsistencyResult:
    """Fit the shared ground-plane motion and find the points that do not follow it.

    ``q``, ``uv``, ``G_virtual_to_pixels`` and ``normals`` as in :func:`fit_plane_motion`;
    ``sigma_px`` is the matching noise of one coordinate. A point is inconsistent when its distance to where the *other* points'
    motion puts it (leave-one-out: a drifting point would otherwise pull the fit towards
    itself) exceeds ``threshold_px`` plus three times that prediction's standard deviation
    (a small, far-away configuration predicts a point only loosely). The point most beyond
    its threshold leads to setting aside the point whose removal leaves the others most
    consistent, and the test is repeated on the rest while a spare equation remains. When
    no point can be left out (two corner points: four equations for three unknowns) the
    disagreement is twice the largest in-sample residual (one point displaced by e across
    the segment leaves e / 2 on each) and, beyond the threshold, ``decided`` is False.

    Leave-one-out needs no refit: with ``N = A^T A`` over the kept points, ``e_i`` point i's
    residual rows and ``H_i = A_i N^-1 A_i^T``, the residual of i against the fit of the others
    is ``(I - H_i)^-1 e_i``, that fit is ``theta - N^-1 A_i^T (I - H_i)^-1 e_i``, and its
    covariance is ``sigma^2 (N - A_i^T A_i)^-1`` (linear least squares, exactly).

    Parameters
    ----------
    q : array_like, shape (n, 2)
        Designation virtual coordinates.
    uv : array_like, shape (n, 2)
        Measured pixels now.
    G_virtual_to_pixels : ndarray, shape (3, 3)
        ``K R_C_from_L`` now.
    threshold_px : float
        Distance, pixels, beyond which a point does not follow the others.
    normals : sequence of n entries, optional
        None for a corner point, a unit (2,) pixel direction across the edge for an edge point.
    sigma_px : float, default 0.2
        Matching noise of one coordinate, pixels.

    Returns
    -------
    ConsistencyResult
    """
    q = np.asarray(q, dtype=float).reshape(-1, 2)
    uv = np.asarray(uv, dtype=float).reshape(-1, 2)
    n = len(q)
    normals = [None] * n if normals is None else list(normals)
    if not (math.isfinite(threshold_px) and threshold_px >= 0):
        raise ValueError(f"threshold_px must be a non-negative number, got {threshold_px!r}")
    if not (math.isfinite(sigma_px) and sigma_px > 0):
        raise ValueError(f"sigma_px must be a positive number, got {sigma_px!r}")
    nan = np.full(n, np.nan)
    blocks = _blocks(q, uv, G_virtual_to_pixels, normals)
    keep = np.ones(n, dtype=bool)
    theta, information = _solve(blocks, keep)
    if theta is None:
        return ConsistencyResult(None, nan, np.zeros(n, dtype=bool), threshold_px, False, False)
    if _n_rows(normals, keep) <= 3:
        # no spare equation: the motion fits exactly, nothing can be checked
        motion = _motion(theta)
        residual = _residuals(motion, q, uv, G_virtual_to_pixels, normals)
        return ConsistencyResult(motion, residual, np.ones(n, dtype=bool), threshold_px, False, False,
                                 prediction_std_px(motion, information, q, G_virtual_to_pixels, sigma_px),
                                 information)
    decided = True
    while True:
        inverse = np.linalg.inv(information)
        leave_out = {}           # k -> (theta without k, excess of k's residual over its threshold)
        for k in np.nonzero(keep)[0]:
            A, r = blocks[k]
            if _n_rows(normals, keep) - len(r) < 3:
                continue
            others = information - A.T @ A
            if not np.linalg.eigvalsh(others)[0] > 1e-12 * np.linalg.eigvalsh(information)[-1]:
                continue
            e = r - A @ theta
            shrink = np.eye(len(r)) - A @ inverse @ A.T
            e_out = np.linalg.solve(shrink, e)
            theta_out = theta - inverse @ A.T @ e_out
            spread = math.sqrt(max(float(np.linalg.eigvalsh(sigma_px ** 2 * A @ np.linalg.inv(others) @ A.T)[-1]),
                                   0.0))
            leave_out[k] = (theta_out, float(np.linalg.norm(e_out)) - (threshold_px + 3.0 * spread))
        if not leave_out:
            residual = _residuals(_motion(theta), q, uv, G_virtual_to_pixels, normals)
            if 2.0 * float(np.max(residual[keep])) > threshold_px:
                decided = False
            break
        if max(excess for _, excess in leave_out.values()) <= 0.0:
            break
        # set aside the point whose removal leaves the others most consistent
        best = None
        for k, (theta_out, _) in leave_out.items():
            remaining = keep.copy()
            remaining[k] = False
            if _n_rows(normals, remaining) <= 3:
                continue        # the others would fit exactly: nothing left to check them against
            spread = max(float(np.linalg.norm(blocks[j][1] - blocks[j][0] @ theta_out))
                         for j in np.nonzero(remaining)[0])
            if best is None or spread < best[0]:
                best = (spread, k)
        if best is None:
            decided = False
            break
        keep[best[1]] = False
        theta, information = _solve(blocks, keep)
        if theta is None:
            decided = False
            keep[best[1]] = True
            theta, information = _solve(blocks, keep)
            break
    motion = _motion(theta)
    residual = _residuals(motion, q, uv, G_virtual_to_pixels, normals)
    std = prediction_std_px(motion, information, q, G_virtual_to_pixels, sigma_px)
    consistent = keep & (residual <= threshold_px + 3.0 * std)
    if not decided:
        consistent = np.zeros(n, dtype=bool)
    return ConsistencyResult(motion, residual, consistent, threshold_px, True, decided, std, information)
