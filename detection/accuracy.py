"""Detection accuracy against exact labels: per-frame errors and per-distance-band summaries.

One home for the figures every detection benchmark and study reports (issues 4 and 11):

- found rate;
- edge error: the largest distance (px) from the labelled left/right edge, over its stretch
  visible in the image, to the detected line;
- near-corner error: distance (px) of each detected threshold corner (P', P'') from its label,
  where the label is in the image; the frame's figure is the worse of the two;
- gross error: a frame reported found with a corner more than ``GROSS_ERROR_PX`` off, or with
  an edge more than that off (the confident wrong answer a landing aid must never give);
- heading: detected dpsi minus the true dpsi (deg).

Pixels: SPEC convention ((0, 0) at the centre of the top-left pixel), undistorted pinhole image.
"""
from __future__ import annotations

import math

import numpy as np

from visland.camera import CameraModel

__all__ = ["BANDS", "GROSS_ERROR_PX", "band_of", "edge_error_px", "frame_errors", "summarise", "format_table"]

#: Distance bands to the threshold, metres: (low, high, name).
BANDS = ((3000.0, math.inf, ">3 km"), (1000.0, 3000.0, "1-3 km"), (500.0, 1000.0, "0.5-1 km"),
         (0.0, 500.0, "<0.5 km"))
#: A corner or edge this far from the truth while the frame is reported found is a gross error.
GROSS_ERROR_PX = 5.0


def band_of(distance_m: float) -> str:
    """Name of the distance band (:data:`BANDS`) holding a distance to the threshold.

    Parameters
    ----------
    distance_m : float
        Distance of the aircraft before the runway threshold, metres (along the runway axis).

    Returns
    -------
    str
        The band's name; the nearest band (``"<0.5 km"``) for a distance below every band.
    """
    for low, high, name in BANDS:
        if low <= distance_m < high:
            return name
    return BANDS[-1][2]


def edge_error_px(camera: CameraModel, corners_uv, rho_theta, side: str) -> float:
    """Largest distance (px) from the labelled edge's visible stretch to a detected line.

    Parameters
    ----------
    camera : CameraModel
        The camera (pinhole intrinsics; the line is in the SPEC chart).
    corners_uv : array (4, 2)
        Labelled corners in ``CORNER_NAMES`` order (pixels).
    rho_theta : tuple
        The detected line ``(rho, theta)``.
    side : {"left", "right"}
    """
    corners_uv = np.asarray(corners_uv, float)
    a = corners_uv[0 if side == "left" else 1]
    b = corners_uv[2 if side == "left" else 3]
    t = np.linspace(0.0, 1.0, 400)[:, None]
    points = a + t * (b - a)
    points = points[camera.in_image(points)]
    rho, theta = rho_theta
    if len(points) == 0 or not (math.isfinite(rho) and math.isfinite(theta)):
        return math.nan
    return float(np.abs(camera.line_distance_px(rho, theta, points)).max())


def frame_errors(result, camera: CameraModel, corners_uv, corners_visible, dpsi_true_rad: float,
                 dF_true_px: float = math.nan) -> dict:
    """Errors of one :class:`~visland.detection.result.DetectionResult` against its labels.

    Parameters
    ----------
    result : DetectionResult
        The detection of the frame.
    camera : CameraModel
        The camera the frame was taken with (pinhole pixels, SPEC convention).
    corners_uv : array_like, shape (4, 2)
        Labelled corners, pixels, in :data:`visland.runway.CORNER_NAMES` order.
    corners_visible : array_like of bool, shape (4,)
        Which labelled corners are in the image (not hidden).
    dpsi_true_rad : float
        True heading deviation of the frame, radians (SPEC sign: positive right of the runway).
    dF_true_px : float, optional
        True d_F (seed 001 eq. 18), pixels; NaN when not labelled.

    Returns
    -------
    dict
        ``found``, ``edge_px`` (worse edge), ``near_left_px``, ``near_right_px``,
        ``far_left_px``, ``far_right_px`` (NaN where the label is not visible or the corner not
        measured), ``near_px`` (worse near corner), ``near_along_px`` (signed shift of the
        threshold's midpoint along the runway's image direction: positive beyond the true
        threshold), ``corners_withheld`` (visible near corners not reported), ``dpsi_err_deg``,
        ``dF_err_px``, ``gross`` (found and a corner or edge more than :data:`GROSS_ERROR_PX`
        off, or a corner reported where none is visible), ``confidence``, ``mode``, ``reason``.
    """
    corners_uv = np.asarray(corners_uv, float)
    visible = np.asarray(corners_visible, bool)
    found = bool(result.found)
    measured = np.asarray(result.corners_found, bool) & found
    error = np.linalg.norm(np.asarray(result.corners_uv, float) - corners_uv, axis=1)
    error = np.where(visible & measured, error, np.nan)
    edge = (max(edge_error_px(camera, corners_uv, result.lines["left"], "left"),
                edge_error_px(camera, corners_uv, result.lines["right"], "right")) if found else math.nan)
    near = error[:2][np.isfinite(error[:2])]
    # signed displacement of the threshold along the runway's image direction (positive:
    # placed beyond the true threshold, towards the runway end)
    along = np.nan
    if np.isfinite(error[:2]).all():
        axis = corners_uv[2:].mean(axis=0) - corners_uv[:2].mean(axis=0)
        if np.all(np.isfinite(axis)) and np.linalg.norm(axis) > 0:
            shift = np.asarray(result.corners_uv, float)[:2].mean(axis=0) - corners_uv[:2].mean(axis=0)
            along = float(shift @ axis / np.linalg.norm(axis))
    # a corner reported where the label says none is visible is wrong too
    phantom = bool(np.any(measured & ~visible))
    worst = max([e for e in error if math.isfinite(e)] + [edge if math.isfinite(edge) else 0.0], default=0.0)
    return {
        "found": int(found),
        "edge_px": edge,
        "near_left_px": float(error[0]), "near_right_px": float(error[1]),
        "far_left_px": float(error[2]), "far_right_px": float(error[3]),
        "near_px": float(near.max()) if near.size else math.nan,
        "near_along_px": along,
        "corners_withheld": int(np.sum(visible[:2] & ~measured[:2])) if found else 0,
        "dpsi_err_deg": math.degrees(result.dpsi_rad - dpsi_true_rad) if found else math.nan,
        "dF_err_px": result.dF_px - dF_true_px if found else math.nan,
        "gross": int(found and (worst > GROSS_ERROR_PX or phantom)),
        "confidence": float(result.confidence),
        "mode": result.mode,
        "reason": result.reason,
    }


