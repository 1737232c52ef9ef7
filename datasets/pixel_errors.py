"""Image-processing errors against the labels, in pixels: the one definition used by the HTML
report (:mod:`visland.datasets.report`) and the campaign benchmark
(``benchmarks/campaign_pixel_errors.py``).

Both take tables in the labels schema of ../SPEC.md (``measurements.csv`` and ``labels.csv``,
one row per frame, same frames): pixels (u, v) with u right, v down, (0, 0) the centre of the
top-left pixel (OpenCV); lines (rho, theta) in normalised image coordinates, SPEC chart.

- **corner error**: distance in pixels between the measured and the labelled corner; NaN where
  the labelled corner is outside the image (``<corner>_visible`` = 0) or was not measured.
- **edge error**: mean distance in pixels, to the measured edge line, of nine points evenly spaced
  on the labelled edge (threshold corner to far corner) that lie inside the image; NaN where
  none does or the line was not measured.
"""
from __future__ import annotations

import numpy as np

from visland.runway import CORNER_NAMES

__all__ = ["EDGE_CORNERS", "corner_errors_px", "edge_errors_px"]

#: Each edge of the runway as (threshold corner, far corner), left and right as a pilot sees them.
EDGE_CORNERS = {"left": ("near_left", "far_left"), "right": ("near_right", "far_right")}
#: Points sampled on a labelled edge, ends included.
EDGE_SAMPLES = 9


def corner_errors_px(measurements, labels) -> dict:
    """``{corner: (n,) distance in px}`` for the four corners of :data:`visland.runway.CORNER_NAMES`.

    Parameters
    ----------
    measurements : visland.contracts.Table
        Measured corners (pixels), one row per frame.
    labels : visland.contracts.Table
        The exact corners and visibility.

    Returns
    -------
    dict of str to ndarray, shape (n,)
    """
    errors = {}
    for name in CORNER_NAMES:
        du = np.asarray(measurements[f"{name}_u_px"], dtype=float) - np.asarray(labels[f"{name}_u_px"], dtype=float)
        dv = np.asarray(measurements[f"{name}_v_px"], dtype=float) - np.asarray(labels[f"{name}_v_px"], dtype=float)
        visible = np.asarray(labels[f"{name}_visible"], dtype=float) > 0.5
        errors[name] = np.where(visible, np.hypot(du, dv), np.nan)
    return errors


def edge_errors_px(measurements, labels, camera) -> dict:
    """``{"left"|"right": (n,) mean distance in px}`` of the labelled edge's visible points to the
    measured line; ``camera`` is the :class:`visland.camera.CameraModel` of the frames.

    Parameters
    ----------
    measurements : visland.contracts.Table
        Measured lines (SPEC chart).
    labels : visland.contracts.Table
        The exact corners.
    camera : visland.camera.CameraModel
        Intrinsics (normalised coordinates to pixels).

    Returns
    -------
    dict of str to ndarray, shape (n,)
    """
    errors = {}
    for edge, corners in EDGE_CORNERS.items():
        near, far = (np.stack([np.asarray(labels[f"{c}_u_px"], dtype=float),
                               np.asarray(labels[f"{c}_v_px"], dtype=float)], axis=1) for c in corners)
        samples_px = np.stack([near + (far - near) * s for s in np.linspace(0.0, 1.0, EDGE_SAMPLES)], axis=1)
        inside = camera.in_image(samples_px)
        rho = np.asarray(measurements[f"{edge}_rho"], dtype=float)[:, None]
        theta_rad = np.asarray(measurements[f"{edge}_theta_rad"], dtype=float)[:, None]
        d = np.where(inside, np.abs(camera.line_distance_px(rho, theta_rad, samples_px)), np.nan)
        counts = np.isfinite(d).sum(axis=1)
        with np.errstate(invalid="ignore", divide="ignore"):
            errors[edge] = np.where(counts > 0, np.nansum(d, axis=1) / counts, np.nan)
    return errors
