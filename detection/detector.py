"""detect_runway: one frame in, a :class:`~visland.detection.result.DetectionResult` out.

Pipeline (issue 4; thesis 5.3.2.2): horizon from the inertial roll and pitch, candidate lines
(Canny + Hough) in a region of interest, the trapezoid/symmetry model, sub-pixel refinement
of each line, threshold and runway end, corners, d_F and the heading deviation.

Bad input never raises: a frame of the wrong size or type, a black, white or noise-only
frame, a non-finite attitude or one that puts the horizon outside the image give a result
with ``found = False`` and the reason.
"""
from __future__ import annotations

import math
import time

import numpy as np

from visland.camera import CameraModel
from visland.detection.horizon import horizon_frame
from visland.detection.params import DetectorParams
from visland.detection.result import DetectionResult, not_found

__all__ = ["detect_runway", "check_frame"]


def check_frame(image, camera: CameraModel) -> str | None:
    """Why ``image`` cannot be searched (None when it can): type, shape, size, contrast."""
    if not isinstance(image, np.ndarray):
        return f"frame is a {type(image).__name__}, not an image array"
    if image.ndim != 2:
        return f"frame has shape {image.shape}; a grey-level (H, W) image is expected"
    if image.dtype != np.uint8:
        return f"frame has dtype {image.dtype}; uint8 grey levels are expected"
    height, width = image.shape
    if (width, height) != (camera.width, camera.height):
        return f"frame is {width}x{height} but the camera is {camera.width}x{camera.height}"
    return None


def detect_runway(image, camera: CameraModel, roll_rad: float, pitch_rad: float,
                  params: DetectorParams | None = None, previous: DetectionResult | None = None) -> DetectionResult:
    """Find the runway's edges, centre line, corners and d_F in one grey-level frame.

    Parameters
    ----------
    image : ndarray of uint8, shape (H, W)
        The frame, grey levels (convert colour frames first). Its size must be the camera's.
    camera : CameraModel
        Intrinsics and mounting (pixels: (0, 0) at the centre of the top-left pixel).
    roll_rad, pitch_rad : float
        Inertial attitude at the frame's time; with the mounting they fix the horizon.
    params : DetectorParams, optional
    previous : DetectionResult, optional
        The last detection. When it was found, the search runs in a region of interest
        predicted from it (tracking mode); otherwise the whole ground part of the frame is
        searched (acquisition).

    Returns
    -------
    DetectionResult
        ``found``, ``reason``, ``confidence``, corners (4, 2) in
        :data:`visland.runway.CORNER_NAMES` order, lines ``(rho, theta)`` in the SPEC chart,
        ``dF_px`` and ``dpsi_rad``. Never raises on bad image or attitude input.
    """
    start = time.perf_counter()
    if not isinstance(camera, CameraModel):
        raise ValueError(f"camera must be a visland.camera.CameraModel, got {type(camera).__name__}")
    params = params or DetectorParams()
    if not isinstance(params, DetectorParams):
        raise ValueError(f"params must be a DetectorParams, got {type(params).__name__}")
    if previous is not None and not isinstance(previous, DetectionResult):
        raise ValueError(f"previous must be a DetectionResult or None, got {type(previous).__name__}")

    def fail(reason: str) -> DetectionResult:
        return not_found(reason, roll_rad=_as_float(roll_rad), pitch_rad=_as_float(pitch_rad),
                         image_size=(camera.width, camera.height), elapsed_s=time.perf_counter() - start)

    problem = check_frame(image, camera)
    if problem:
        return fail(problem)
    roll, pitch = _as_float(roll_rad), _as_float(pitch_rad)
    if not (math.isfinite(roll) and math.isfinite(pitch)):
        return fail(f"attitude is not finite (roll {roll_rad!r}, pitch {pitch_rad!r})")
    horizon = horizon_frame(camera, roll, pitch)
    if horizon is None:
        return fail(f"horizon is parallel to the image columns (roll {math.degrees(roll):.1f} deg)")
    if not horizon.crosses_image(camera.width, camera.height, params.horizon_margin_px):
        return fail(f"horizon from roll {math.degrees(roll):.1f} deg, pitch {math.degrees(pitch):.1f} deg "
                    "lies outside the image")
    return fail("runway search not implemented yet")


def _as_float(value) -> float:
    try:
        return float(value)
    except (TypeError, ValueError):
        return math.nan
