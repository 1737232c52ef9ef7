"""A search window placed by an estimator's prediction (seed 004: "when it is known what to look for").

Dickmanns and Schell place their edge windows where the filter predicts the runway's borders in
the next frame. visland's detector tracks from a previous result (:func:`visland.detection.detect_runway`,
``previous``: its edges' end points, threshold corners and attitude place the region of interest);
:func:`prior_from_prediction` writes an estimator's predicted runway as such a result, so that
:class:`visland.detection.DetectionSequence` (its ``predicted`` argument) searches where the
estimator expects the runway instead of where the last detection saw it. The prediction already
holds this frame's attitude and the motion since the last frame, which the detector's own
prediction leaves to its search band.

Conventions (SPEC): normalised image points ``x = (u - cx)/fx, y = (v - cy)/fy``; pixels (u right,
v down, (0, 0) the centre of the top-left pixel); lines ``(rho, theta)`` in the SPEC chart.
"""
from __future__ import annotations

import math

import numpy as np

from visland.camera import CameraModel
from visland.detection.result import DetectionResult

__all__ = ["prior_from_prediction"]


def prior_from_prediction(camera: CameraModel, near_xy, far_xy, roll_rad: float, pitch_rad: float,
                          dpsi_rad: float, lines: dict | None = None, source: str = "estimator") -> DetectionResult:
    """The predicted runway as a found :class:`DetectionResult` for the detector's ``previous``.

    Parameters
    ----------
    camera : CameraModel
        The frame's camera (undistorted pixels).
    near_xy : (2, 2) array_like
        Normalised image points of the threshold corners P' (near left, row 0) and P'' (near right).
    far_xy : (2, 2) array_like
        Normalised image points further along the left and right edges (rows 0, 1): with the near
        corners they are the edges' segments the detector tracks.
    roll_rad, pitch_rad : float
        The attitude of this frame (the detector carries the prior by the attitude change: none).
    dpsi_rad : float
        Heading deviation of the prediction.
    lines : dict, optional
        ``{"left", "right", "threshold"}`` -> ``(rho, theta)``, kept in the result for reference.
    source : str
        Who predicted (in the result's reason).

    Returns
    -------
    DetectionResult
        ``found`` when both edges are in front of the camera; ``mode`` "predicted"; the near corners
        marked found where they fall inside the frame. Not a measurement: never written out.
    """
    near = np.asarray(near_xy, dtype=float)
    far = np.asarray(far_xy, dtype=float)
    if near.shape != (2, 2) or far.shape != (2, 2):
        raise ValueError(f"near_xy and far_xy must have shape (2, 2), got {near.shape} and {far.shape}")
    for name, value in (("roll_rad", roll_rad), ("pitch_rad", pitch_rad), ("dpsi_rad", dpsi_rad)):
        if not math.isfinite(float(value)):
            raise ValueError(f"{name} must be a finite angle, got {value!r}")
    if not (np.isfinite(near).all() and np.isfinite(far).all()):
        return DetectionResult(found=False, reason=f"{source}: predicted runway not in front of the camera",
                               mode="predicted", image_size=(camera.width, camera.height))
    scale = np.array([camera.fx, camera.fy])
    centre = np.array([camera.cx, camera.cy])
    near_uv = near * scale + centre
    far_uv = far * scale + centre
    inside = ((near_uv[:, 0] > -0.5) & (near_uv[:, 0] < camera.width - 0.5)
              & (near_uv[:, 1] > -0.5) & (near_uv[:, 1] < camera.height - 0.5))
    corners = np.full((4, 2), np.nan)
    corners[:2] = near_uv
    corners_found = np.zeros(4, dtype=bool)
    corners_found[:2] = inside
    nan_line = (math.nan, math.nan)
    lines = dict(lines or {})
    return DetectionResult(
        found=True, reason=f"predicted by {source}", confidence=0.0, corners_uv=corners, corners_found=corners_found,
        lines={"left": tuple(lines.get("left", nan_line)), "right": tuple(lines.get("right", nan_line)),
               "center": nan_line},
        segments_uv={"left": np.array([far_uv[0], near_uv[0]]), "right": np.array([far_uv[1], near_uv[1]]),
                     "center": np.full((2, 2), np.nan)},
        threshold_line=tuple(lines.get("threshold", nan_line)), dpsi_rad=float(dpsi_rad), roll_rad=float(roll_rad),
        pitch_rad=float(pitch_rad), mode="predicted", image_size=(camera.width, camera.height))