def _stats(values) -> dict:
    values = np.asarray([v for v in values if v is not None and math.isfinite(v)], float)
    if values.size == 0:
        return {"median": None, "p95": None, "max": None, "n": 0}
    return {"median": round(float(np.median(values)), 3), "p95": round(float(np.percentile(values, 95)), 3),
            "max": round(float(values.max()), 3), "n": int(values.size)}


def summarise(rows: list[dict], key: str = "band") -> dict:
    """Per-band (and ``"all"``) figures of rows holding :func:`frame_errors` and ``key``.

    Parameters
    ----------
    rows : list of dict
        One per frame: the keys of :func:`frame_errors` and ``key``.
    key : str, optional
        The column grouping the rows: ``"band"`` (the :data:`BANDS`, in their order) or any
        other column (its values, sorted).

    Returns
    -------
    dict
        Group name -> ``frames``, ``found_rate``, ``gross_rate`` (of all frames), ``gross``
        (count), ``edge_px``, ``near_corner_px`` (the worse near corner per frame),
        ``near_along_px``, ``dpsi_abs_err_deg`` (median / p95 / max / n each, over the found
        frames), ``withheld`` (visible near corners not reported); groups with no row left out.
    """
    names = [b[2] for b in BANDS] if key == "band" else sorted({r[key] for r in rows})
    out = {}
    for name in names + ["all"]:
        chosen = [r for r in rows if name == "all" or r[key] == name]
        if not chosen:
            continue
        found = [r for r in chosen if r["found"]]
        out[name] = {
            "frames": len(chosen),
            "found_rate": round(len(found) / len(chosen), 4),
            "gross": int(sum(r["gross"] for r in chosen)),
            "gross_rate": round(sum(r["gross"] for r in chosen) / len(chosen), 4),
            "edge_px": _stats([r["edge_px"] for r in found]),
            "near_corner_px": _stats([r["near_px"] for r in found]),
            "near_along_px": _stats([r["near_along_px"] for r in found]),
            "dpsi_abs_err_deg": _stats([abs(r["dpsi_err_deg"]) for r in found]),
            "withheld": int(sum(r["corners_withheld"] for r in found)),
        }
    return out


def format_table(summary: dict, title: str = "band") -> list[str]:
    """Lines of a plain-text table of :func:`summarise`'s output.

    Parameters
    ----------
    summary : dict
        The output of :func:`summarise`.
    title : str, optional
        Heading of the first column (the grouping).

    Returns
    -------
    list of str
        A header line, then one line per group (pixels and degrees as medians / p95 / max).
    """
    lines = [f"{title:22s} {'frames':>6s} {'found':>7s} {'gross':>6s} {'edge med/p95 px':>16s} "
             f"{'near corner med/p95/max px':>27s} {'|dpsi| med/p95 deg':>19s} {'withheld':>8s}"]
    for name, s in summary.items():
        e, c, d = s["edge_px"], s["near_corner_px"], s["dpsi_abs_err_deg"]
        lines.append(f"{name:22s} {s['frames']:6d} {100 * s['found_rate']:6.1f}% {s['gross']:6d} "
                     f"{e['median']!s:>7s}/{e['p95']!s:<8s} "
                     f"{c['median']!s:>8s}/{c['p95']!s:>7s}/{c['max']!s:<10s} "
                     f"{d['median']!s:>8s}/{d['p95']!s:<10s} {s['withheld']:8d}")
    return lines
