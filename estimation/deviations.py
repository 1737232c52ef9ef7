"""From the estimated height to the deviations dX, dY and the runway width (issue item 5).

The observers estimate ``eta = 1/dH``; the rest follows from the measured (or the observer's
filtered) features, with no knowledge of the runway's size (ECC'15 section II and remark 1,
thesis 3.25):

Two threshold corners P' (left, runway y = -W/2) and P'' (right, y = +W/2) at the threshold
(runway x = 0) have virtual coordinates ``y_v = (X_v, Y_v) / Z_v`` with ``Z_v = dH``,
``X_v = -x_cam`` and ``Y_v = y_corner - y_cam`` (virtual frame = runway axes at the camera). So::

    dH = 1/eta
    dX = x_cam - D = -dH (y'1 + y''1)/2 - D          (both corners share X_v: their mean)
    dY = y_cam     = -dH (y'2 + y''2)/2               (symmetry of the corners about the centreline)
    W  = dH (y''2 - y'2)                              (ECC'15 remark 1)

with D the aiming-point distance (320 m, SPEC; a procedure constant, not a runway dimension).

Two edge lines: the interpretation plane of an edge has normal ``m_C = (cos theta, sin theta,
-rho)`` in C, ``m_V = R_runway_from_camera m_C`` in V; it holds the edge ``{(s, Y_e, dH)}``, so
``m_V1 Y_e + m_V2 dH = 0`` and ``Y_e = -dH m_V2 / m_V1``. Then ``dY = -(Y_left + Y_right)/2``
and ``W = Y_right - Y_left``; dX is not observable from lines along the runway.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

__all__ = ["Deviations", "deviations_from_points", "deviations_from_lines", "DEFAULT_AIM_DISTANCE_M"]

DEFAULT_AIM_DISTANCE_M = 320.0


@dataclass(frozen=True)
class Deviations:
    """SPEC deviations (metres); NaN where the feature set cannot give one (dX from lines).

    Attributes
    ----------
    dx_m : float
        Along-track position relative to the aiming point E, metres (negative before it).
    dy_m : float
        Cross-track deviation, metres, right of the centreline positive.
    dh_m : float
        Height above the runway, metres.
    width_m : float
        Runway width recovered from the image, metres.
    """

    dx_m: float
    dy_m: float
    dh_m: float
    width_m: float


def deviations_from_points(points_yv, dh_m: float, aim_distance_m: float = DEFAULT_AIM_DISTANCE_M) -> Deviations:
    """Deviations from the threshold corners' virtual coordinates (rows P', P'') and dH.

    Parameters
    ----------
    points_yv : array_like, shape (2, 2)
        Virtual coordinates ``y_v`` of P' and P'' (thesis 3.23), one row each.
    dh_m : float
        Height above the runway, metres.
    aim_distance_m : float, default 320
        Aiming point distance past the threshold, metres.

    Returns
    -------
    Deviations
    """
    yv = np.asarray(points_yv, dtype=float)
    if yv.shape != (2, 2):
        raise ValueError(f"points_yv must have shape (2, 2) (rows P', P''), got {yv.shape}")
    _check_height(dh_m)
    dx = -dh_m * 0.5 * (yv[0, 0] + yv[1, 0]) - aim_distance_m
    dy = -dh_m * 0.5 * (yv[0, 1] + yv[1, 1])
    width = dh_m * (yv[1, 1] - yv[0, 1])
    return Deviations(float(dx), float(dy), float(dh_m), float(width))


def deviations_from_lines(lines, R_runway_from_camera, dh_m: float) -> Deviations:
    """Lateral deviation and width from the left/right edge lines ``[[rho, theta], [rho, theta]]``.

    Parameters
    ----------
    lines : array_like, shape (2, 2)
        ``[[rho, theta], [rho, theta]]`` of the left and right edges (SPEC chart, normalised
        coordinates, radians).
    R_runway_from_camera : ndarray, shape (3, 3)
        Camera-to-runway rotation.
    dh_m : float
        Height above the runway, metres.

    Returns
    -------
    Deviations
        ``dx_m`` NaN (the edges do not fix the position along the runway).
    """
    lines = np.asarray(lines, dtype=float)
    if lines.shape != (2, 2):
        raise ValueError(f"lines must have shape (2, 2) (rows left, right edge), got {lines.shape}")
    R = np.asarray(R_runway_from_camera, dtype=float)
    if R.shape != (3, 3):
        raise ValueError(f"R_runway_from_camera must have shape (3, 3), got {R.shape}")
    _check_height(dh_m)
    # on Python floats (the runner calls this at every frame of a line observer's run)
    _, (r10, r11, r12), (r20, r21, r22) = R.tolist()
    offsets = []
    for rho, theta in lines.tolist():
        c, s = math.cos(theta), math.sin(theta)
        m1 = r10 * c + r11 * s - r12 * rho                 # m_V = R_runway_from_camera m_C, rows 1 and 2
        m2 = r20 * c + r21 * s - r22 * rho
        if abs(m1) < 1e-12:           # the line's plane contains the lateral axis: no lateral offset
            return Deviations(math.nan, math.nan, float(dh_m), math.nan)
        offsets.append(-dh_m * m2 / m1)
    y_left, y_right = offsets
    return Deviations(math.nan, float(-0.5 * (y_left + y_right)), float(dh_m), float(y_right - y_left))


def _check_height(dh_m: float) -> None:
    if not (isinstance(dh_m, (int, float, np.floating)) and math.isfinite(dh_m) and dh_m > 0):
        raise ValueError(f"dh_m must be a positive finite height in metres, got {dh_m!r}")
