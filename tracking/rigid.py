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

    ``scale`` is ``dH_0 / dH_k`` (grows as the aircraft descends), ``shift`` (2,) is
    ``(c_0 - c_k)_xy / dH_k``.
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
    """

    motion: PlaneMotion | None
    residual_px: np.ndarray
    consistent: np.ndarray
    threshold_px: float
    checked: bool
    decided: bool
    prediction_std_px: np.ndarray | None = None
    information: np.ndarray | None = None


def _rows(q, y, J, normals):
    """Least-squares rows (A, rhs) of the linearised pixel residuals; one or two rows per point."""
    A_rows, rhs = [], []
    for k in range(len(q)):
        Jq = J[k] @ q[k]
        block = np.column_stack([Jq, J[k]])           # (2, 3): d(pixels)/d(s, b1, b2)
        target = J[k] @ y[k]
        n = normals[k]
        if n is None:
            A_rows.append(block)
            rhs.append(target)
        else:
            A_rows.append(n[None, :] @ block)
            rhs.append(np.atleast_1d(n @ target))
    return np.vstack(A_rows), np.concatenate(rhs)


def _n_rows(normals, keep) -> int:
    return sum(1 if normals[k] is not None else 2 for k in np.nonzero(keep)[0])


def _fit(q, uv, G_virtual_to_pixels, normals, keep):
    """Least squares of the module docstring: (motion, normal matrix A^T A) or (None, None)."""
    if _n_rows(normals, keep) < 3:
        return None, None
    G_inv = np.linalg.inv(G_virtual_to_pixels)
    index = np.nonzero(keep)[0]
    y = apply_homography(G_inv, uv[index])
    J = [homography_jacobian(G_virtual_to_pixels, y[k]) for k in range(len(index))]
    A, rhs = _rows(q[index], y, J, [normals[k] for k in index])
    solution, _, rank, singular = np.linalg.lstsq(A, rhs, rcond=None)
    if rank < 3 or singular[-1] < 1e-9 * singular[0] or not np.all(np.isfinite(solution)) or solution[0] <= 0:
        return None, None
    return PlaneMotion(scale=float(solution[0]), shift=solution[1:].copy()), A.T @ A


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

    Parameters as :func:`fit_plane_motion`; ``sigma_px`` is the matching noise of one
    coordinate. A point is inconsistent when its distance to where the *other* points'
    motion puts it (leave-one-out: a drifting point would otherwise pull the fit towards
    itself) exceeds ``threshold_px`` plus three times that prediction's standard deviation
    (a small, far-away configuration predicts a point only loosely). The point most beyond
    its threshold is set aside (the one whose removal leaves the others most consistent) and
    the test repeated on the rest while a spare equation remains. When no point can be left
    out (two corner points: four equations for three unknowns) the disagreement is twice the
    largest in-sample residual (one point displaced by e across the segment leaves e / 2 on
    each) and, beyond the threshold, ``decided`` is False.
    """
    q = np.asarray(q, dtype=float).reshape(-1, 2)
    uv = np.asarray(uv, dtype=float).reshape(-1, 2)
    n = len(q)
    normals = [None] * n if normals is None else list(normals)
    if not (math.isfinite(threshold_px) and threshold_px >= 0):
        raise ValueError(f"threshold_px must be a non-negative number, got {threshold_px!r}")
    if not (math.isfinite(sigma_px) and sigma_px > 0):
        raise ValueError(f"sigma_px must be a positive number, got {sigma_px!r}")
    keep = np.ones(n, dtype=bool)
    nan = np.full(n, np.nan)
    motion, information = _fit(q, uv, G_virtual_to_pixels, normals, keep)
    if motion is None:
        return ConsistencyResult(None, nan, np.zeros(n, dtype=bool), threshold_px, False, False)
    if _n_rows(normals, keep) <= 3:
        # no spare equation: the motion fits exactly, nothing can be checked
        residual = _residuals(motion, q, uv, G_virtual_to_pixels, normals)
        return ConsistencyResult(motion, residual, np.ones(n, dtype=bool), threshold_px, False, False,
                                 prediction_std_px(motion, information, q, G_virtual_to_pixels, sigma_px),
                                 information)
    decided = True
    while True:
        worst_excess, any_left_out = -math.inf, False
        for k in np.nonzero(keep)[0]:
            others = keep.copy()
            others[k] = False
            trial, trial_information = _fit(q, uv, G_virtual_to_pixels, normals, others)
            if trial is None:
                continue
            any_left_out = True
            left_out = float(_residuals(trial, q[k:k + 1], uv[k:k + 1], G_virtual_to_pixels, [normals[k]])[0])
            spread = float(prediction_std_px(trial, trial_information, q[k:k + 1], G_virtual_to_pixels, sigma_px)[0])
            worst_excess = max(worst_excess, left_out - (threshold_px + 3.0 * spread))
        if not any_left_out:
            residual = _residuals(motion, q, uv, G_virtual_to_pixels, normals)
            if 2.0 * float(np.max(residual[keep])) > threshold_px:
                decided = False
            break
        if worst_excess <= 0.0:
            break
        best = None
        for k in np.nonzero(keep)[0]:
            others = keep.copy()
            others[k] = False
            if _n_rows(normals, others) <= 3:
                continue        # the others would fit exactly: nothing left to check them against
            trial, trial_information = _fit(q, uv, G_virtual_to_pixels, normals, others)
            if trial is None:
                continue
            spread = float(np.max(_residuals(trial, q, uv, G_virtual_to_pixels, normals)[others]))
            if best is None or spread < best[0]:
                best = (spread, k, trial, trial_information)
        if best is None:
            decided = False
            break
        keep[best[1]] = False
        motion, information = best[2], best[3]
    residual = _residuals(motion, q, uv, G_virtual_to_pixels, normals)
    std = prediction_std_px(motion, information, q, G_virtual_to_pixels, sigma_px)
    consistent = keep & (residual <= threshold_px + 3.0 * std)
    if not decided:
        consistent = np.zeros(n, dtype=bool)
    return ConsistencyResult(motion, residual, consistent, threshold_px, True, decided, std, information)
